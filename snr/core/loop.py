"""`ThreadLoop`: user code that runs over and over in its own thread."""

from __future__ import annotations

import enum
import threading
import time
from typing import ClassVar, Optional

from snr.core import tasks
from snr.core.checks import life_cycle
from snr.core.checks.explain import check_loop_class
from snr.core.checks.student_code import running_line
from snr.core.clock import LoopTurn, clock_of
from snr.core.component import Component
from snr.prelude.abstract import AbstractFactory, AbstractLoop, AbstractNode
from snr.prelude.names import ComponentName, TaskType
from snr.prelude.task import Task

__all__ = ["LoopState", "ThreadLoop"]


class LoopState(enum.Enum):
    """Where a loop is in its life: NEW → RUNNING → STOPPED.

    Example::

        loop.state is LoopState.RUNNING
    """

    NEW = "new"
    RUNNING = "running"
    STOPPED = "stopped"


class ThreadLoop(Component, AbstractLoop):
    """Subclass this to run code continuously beside the node (thesis 4.4.3).

    Write ``loop()`` and, if needed, ``setup()``, ``halt()`` and ``terminate()``.
    ``loop()`` runs again and again on the loop's own thread, at most
    ``max_tick_rate_hz`` times a second (0: no limit: it must block on I/O).
    From the thread use only the thread-safe ``schedule``, ``store_data``,
    ``get_page`` and ``get_data``. On a `SimClock`, a loop with a tick rate
    takes turns with its node (docs/sim-time.md).

    Example::

        class Clock(ThreadLoop):
            def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "clock", max_tick_rate_hz=10)

            def loop(self) -> None:
                self.store_data("time_s", self.parent.get_time_s())
    """

    follows_clock: ClassVar[bool] = False
    """True for a loop with no tick rate that waits only on time (``wait_s``).

    On a `SimClock` it then takes turns, as loops with a tick rate do
    (`TimeoutLoop` sets it). Leave it False for a loop that blocks on the
    outside world: holding the clock while blocked would stop everything.
    """

    def __init__(
        self,
        factory: AbstractFactory,
        parent: AbstractNode,
        name: ComponentName,
        max_tick_rate_hz: float = 0.0,
    ) -> None:
        super().__init__(factory, parent, name)
        check_loop_class(type(self), ThreadLoop.loop, max_tick_rate_hz)
        self.max_tick_rate_hz = max_tick_rate_hz
        self.state = LoopState.NEW
        self._clock_turn: Optional[LoopTurn] = None  # on a clock with turns
        self.terminate_reason = ""
        self._stop_event = threading.Event()
        # Held while the loop may run; released to stop it. Waiting on a lock,
        # not the Event, hands the GIL back to the node sooner after each pass.
        self._running_lock = threading.Lock()
        self._running_lock.acquire()
        self._thread: Optional[threading.Thread] = None

    def setup(self) -> None:
        """Runs once on the loop's thread before the first ``loop()``.

        What it stores is in the datastore by the first ``loop()``.

        Example::

            def setup(self) -> None:
                self.store_data("thruster_data", 0)   # loop() can read it at once
        """

    def loop(self) -> None:
        """One pass of the work; override this (required)."""

    # -- stopping -----------------------------------------------------------
    def set_terminate_flag(self, reason: str = "") -> None:
        """Stop this loop after the current pass (the node keeps running).

        Example::

            if done:
                self.set_terminate_flag("replayed every line")
        """
        if not self._stop_event.is_set():
            self.terminate_reason = reason
            self._stop_event.set()
            try:
                self._running_lock.release()
            except RuntimeError:
                pass  # another thread stopped it at the same moment
            if self._clock_turn is not None:
                self._clock_turn.wake()

    def is_terminated(self) -> bool:
        """True once the loop has been asked to stop."""
        return self._stop_event.is_set()

    def wait_s(self, seconds: float) -> bool:
        """Sleep up to ``seconds``, waking early when the loop is stopped.

        Use it instead of ``time.sleep`` inside ``loop()`` so shutdown is quick.
        Returns True if the loop was stopped while waiting.
        """
        turn = self._clock_turn
        if turn is not None and threading.current_thread() is self._thread:
            return turn.sleep_until(turn.now_s() + seconds)
        if self._running_lock.acquire(timeout=max(0.0, seconds)):
            self._running_lock.release()  # stays released: the loop is stopped
            return True
        return False

    # -- driven by the node -------------------------------------------------
    def start_thread(self) -> None:
        """Called by the node: ``begin()``, then ``setup()`` and ``loop()`` on a new thread.

        Raises:
            NodeStateError: the loop is running already.
        """
        if self.state is LoopState.RUNNING:
            raise life_cycle.started_twice_error(self.name, self.state.value)
        if self.state is LoopState.STOPPED:  # after a reload that failed: run again
            self._resume_running()
        self.begin()
        self.state = LoopState.RUNNING
        if self.max_tick_rate_hz > 0 or self.follows_clock:
            # Registered here, on the node's thread, so a clock with turns cannot
            # move on before the new thread is in line: the run stays the same.
            clock = clock_of(self.parent.config)
            self._clock_turn = clock.loop_turn(self.parent.role, self.name, self._stop_event)
        self._thread = threading.Thread(
            target=self._run, name=f"snr-{self.parent.role}-{self.name}", daemon=True
        )
        self._thread.start()

    def cancel_stop(self) -> None:
        """Take back a request to stop, if the thread still runs: the loop carries on.

        Example (what the node does when a loop would not stop to be reloaded)::

            loop.cancel_stop()
        """
        if self.is_alive():
            self._resume_running()

    def _resume_running(self) -> None:
        self.terminate_reason = ""
        if self._stop_event.is_set():
            self._running_lock.acquire()  # released by the stop: take it back
            self._stop_event.clear()

    def join(self, timeout_s: Optional[float] = None) -> None:
        """Wait (up to ``timeout_s``) for the loop's thread to end."""
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout_s)

    def is_alive(self) -> bool:
        """True while the loop's thread is running."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def thread_id(self) -> Optional[int]:
        """The id of the loop's thread (its ``threading.get_ident()``), or None before it starts.

        Example::

            sys._current_frames().get(loop.thread_id)   # what the loop is doing now
        """
        thread = self._thread
        return None if thread is None else thread.ident

    def where_running(self) -> str:
        """The line the loop's thread is on now (e.g. where it is blocked), or ""."""
        return running_line(self.thread_id) if self.is_alive() else ""

    def _wait_for_setup_tasks(self, timeout_s: float = 1.0) -> None:
        """Let the node handle what ``setup()`` stored before the first ``loop()``.

        A ``loop()`` reading it at once (thesis listing A.4) must find it: the
        node handles tasks in order, so the wait is for a marker task behind them.
        """
        turn = self._clock_turn
        if turn is not None:
            turn.sleep_until(turn.now_s())
            return
        caught_up = threading.Event()
        self.schedule(Task(TaskType.event, tasks.CAUGHT_UP, [caught_up]))
        deadline = time.monotonic() + timeout_s
        while not caught_up.wait(0.01):
            if self._stop_event.is_set() or time.monotonic() > deadline:
                return

    def _run(self) -> None:
        profiler = self.parent.profiler
        cell = profiler.loop_cell(self.name) if profiler is not None else None
        period_s = 1.0 / self.max_tick_rate_hz if self.max_tick_rate_hz > 0 else 0.0
        stop = self._stop_event
        clock = time.perf_counter
        turn = self._clock_turn
        try:
            if turn is not None and not turn.first_turn():
                return  # stopped before its first turn
            self.setup()
            if type(self).setup is not ThreadLoop.setup:
                self._wait_for_setup_tasks()
            # A stored page reaches the node only once this thread blocks and
            # lets go of the GIL: so little between loop() and the wait.
            running, rate_hz = self._running_lock, self.max_tick_rate_hz
            first_s, ticks = (0.0 if turn is None else turn.now_s()), 0
            while not stop.is_set():
                started = clock()
                self.loop()
                ended = clock()
                if turn is not None:  # simulated time: tick n is at first + n / rate, exactly
                    ticks += 1
                    stopped = rate_hz > 0 and turn.sleep_until(first_s + ticks / rate_hz)
                else:
                    left_s = period_s - (ended - started)  # of this pass's period
                    stopped = left_s > 0 and running.acquire(True, left_s)
                    if stopped:
                        running.release()  # stays released: the loop is stopped
                if cell is not None:
                    cell[0] += 1
                    cell[1] += ended - started
                if stopped:
                    break
        except BaseException as error:
            # sys.exit() and Ctrl-C too: they would end this thread silently.
            self.parent.loop_failed(self, error)
        finally:
            self.state = LoopState.STOPPED
            if turn is not None:
                turn.leave()
