"""`MissingKeyHints`: one log hint per data key that is read but never stored.

``get_data``/``get_page`` return None for a key nothing has stored: that is
the thesis API, and reading a key before its first page arrives is normal
(listing A.7 does). A misspelled key looks exactly the same, though, so in
DEBUG mode the node asks this helper to watch the misses and say something
when one looks like a mistake:

* after ``typo_s`` a missing key spelled almost like a stored one (warning,
  with the closest match), or
* after ``missing_s`` any key still missing (info).

Each key is reported at most once, and the closest-match search runs at most
every ``CHECK_EVERY_S`` per key, so a loop polling a missing key stays cheap.

A key that some handler on the node is registered for (``(TaskType.store_page,
key)`` or ``(TaskType.process_data, key)``) is *expected*: the node's own wiring
says its pages will come, e.g. once a peer connects, so reading it early is not
a mistake and gets no hint. (If that handler's key is the misspelt one,
``check_handlers`` says so.)
"""

from __future__ import annotations

import logging
import threading
from typing import Callable, Dict, Iterable, List, Optional, Set, Tuple

from snr.prelude import DataKey, TaskHandler
from snr.prelude.errors import caller_location, closest_match, describe_callable

__all__ = ["MissingKeyHints"]


class MissingKeyHints:
    """Watches reads of missing data keys and logs a hint when one looks wrong.

    Args:
        log: where hints go (the node's logger).
        clock: seconds, e.g. ``node.timer.current_s``.

    Example::

        hints = MissingKeyHints(node.log, node.timer.current_s)
        if page is None:
            hints.missed("depht", node.datastore)   # may log "Did you mean 'depth'?"
    """

    CHECK_EVERY_S = 0.25
    MAX_WATCHED_KEYS = 1000

    def __init__(
        self,
        log: logging.Logger,
        clock: Callable[[], float],
        typo_s: float = 0.5,
        missing_s: float = 5.0,
        handlers_s: float = 3.0,
    ) -> None:
        self.log = log
        self.clock = clock
        self.typo_s = typo_s
        self.missing_s = missing_s
        self.handlers_s = handlers_s
        self._first_and_next_check: Dict[DataKey, List[float]] = {}
        self._reported: Set[DataKey] = set()
        self._lock = threading.Lock()  # loops read keys from their own threads
        #: Returns the keys the node's handlers are registered for (set by the node).
        self.expected_keys: Callable[[], Set[DataKey]] = set

    def missed(self, key: DataKey, stored_keys: Iterable[DataKey]) -> None:
        """Note a read of ``key`` that found nothing; maybe log a hint."""
        if key in self._reported:
            return
        now = self.clock()
        with self._lock:
            times = self._first_and_next_check.get(key)
            if times is None:
                if len(self._first_and_next_check) < self.MAX_WATCHED_KEYS:
                    self._first_and_next_check[key] = [now, now + self.typo_s]
                return
            first_read_s, next_check_s = times
            if now < next_check_s:
                return
            times[1] = min(now + self.CHECK_EVERY_S, first_read_s + self.missing_s)
            waited_s = now - first_read_s
            if key in self.expected_keys():
                # A handler waits for this key: its pages are planned, not misspelt.
                self._reported.add(key)
                del self._first_and_next_check[key]
                return
            stored = [k for k in list(stored_keys) if isinstance(k, str)]
            guess = closest_match(key, stored) if isinstance(key, str) else None
            if guess is None and waited_s < self.missing_s:
                return
            self._reported.add(key)
            del self._first_and_next_check[key]
        self._report(key, guess, stored, waited_s)

    def _report(
        self, key: DataKey, guess: Optional[str], stored: List[str], waited_s: float
    ) -> None:
        shown = ", ".join(repr(k) for k in stored[:20]) or "none yet"
        where = caller_location()
        footer = (
            "get_data/get_page return None until something stores the key. (This hint "
            "shows once per key, in DEBUG mode only.)"
        )
        if guess is not None:
            self.log.warning(
                "Nothing is stored under data key %r (read at %s). Did you mean %r? "
                "Stored keys: %s. %s",
                key,
                where,
                guess,
                shown,
                footer,
            )
        else:
            self.log.info(
                "Data key %r has been read for %.1f s (at %s) but nothing has stored it. "
                "Stored keys: %s. If a component should store it, check that it runs "
                "and spells the key the same way. %s",
                key,
                waited_s,
                where,
                shown,
                footer,
            )

    def check_handlers(
        self, handled: Iterable[Tuple[DataKey, TaskHandler]], stored_keys: Iterable[DataKey]
    ) -> None:
        """Warn, once per key, about a handler for a data key that looks misspelled.

        Called once, ``handlers_s`` after the node started. A handler registered
        for ``(TaskType.store_page, key)`` when nothing has stored ``key`` but a
        key spelled almost the same was stored is the commonest silent wiring
        mistake: the handler simply never runs. A key with no close match stays
        quiet (its pages may come later, e.g. from a node not yet connected).

        Example::

            hints.check_handlers([("X", doubler.double)], ["x"])
            # Doubler.double (robot.py:9) handles pages under 'X', but nothing stored 'X' ...
        """
        stored = [k for k in list(stored_keys) if isinstance(k, str)]
        for key, handler in handled:
            if key in stored or key in self._reported or not isinstance(key, str):
                continue
            same_but_case = [k for k in stored if k.lower() == key.lower()]
            guess = same_but_case[0] if same_but_case else closest_match(key, stored)
            if guess is None:
                continue
            self._reported.add(key)
            self.log.warning(
                "%s handles pages under %r, but nothing stored %r in the first %.1f s, "
                "while %r was stored. Did you mean %r? Data keys must match exactly "
                "(capitals too). (This hint shows once per key, in DEBUG mode only; "
                "node.key_hints = None turns such hints off.)",
                describe_callable(handler),
                key,
                key,
                self.handlers_s,
                guess,
                guess,
            )
