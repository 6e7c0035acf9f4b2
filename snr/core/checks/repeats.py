"""Log lines that come too often: counted, not written one by one.

* `RepeatFilter`: a failure repeated over and over, logged in full a few
  times, then counted. A DEPLOYED node keeps running when a handler fails, so
  a handler that raises on every task would write thousands of identical
  lines a second; the node's `snr.core.checks.failures.FailureReport` logs
  each kind of failure in full three times, then counts it. Components that
  read bad input again and again (a recorder, a replayer, a console) use it too.
* `RateLimitedLog`: news that is welcome one by one but not a thousand times
  a second (the comms: a client connecting), counted past a burst.

The node itself needs neither to run; components import both from
``snr.core.logs``.

Example::

    repeats = RepeatFilter(log)
    repeats.report(("parse", "ValueError"), "bad reading from the sonar",
                   logging.WARNING, "Bad reading %r", reading)
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from typing import Any, Callable, Deque, Dict, Hashable, List

__all__ = ["RateLimitedLog", "RepeatFilter"]


class RepeatFilter:
    """Logs the first few of a repeated message in full, then a count every few seconds.

    A handler that raises on every task would otherwise write thousands of
    identical lines a second and bury everything else in the log. Messages
    are grouped by a key (e.g. the handler and the error's type): the first
    ``first`` of each group are logged in full, then at most one summary line
    every ``every_s`` seconds says how many more there were.

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

    def count(self, key: Hashable) -> int:
        """How many times ``key`` was reported in all."""
        return int(self._seen.get(key, [0])[0])

    def flush(self) -> None:
        """Log the summary of every group with uncounted repeats (e.g. at shutdown)."""
        now = self._clock()
        for seen in self._seen.values():
            if seen[1]:
                self._summarise(seen, now)


class RateLimitedLog:
    """Logs news in full unless it comes in a flood; then counts it, one line a window.

    For news that is welcome one by one but not a thousand times a second,
    such as a client connecting: lines of one kind (``what``) are logged in
    full while no more than ``burst`` came in the last ``window_s`` seconds;
    past that they are counted, and ``tick()`` (call it every second or so)
    logs how many, once a window. Safe to call from any thread.

    Example::

        news = RateLimitedLog(log, burst=20, window_s=10.0)
        news.report("Clients connected", logging.INFO, "Client %s connected", "urov")
        news.tick()    # in a loop: "Clients connected: 480 more in the last 10.0 s, ..."
        news.flush()   # at the end: every count not yet said
    """

    def __init__(
        self,
        log: logging.Logger,
        burst: int = 20,
        window_s: float = 10.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.log = log
        self.burst = burst
        self.window_s = window_s
        self._clock = clock
        self._lock = threading.Lock()
        self._shown: Dict[str, Deque[float]] = {}  # what -> when its recent full lines went out
        self._unsaid: Dict[str, List[Any]] = {}  # what -> [count, since, level]

    def report(self, what: str, level: int, msg: str, *args: Any) -> bool:
        """Log ``msg % args`` in full, or count it under ``what`` if they come too fast.

        Returns True if it was counted: a `tick` must then come after the window.
        """
        with self._lock:
            now = self._clock()
            shown = self._shown.setdefault(what, collections.deque())
            while shown and now - shown[0] >= self.window_s:
                shown.popleft()
            full = len(shown) < self.burst
            if full:
                shown.append(now)
            else:
                self._unsaid.setdefault(what, [0, now, level])[0] += 1
        self._say_counts(self.window_s)
        if full:
            self.log.log(level, msg, *args)
        return not full

    def tick(self) -> None:
        """Log the counts whose window has passed (any thread)."""
        self._say_counts(self.window_s)

    def flush(self) -> None:
        """Log every count not yet said (e.g. when the component stops)."""
        self._say_counts(0.0)

    def _say_counts(self, age_s: float) -> None:
        """Log, and forget, every count at least ``age_s`` old."""
        with self._lock:
            now = self._clock()
            due = [
                (what, unsaid) for what, unsaid in self._unsaid.items() if now - unsaid[1] >= age_s
            ]
            for what, _ in due:
                del self._unsaid[what]
        for what, (count, since, level) in due:
            self.log.log(
                level,
                f"{what}: {count} more in the last {now - since:.1f} s, not logged one by one "
                f"(over {self.burst} in {self.window_s:g} s).",
            )
