"""Logging set-up: readable lines on stderr unless the program set its own.

Every node logs to ``snr.<role>`` and every component to
``snr.<role>.<component>``, so one call quiets a whole node::

    node.log.setLevel(logging.WARNING)
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from typing import Callable, Optional, Tuple

from snr.core.checks.repeats import RepeatFilter  # kept here too: components import it
from snr.prelude import Mode

__all__ = ["LOG_FORMAT", "LossReport", "RepeatFilter", "ensure_log_handler", "level_for_mode"]

LOG_FORMAT = "%(asctime)s %(name)s %(levelname)s: %(message)s"
"""How SNR's own handler formats a line."""

_ROOT = "snr"


def level_for_mode(mode: Mode) -> int:
    """INFO while developing or deployed, WARNING in tests (quiet output)."""
    return logging.WARNING if mode is Mode.TEST else logging.INFO


def ensure_log_handler() -> None:
    """Give the ``snr`` logger SNR's own stderr handler, once per process.

    It writes a line only while the program has set no handler of its own,
    so ``logging.basicConfig`` gets each line once, formatted its way.

    Example::

        ensure_log_handler()          # what every Node does
        logging.basicConfig(level=logging.INFO)
        logging.getLogger("snr.urov").warning("Depth sensor silent")   # printed once
    """
    snr_log = logging.getLogger(_ROOT)
    if any(isinstance(handler, _DefaultHandler) for handler in snr_log.handlers):
        return
    handler = _DefaultHandler(sys.stderr)
    handler.setFormatter(logging.Formatter(LOG_FORMAT, datefmt="%H:%M:%S"))
    snr_log.addHandler(handler)


class _DefaultHandler(logging.StreamHandler):  # type: ignore[type-arg]
    """SNR's stderr handler: it steps aside for any handler the program set.

    It decides line by line: logging may be configured later.
    """

    def handle(self, record: logging.LogRecord) -> bool:
        if _another_handler_takes(record, self):
            return False
        return super().handle(record)


def _another_handler_takes(record: logging.LogRecord, own: logging.Handler) -> bool:
    """Whether ``record`` reaches a handler that prints or keeps it, besides ``own``.

    A handler marked ``snr_only_listens`` (the console's) does not count.
    """
    logger: Optional[logging.Logger] = logging.getLogger(record.name)
    while logger is not None:
        for handler in logger.handlers:
            if (
                handler is not own
                and record.levelno >= handler.level
                and not getattr(handler, "snr_only_listens", False)
            ):
                return True
        logger = logger.parent if logger.propagate else None
    return False


class LossReport:
    """Counts what had to be dropped, says so at most once a second, and says when it ended.

    A drop is never silent: a line at most every ``every_s`` seconds, then one
    "recovered" line with the total. Safe from any thread.

    Example::

        loss = LossReport(log, "tasks from loops", "the node's queue is full")
        loss.dropped()          # logs at once: the first drop
        loss.dropped(5)         # counted; logged a second later if drops go on
        loss.recovered()        # "recovered: 6 tasks from loops dropped over 0.2 s"
        loss.total              # 6: every drop so far (``last_drop``: the last one's time)
    """

    def __init__(
        self,
        log: logging.Logger,
        what: str,
        why: str,
        every_s: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
        verb: str = "Dropped",
    ) -> None:
        self.log = log
        self.what = what
        self.why = why
        self.verb = verb
        self.every_s = every_s
        self._clock = clock
        self._lock = threading.Lock()
        self.total = 0
        self._episode = 0
        self._unsaid = 0
        self._episode_start: Optional[float] = None
        self._last_said = 0.0
        self.last_drop = 0.0

    def dropped(self, n: int = 1) -> None:
        """Count ``n`` more dropped items; log the count if a second has passed."""
        with self._lock:
            now = self.last_drop = self._clock()
            self.total += n
            self._episode += n
            self._unsaid += n
            if self._episode_start is None:
                self._episode_start = now
            elif now - self._last_said < self.every_s:
                return
            self._last_said = now
            unsaid, self._unsaid = self._unsaid, 0
            episode, since = self._episode, now - self._episode_start
        self.log.warning(
            f"{self.verb} {unsaid} {self.what} ({episode} in the last {since:.1f} s, "
            f"{self.total} in all): {self.why}."
        )

    def _end(self, quiet_s: float = 0.0) -> Optional[Tuple[int, int, float]]:
        """End the episode: (unsaid, episode, seconds); None without one or within ``quiet_s``."""
        with self._lock:
            now = self._clock()
            if self._episode_start is None or now - self.last_drop < quiet_s:
                return None
            ended = self._unsaid, self._episode, now - self._episode_start
            self._episode, self._unsaid, self._episode_start = 0, 0, None
            return ended

    def recovered(self, quiet_s: float = 0.0) -> bool:
        """The cause of the drops has passed: log the episode's total once.

        With ``quiet_s``, only if nothing was dropped for that long (so a
        peer that keeps up by fits and starts gives one episode, not many).
        Returns True if the episode ended now.
        """
        ended = self._end(quiet_s)
        if ended is not None:
            _, episode, since = ended
            self.log.warning(
                f"Recovered: {episode} {self.what} {self.verb.lower()} over {since:.1f} s."
            )
        return ended is not None

    def ended(self, how: str) -> bool:
        """The source of the drops is gone (e.g. a link closed): say the drops not yet logged.

        Ends the episode (no "Recovered" line follows); True if there was anything to say.

        Example::

            loss.ended("the link ended")
            # "Dropped 3 more pages for 'urov' before the link ended (8 over 0.4 s, 8 in all)."
        """
        ended = self._end()
        if ended is None or not ended[0]:  # nothing, or every drop is in the log already
            return False
        unsaid, episode, since = ended
        self.log.warning(
            f"{self.verb} {unsaid} more {self.what} before {how} ({episode} over {since:.1f} s, "
            f"{self.total} in all)."
        )
        return True

    @property
    def dropping(self) -> bool:
        """True between the first drop and ``recovered()``."""
        return self._episode_start is not None
