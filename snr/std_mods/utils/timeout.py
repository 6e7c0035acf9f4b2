"""`TimeoutLoopFactory`: stop the node after a fixed time."""

from __future__ import annotations

from typing import Optional

from snr.core import LoopFactory, ThreadLoop, tasks
from snr.prelude import AbstractNode, ComponentError

__all__ = ["TimeoutLoop", "TimeoutLoopFactory"]


class TimeoutLoop(ThreadLoop):
    """Waits ``seconds`` (without using CPU), then schedules ``terminate("Timeout")``.

    Example::

        TimeoutLoopFactory(seconds=20)   # the node stops 20 s after it starts
    """

    def __init__(self, factory: TimeoutLoopFactory, parent: AbstractNode, seconds: float) -> None:
        super().__init__(factory, parent, factory.name)
        self.seconds = seconds

    def loop(self) -> None:
        # Measured from the node's clock so the deadline holds however late
        # this thread starts.
        remaining = self.seconds - self.parent.get_time_s()
        if remaining > 0 and self.wait_s(remaining):
            return  # stopped early by the node
        self.schedule(tasks.terminate("Timeout"))
        self.set_terminate_flag("timeout reached")


class TimeoutLoopFactory(LoopFactory):
    """Builds a `TimeoutLoop`: ``TimeoutLoopFactory(seconds=20)`` or ``(ms=500)``.

    The two add up: ``TimeoutLoopFactory(seconds=1, ms=500)`` is 1.5 s,
    counted from when the node was created.

    Example::

        components = {"receiver": [..., snr.TimeoutLoopFactory(seconds=20)]}
    """

    def __init__(self, seconds: float = 0.0, ms: float = 0.0, name: Optional[str] = None) -> None:
        super().__init__()
        total = seconds + ms / 1000.0
        if total <= 0:
            raise ComponentError(
                f"TimeoutLoopFactory(seconds={seconds}, ms={ms}) would stop the node at "
                "once; give a positive time, e.g. TimeoutLoopFactory(seconds=5)."
            )
        self.seconds = total
        self.name = name or "timeout_loop"

    def get(self, parent: AbstractNode) -> TimeoutLoop:
        return TimeoutLoop(self, parent, self.seconds)
