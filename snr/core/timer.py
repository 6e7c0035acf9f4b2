"""`Timer`: a stopwatch with an injectable clock, for nodes and tests."""

from __future__ import annotations

import time
from typing import Callable

__all__ = ["Clock", "Timer"]

Clock = Callable[[], float]
"""A function returning seconds, such as ``time.perf_counter``."""


class Timer:
    """Measures seconds since it was made (or last reset).

    Pass your own ``clock`` in tests to control time.

    Example::

        timer = Timer()
        do_work()
        print(f"took {timer.current_s() * 1000:.1f} ms")
    """

    def __init__(self, clock: Clock = time.perf_counter) -> None:
        self._clock = clock
        self._start = clock()

    def current_s(self) -> float:
        """Seconds elapsed since the timer started."""
        return self._clock() - self._start

    def reset(self) -> None:
        """Start counting from zero again."""
        self._start = self._clock()
