"""`RepeatFilter`: a failure repeated over and over, logged in full a few times, then counted."""

from __future__ import annotations

import logging
import time
from typing import Any, Callable, Dict, Hashable, List

__all__ = ["RepeatFilter"]


class RepeatFilter:
    """Logs the first few of a repeated message in full, then a count every few seconds.

    Messages are grouped by a key (e.g. the handler and the error's type):
    the first ``first`` of each are logged in full, then one count every ``every_s``.

    Example::

        repeats = RepeatFilter(log)
        for reading in readings:
            repeats.report(("parse", "ValueError"), "bad reading from the sonar",
                           logging.WARNING, "Bad reading %r", reading)
        repeats.flush()   # a last summary for anything not yet counted aloud
    """

    def __init__(
        self,
        log: logging.Logger,
        first: int = 3,
        every_s: float = 5.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.log = log
        self.first = first
        self.every_s = every_s
        self._clock = clock
        # key -> [times seen, not yet summarised, start of this summary period, level, what]
        self._seen: Dict[Hashable, List[Any]] = {}

    def report(self, key: Hashable, what: str, level: int, msg: str, *args: Any) -> None:
        """Log ``msg % args`` in full, or count it under ``key`` (``what`` names it)."""
        now = self._clock()
        seen = self._seen.setdefault(key, [0, 0, now, level, what])
        seen[0] += 1
        if seen[0] <= self.first:
            if seen[0] == self.first:
                msg += (
                    f"\n(More of these are counted from now on: one line every {self.every_s:g} s.)"
                )
            self.log.log(level, msg, *args)
            seen[2] = now
            return
        seen[1] += 1
        if now - seen[2] >= self.every_s:
            self._summarise(seen, now)

    def _summarise(self, seen: List[Any], now: float) -> None:
        count, unsaid, since, level, what = seen
        self.log.log(
            level, f"{what}: {unsaid} more times in the last {now - since:.1f} s ({count} in all)."
        )
        seen[1] = 0
        seen[2] = now

    def flush(self) -> None:
        """Log the summary of every group with uncounted repeats (e.g. at shutdown)."""
        now = self._clock()
        for seen in self._seen.values():
            if seen[1]:
                self._summarise(seen, now)
