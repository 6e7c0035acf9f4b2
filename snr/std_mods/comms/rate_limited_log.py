"""`RateLimitedLog`: a link's news in full, or counted when it comes in a flood.

The node's own dropped tasks are counted by `snr.core.logs.LossReport`.
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from typing import Any, Callable, Deque, Dict, List

__all__ = ["RateLimitedLog"]


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
            counted = len(shown) >= self.burst
            if counted:
                self._unsaid.setdefault(what, [0, now, level])[0] += 1
            else:
                shown.append(now)
        self.tick()
        if not counted:
            self.log.log(level, msg, *args)
        return counted

    def tick(self) -> bool:
        """Log the counts whose window has passed (any thread); True while counts wait."""
        return self._say_counts(self.window_s)

    def flush(self) -> None:
        """Log every count not yet said (e.g. when the component stops)."""
        self._say_counts(0.0)

    def _say_counts(self, age_s: float) -> bool:
        with self._lock:
            now = self._clock()
            due = [(what, n) for what, n in self._unsaid.items() if now - n[1] >= age_s]
            for what, _ in due:
                del self._unsaid[what]
            waiting = bool(self._unsaid)
        for what, (count, since, level) in due:
            self.log.log(
                level,
                f"{what}: {count} more in the last {now - since:.1f} s, not logged one by one "
                f"(over {self.burst} in {self.window_s:g} s).",
            )
        return waiting
