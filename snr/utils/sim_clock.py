"""`SimClock`: simulated time for nodes, advanced in lockstep (docs/sim-time.md).

A `snr.core.clock.NodeClock` whose nodes and loops take turns: the kernel
knows it only through that interface.

A node built from ``Config(..., clock=SimClock())`` reads its time from the
clock. Nodes and ticking loops take *turns* in a fixed order, so the same run
gives the same pages, and the clock jumps when nothing can act now. Who gets
the clock next: a node with work (by role), else the turn waiting for the
earliest instant, else nobody (a wall wait). Safety waits stay on the wall
clock, so a stalled clock ends in a timeout, never a hang. docs/sim-time.md
tells the whole story.
"""

from __future__ import annotations

import queue
import threading
import time
from typing import Callable, List, Optional, Sized, Tuple

from snr.core.clock import NodeClock
from snr.prelude.errors import ConfigError

__all__ = ["LoopTurn", "NodeTurn", "SimClock", "Turn"]

_POLL_S = 0.25  # how long a waiting thread sleeps before it looks again, unwoken
_LATE_S = 0.1  # a paced clock this far behind real time stops catching up
_NS = 1_000_000_000


class Turn:
    """One thread's place in a `SimClock`'s lockstep: a node's or a loop's.

    Made by `SimClock.node_turn` and `SimClock.loop_turn`; students never use one.

    Example::

        turn = clock.loop_turn("sim", "sim_robot", stop_event)
        turn.first_turn()          # on the loop's thread: wait for its first turn
    """

    def __init__(self, clock: SimClock, key: Tuple[str, str]) -> None:
        self.clock = clock
        self.key = key
        self.waiting = True  # it waits for the clock
        self.deadline_ns: Optional[int] = None  # the instant it waits for; None: work (a node)
        # Rung when the clock is handed over or to look again: the quickest hand-over.
        self.bell: queue.SimpleQueue[None] = queue.SimpleQueue()


class NodeTurn(Turn):
    """A node's turn (a `snr.core.clock.NodeTurn`): an idle node gives the clock back.

    Example (what `Node` does with a simulated clock)::

        turn = clock.node_turn("sim", node.queue, node.is_terminated)
        node.queue.use_waiter(turn)
        turn.begin()   # in node.loop(), before the components start
        ...
        turn.end()     # after the node has terminated
    """

    def __init__(self, clock: SimClock, role: str, tasks: Sized, stopping: Callable[[], bool]):
        super().__init__(clock, (role, ""))
        self.tasks = tasks
        self.stopping = stopping
        self.started = False

    def has_work(self) -> bool:
        """True if the node has tasks to run, has not started (it starts in its
        turn) or is stopping: a node told to stop (a loop failed, say) ends
        before anyone moves the clock on, so it stops at the time it was told."""
        return not self.started or len(self.tasks) > 0 or self.stopping()

    def begin(self) -> None:
        """Wait for the node's first turn (every node built with the clock is waited for)."""
        self.clock._await(self, self.stopping)
        self.started = True

    def wait(self, timeout_s: Optional[float]) -> None:
        """The queue is empty: give the clock back until the node has work or stops.

        ``timeout_s`` is not used: the node's idle wake-up only checks that it
        should still run, and a stop wakes this wait at once.
        """
        self.clock._give_back(self, None)
        self.clock._await(self, self.stopping)

    def woken(self) -> None:
        """Nothing to do: the node reads no sockets in its idle wait on a simulated clock."""

    def wake(self) -> None:
        """A task arrived (or the node stops): let the clock hand the node its turn."""
        if self.stopping():
            self.bell.put(None)  # look again: it must stop, turn or not
        self.clock._work_arrived()

    def end(self) -> None:
        """The node has stopped: it takes no more turns."""
        self.clock._leave(self)


class LoopTurn(Turn):
    """A loop's turn (a `snr.core.clock.LoopTurn`): a pass of ``loop()``, then a sleep.

    Example (what `ThreadLoop` does on its thread)::

        if turn.first_turn():
            loop.loop()
            turn.sleep_until(turn.now_s() + 0.1)   # True if the loop was stopped
    """

    def __init__(self, clock: SimClock, role: str, name: str, stop: threading.Event) -> None:
        super().__init__(clock, (role, name))
        self.stop = stop

    def now_s(self) -> float:
        """The clock's time, in simulated seconds."""
        return self.clock._now_ns / _NS

    def first_turn(self) -> bool:
        """Wait for the loop's first turn; False if the loop was stopped first."""
        return self.clock._await(self, self.stop.is_set)

    def sleep_until(self, deadline_s: float) -> bool:
        """Give the clock back until simulated ``deadline_s``; True if stopped first.

        Example::

            turn.sleep_until(turn.now_s() + 0.5)   # half a simulated second
        """
        deadline_ns = max(self.clock._now_ns, round(deadline_s * _NS))
        self.clock._give_back(self, deadline_ns)
        return not self.clock._await(self, self.stop.is_set)

    def wake(self) -> None:
        """The loop was asked to stop: end its wait now."""
        self.bell.put(None)

    def leave(self) -> None:
        """The loop's thread ends: it takes no more turns."""
        self.clock._leave(self)


class SimClock(NodeClock):
    """Simulated time for every node built from a `Config` with it.

    Args:
        speed: simulated seconds per real second: None (the default) runs as
            fast as the computer can, 1.0 in real time, 0.5 at half speed.
        epoch_s: the ``created_at_s`` of pages made at simulated time 0
            (fixed, 0 by default, so a recording does not depend on the day).

    Calling the clock gives the simulated seconds since it was made. Build
    every node of a run before running any: the clock waits for each
    node's first turn.

    Example::

        clock = snr.SimClock()                         # as fast as possible
        config = snr.Config({"sim": [SimRobotFactory(world, seed=1), WallFollowerFactory(),
                                     snr.TimeoutLoopFactory(seconds=60)]}, clock=clock)
        snr.SynchronousRunner("sim", config).run()     # 60 simulated s, in about a second
        clock()                                        # 60.0

    Attributes:
        turns: how many turns it has handed out.
        jumps: how many times time jumped ahead to the next instant someone waited for.
        wall_waits: quarter seconds of real time in which nobody could act
            (waiting for a link or a stop); 0 in a run that only simulates.
        paced_waits: waits on the wall clock to keep to ``speed``.
    """

    def __init__(self, speed: Optional[float] = None, epoch_s: float = 0.0) -> None:
        if speed is not None and not (isinstance(speed, (int, float)) and speed > 0):
            raise ConfigError(
                f"SimClock(speed={speed!r}): the speed is simulated seconds per real "
                "second, a number above 0 (1.0 is real time), or None to run as fast as "
                "possible."
            )
        self.speed = None if speed is None else float(speed)
        self.epoch_s = float(epoch_s)
        self.turns = 0
        self.jumps = 0
        self.wall_waits = 0
        self.paced_waits = 0
        self._now_ns = 0
        self._lock = threading.Lock()
        self._nodes: List[NodeTurn] = []  # sorted by role
        self._loops: List[LoopTurn] = []  # sorted by (role, name)
        self._holder: Optional[Turn] = None
        self._pacer: Optional[Turn] = None  # sleeps on the wall clock until its instant
        self._anchor: Optional[Tuple[int, float]] = None  # (simulated ns, wall s) for speed

    def __call__(self) -> float:
        """Simulated seconds since the clock was made."""
        return self._now_ns / _NS

    def stamp(self) -> float:
        """The ``created_at_s`` of a page made now: ``epoch_s`` plus the simulated time.

        Example::

            SimClock(epoch_s=1000.0).stamp()   # 1000.0
        """
        return self.epoch_s + self._now_ns / _NS

    def node_turn(self, role: str, tasks: Sized, stopping: Callable[[], bool]) -> NodeTurn:
        """A turn for the node ``role`` (its queue ``tasks``); it waits for its first turn.

        Example::

            turn = clock.node_turn("sim", node.queue, node.is_terminated)
        """
        turn = NodeTurn(self, role, tasks, stopping)
        with self._lock:
            self._nodes = sorted([*self._nodes, turn], key=lambda t: t.key)
            self._release(None)
        return turn

    def loop_turn(self, role: str, name: str, stop: threading.Event) -> LoopTurn:
        """A turn for loop ``name`` of node ``role``, due now; ``stop`` ends its waits.

        Called on the node's thread as the loop starts, so the loop is in the
        lockstep before the clock can move on.

        Example::

            turn = clock.loop_turn("sim", "sim_robot", loop_stop_event)
        """
        turn = LoopTurn(self, role, name, stop)
        with self._lock:
            turn.deadline_ns = self._now_ns
            self._loops = sorted([*self._loops, turn], key=lambda t: t.key)
            self._release(None)
        return turn

    # -- the lockstep (every method below holds or takes the lock) -------------
    def _await(self, turn: Turn, stopped: Callable[[], bool]) -> bool:
        """Block until ``turn`` holds the clock (True), or ``stopped()`` (False)."""
        while True:
            timeout = _POLL_S
            with self._lock:
                if self._holder is turn:
                    return True
                if stopped():
                    turn.waiting = False  # no longer in line
                    if self._pacer is turn:
                        self._pacer = None
                    self._release(None)
                    return False
                pacing = self._pacer is turn and turn.deadline_ns is not None
                if pacing:
                    assert turn.deadline_ns is not None
                    timeout = self._wall_delay_s(turn.deadline_ns)
                    if timeout <= 0:
                        self._pick_next()  # its instant has come in real time
                        continue
                    self.paced_waits += 1
            try:
                turn.bell.get(timeout=timeout)
            except queue.Empty:
                if not pacing:
                    with self._lock:
                        if self._holder is None and self._pacer is None:
                            self.wall_waits += 1  # nobody could act: held up from outside

    def _give_back(self, turn: Turn, deadline_ns: Optional[int]) -> None:
        with self._lock:
            turn.waiting = True
            turn.deadline_ns = deadline_ns
            self._release(turn)

    def _work_arrived(self) -> None:
        with self._lock:
            self._release(None)  # if everyone waits, the node with work goes now

    def _leave(self, turn: Turn) -> None:
        with self._lock:
            turn.waiting = False
            self._nodes = [node for node in self._nodes if node is not turn]
            self._loops = [loop for loop in self._loops if loop is not turn]
            if self._pacer is turn:
                self._pacer = None
            self._release(turn)

    def _release(self, turn: Optional[Turn]) -> None:
        """``turn`` lets go of the clock if it holds it; a free clock goes to the next to act."""
        if self._holder is turn:
            self._holder = None
        if self._holder is None:
            self._pick_next()

    def _pick_next(self) -> None:
        """Hand the clock to whoever acts next (the lock held, the clock free)."""
        self._pacer = None
        for node in self._nodes:
            if node.waiting and node.has_work():
                self._grant(node)
                return
        best: Optional[LoopTurn] = None
        due_ns = 0
        for loop in self._loops:  # in key order, so the first wins a tie
            due = loop.deadline_ns
            if loop.waiting and due is not None and (best is None or due < due_ns):
                best, due_ns = loop, due
        if best is None:
            return  # nothing can act: wait for the outside world
        if due_ns > self._now_ns:
            if any(node.stopping() for node in self._nodes):
                return  # a stopping node ends at the time it was told: move on after

            if self.speed is not None and self._wall_delay_s(due_ns) > 0:
                self._pacer = best  # it sleeps on the wall clock, then jumps
                best.bell.put(None)
                return
            self._now_ns = due_ns
            self.jumps += 1
        self._grant(best)

    def _grant(self, turn: Turn) -> None:
        self._holder = turn
        turn.waiting = False
        turn.deadline_ns = None
        self.turns += 1
        turn.bell.put(None)

    def _wall_delay_s(self, due_ns: int) -> float:
        """Wall seconds until simulated ``due_ns`` at ``speed`` (<= 0: it is due)."""
        assert self.speed is not None
        wall = time.monotonic()
        if self._anchor is None:
            self._anchor = (self._now_ns, wall)
        sim0, wall0 = self._anchor
        delay = wall0 + (due_ns - sim0) / _NS / self.speed - wall
        if delay < -_LATE_S:  # far behind (a slow machine): go on from here, no rush
            self._anchor = (due_ns, wall)
            return 0.0
        return delay

    def __repr__(self) -> str:
        speed = "as fast as possible" if self.speed is None else f"speed={self.speed:g}"
        return f"<SimClock t={self():.3f} s, {speed}, {self.turns} turns>"
