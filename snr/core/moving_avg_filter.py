"""`MovingAvgFilter`: the mean of the last few samples (the state of listing A.1).

It lives in the runtime layer, as it did in 2021 (listing A.1 finds it with
``from snr.core import *``); the endpoint and factory that use it are in
`snr.std_mods.filters.moving_average`.
"""

from __future__ import annotations

from typing import Deque

__all__ = ["MovingAvgFilter"]


class MovingAvgFilter:
    """The mean of the last ``maxlen`` samples of a deque.

    The deque is passed in, not made here, so a factory can own it and a
    rebuilt endpoint (after a hot reload) keeps the samples.

    Example::

        f = MovingAvgFilter(collections.deque(maxlen=2))
        f.update(1); f.update(3); f.avg()   # 2.0
    """

    def __init__(self, backing_deque: Deque[float]) -> None:
        self.samples = backing_deque

    def update(self, value: float) -> None:
        """Add a sample (the oldest drops out when full)."""
        self.samples.append(value)

    def avg(self) -> float:
        """The mean of the samples held (0.0 when there are none)."""
        return sum(self.samples) / len(self.samples) if self.samples else 0.0
