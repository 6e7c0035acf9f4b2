"""`NodeClock`: the time a node and its loops run on; the wall's by default.

The one extension point for time: `Config(clock=...)` hands its clock to every
node built from it. The wall hands out no turns; `snr.utils.sim_clock.SimClock`
(docs/sim-time.md) makes nodes and loops take turns.
"""

from __future__ import annotations

import threading
import time
from typing import Callable, Optional, Protocol, Sized

__all__ = ["LoopTurn", "NodeClock", "NodeTurn", "clock_of"]


class NodeTurn(Protocol):
    """A node's place on a clock that takes turns; also the node's idle waiter.

    Example (what `Node` does)::

        turn = clock.node_turn("sim", node.queue, node.is_terminated)
        if turn is not None:
            node.queue.use_waiter(turn)
            turn.begin()   # in node.loop(), before the components start
    """

    def begin(self) -> None:
        """Wait for the node's first turn."""

    def end(self) -> None:
        """The node has stopped: it takes no more turns."""

    def wait(self, timeout_s: Optional[float]) -> None:
        """The queue is empty: give the clock back until the node has work or stops."""

    def woken(self) -> None:
        """After ``wait``: nothing to do (`IdleWaiter.woken`)."""

    def wake(self) -> None:
        """A task arrived, or the node stops (any thread)."""


class LoopTurn(Protocol):
    """A loop's place on a clock that takes turns: a pass of ``loop()`` per turn.

    Example (what `ThreadLoop` does on its thread)::

        if turn.first_turn():
            loop.loop()
            turn.sleep_until(turn.now_s() + 0.1)   # True if the loop was stopped
    """

    def now_s(self) -> float:
        """The clock's time, in seconds."""

    def first_turn(self) -> bool:
        """Wait for the loop's first turn; False if the loop was stopped first."""

    def sleep_until(self, deadline_s: float) -> bool:
        """Give the clock back until ``deadline_s``; True if the loop was stopped first."""

    def wake(self) -> None:
        """The loop was asked to stop: end its wait now (any thread)."""

    def leave(self) -> None:
        """The loop's thread ends: it takes no more turns."""


class NodeClock:
    """The wall clock, and what every clock gives a node: seconds, stamps, turns.

    Calling it gives seconds; ``stamp()`` a page's ``created_at_s``; the wall
    hands out no turns (None).

    Example::

        clock = clock_of(config)                    # the config's clock, or the wall's
        Timer(clock).current_s()                    # seconds since now
        clock.node_turn("robot", queue, lambda: False)   # None: no turns on the wall
    """

    __call__ = staticmethod(time.perf_counter)
    stamp = staticmethod(time.time)  # a C function: a page's stamp costs no Python call

    def node_turn(self, role: str, tasks: Sized, stop: Callable[[], bool]) -> Optional[NodeTurn]:
        """The turn of node ``role`` (its queue ``tasks``), or None: no turns."""
        return None

    def loop_turn(self, role: str, name: str, stop: threading.Event) -> Optional[LoopTurn]:
        """The turn of loop ``name`` of node ``role`` (``stop`` ends its waits), or None."""
        return None


_WALL = NodeClock()


def clock_of(config: object) -> NodeClock:
    """The clock a config hands its nodes: its ``clock``, or the wall's.

    Example::

        clock_of(Config({"sim": [...]}, clock=SimClock()))   # the SimClock
        clock_of(Config({"sim": [...]}))                     # the wall's NodeClock
    """
    clock: Optional[NodeClock] = getattr(config, "clock", None)
    return _WALL if clock is None else clock
