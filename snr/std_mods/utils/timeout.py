"""`TimeoutLoopFactory`: stop the node after a fixed time."""

from __future__ import annotations

from typing import Optional

from snr.core import LoopFactory, ThreadLoop, tasks
from snr.core.checks.call_checks import wrong_call
from snr.prelude import AbstractNode, ComponentError

__all__ = ["TimeoutLoop", "TimeoutLoopFactory"]


class TimeoutLoop(ThreadLoop):
    """Waits ``seconds`` (without using CPU), then schedules ``terminate("Timeout")``.

    Example::

        TimeoutLoopFactory(seconds=20)   # the node stops 20 s after it starts

    On a `SimClock` the seconds are simulated: the node stops when the
    clock reaches them, however fast that is.
    """

    follows_clock = True  # it only waits on time: in simulated time, it takes turns

    def __init__(self, factory: TimeoutLoopFactory, parent: AbstractNode, seconds: float) -> None:
        super().__init__(factory, parent, factory.name)
        self.seconds = seconds

    def loop(self) -> None:
        if self.seconds == 0:
            self.dbg(
                "TimeoutLoopFactory() was given no time, so it stops the node as soon as it "
                "starts (a start-and-stop check). Give a time to keep the node running, "
                "e.g. TimeoutLoopFactory(seconds=5)."
            )
        # Measured from the node's clock so the deadline holds however late
        # this thread starts.
        remaining = self.seconds - self.parent.get_time_s()
        if remaining > 0 and self.wait_s(remaining):
            return  # stopped early by the node
        self.schedule(tasks.terminate("Timeout"))
        self.set_terminate_flag("timeout reached")


class TimeoutLoopFactory(LoopFactory):
    """Builds a `TimeoutLoop`: ``TimeoutLoopFactory(seconds=20)`` or ``(ms=500)``.

    The two add up, counted from when the node was created; with no time the
    node stops as soon as it has started (a start-and-stop check).

    Example::

        components = {"receiver": [..., snr.TimeoutLoopFactory(seconds=20)]}
        self.run_test_node([MyEndpointFactory(), TimeoutLoopFactory()])  # start, stop
    """

    def __init__(self, seconds: float = 0.0, ms: float = 0.0, name: Optional[str] = None) -> None:
        super().__init__()
        if not all(isinstance(t, (int, float)) for t in (seconds, ms)):
            raise ComponentError(
                wrong_call(
                    "TimeoutLoopFactory",
                    TimeoutLoopFactory,
                    (seconds, ms) if ms else (seconds,),
                    "the time must be a number of seconds (or ms), not "
                    f"{type(seconds if not isinstance(seconds, (int, float)) else ms).__name__}.",
                )
            )
        total = seconds + ms / 1000.0
        if not total >= 0:  # negative, or NaN
            raise ComponentError(
                f"TimeoutLoopFactory(seconds={seconds}, ms={ms}) is a negative time. Give "
                "a positive time, e.g. TimeoutLoopFactory(seconds=5), or no time at all, "
                "TimeoutLoopFactory(), to stop the node as soon as it starts."
            )
        self.seconds = total
        self.name = name or "timeout_loop"

    def get(self, parent: AbstractNode) -> TimeoutLoop:
        return TimeoutLoop(self, parent, self.seconds)
