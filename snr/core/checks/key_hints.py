"""`MissingKeyHints`: one log hint per data key that is read but never stored.

``get_data`` returns None for a key nothing has stored, both before its first
page and when the key is misspelt; in DEBUG mode the node tells this helper of
each miss (docs/errors.md, 9). After ``typo_s`` a key spelled almost like a
stored one gets a warning, after ``missing_s`` any key still missing an info
line; once per key, and the search runs at most every ``CHECK_EVERY_S``. A key
some handler on the node waits for is expected, not misspelt, and a key whose
page is late (``on_its_way``: queued, or behind a stuck handler) waits.

Example::

    hints = MissingKeyHints(node.log, node.timer.current_s)
    hints.missed("depht", node.datastore)   # may log "Did you mean 'depth'?"
"""

from __future__ import annotations

import logging
import threading
from typing import Callable, Dict, Iterable, List, Mapping, Optional, Set, Tuple

from snr.core.checks.error_text import closest_key, closest_match, suggestion
from snr.core.checks.student_code import caller_location, describe_callable, is_snr
from snr.prelude import DataKey, TaskHandler

__all__ = ["MissingKeyHints"]


class MissingKeyHints:
    """Watches reads of missing data keys and logs a hint when one looks wrong.

    ``get_data`` returns None for a key nothing has stored, both before its first
    page and when the key is misspelt; a DEBUG node tells this helper of each miss.
    After ``typo_s`` a key spelled almost like a stored one gets a warning, after
    ``missing_s`` any key still missing an info line; once per key, searching at
    most every ``CHECK_EVERY_S``. A key a handler on the node waits for is expected,
    not misspelt; a key whose page is late (``on_its_way``) waits.

    Args:
        log: where hints go (the node's logger).
        clock: seconds, e.g. ``node.timer.current_s``.
        typo_s, missing_s: how long a missing key is read before a hint.
        handlers_s: when, after the node starts, `check_handlers` runs.
        role: the node's role: a hint says when a key came from another node.
        link_s: when, after a link comes up, `check_link` runs.
        on_its_way: True for a key whose page is late, not missing: no hint yet.

    Example::

        hints = MissingKeyHints(node.log, node.timer.current_s)
        if page is None:
            hints.missed("depht", node.datastore)   # may log "Did you mean 'depth'?"

    Attributes:
        last_missed: for each thread, the last key it read and found missing
            (the watchdog names the key a stuck handler waits for).
    """

    CHECK_EVERY_S = 0.25
    MAX_WATCHED_KEYS = 1000
    MAX_READERS = 100

    def __init__(
        self,
        log: logging.Logger,
        clock: Callable[[], float],
        typo_s: float = 0.5,
        missing_s: float = 5.0,
        handlers_s: float = 3.0,
        role: str = "",
        link_s: float = 3.0,
        on_its_way: Optional[Callable[[DataKey], bool]] = None,
    ) -> None:
        self.log, self.role, self.clock, self.on_its_way = log, role, clock, on_its_way
        self.typo_s, self.missing_s, self.handlers_s = typo_s, missing_s, handlers_s
        self.link_s = link_s
        self.last_missed: Dict[int, DataKey] = {}
        self._first_and_next_check: Dict[DataKey, List[float]] = {}
        self._reported: Set[DataKey] = set()
        # Keys read early that a handler waits for (the wiring checks may still report them).
        self._expected_reads: Set[DataKey] = set()
        self._lock = threading.Lock()  # loops read keys from their own threads
        #: Returns the keys the node's handlers are registered for (set by the node).
        self.expected_keys: Callable[[], Set[DataKey]] = set

    def missed(self, key: DataKey, stored_keys: Iterable[DataKey]) -> None:
        """Note a read of ``key`` that found nothing; maybe log a hint."""
        readers = self.last_missed
        if len(readers) >= self.MAX_READERS:
            readers.clear()  # the live threads are back at once
        readers[threading.get_ident()] = key
        if key in self._reported or key in self._expected_reads:
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
            if key in self.expected_keys():  # its pages are planned, not misspelt
                self._expected_reads.add(key)
                del self._first_and_next_check[key]
                return
            stored = _str_keys(stored_keys)
            guess = closest_match(key, stored) if isinstance(key, str) else None
            if guess is None and waited_s < self.missing_s:
                return
            if self.on_its_way is not None and self.on_its_way(key):
                times[1] = now + self.CHECK_EVERY_S
                return
            self._reported.add(key)
            del self._first_and_next_check[key]
        where = caller_location()
        shown = ", ".join(repr(k) for k in stored[:20]) or "none yet"
        footer = (
            "get_data/get_page return None until something stores the key. (This hint "
            "shows once per key, in DEBUG mode only.)"
        )
        if guess is not None:
            self.log.warning(
                f"Nothing is stored under data key {key!r} (read at {where}). Did you mean "
                f"{guess!r}? Stored keys: {shown}. {footer}"
            )
        else:
            self.log.info(
                f"Data key {key!r} has been read for {waited_s:.1f} s (at {where}) but nothing "
                f"has stored it. Stored keys: {shown}. If a component should store it, check "
                f"that it runs and spells the key the same way. {footer}"
            )

    def check_handlers(
        self, handled: Iterable[Tuple[DataKey, TaskHandler]], stored_keys: Iterable[DataKey]
    ) -> None:
        """Warn, once per key, about a handler for a key not stored while a close one was.

        A key with no close match stays quiet (its pages may come later); the
        keys of comms components (``checks_keys_per_link``) are `check_link`'s.

        Example::

            hints.check_handlers([("X", doubler.double)], ["x"])
            # Doubler.double (robot.py:9) handles pages under 'X', but nothing stored 'X' ...
        """
        stored = _str_keys(stored_keys)
        for key, handler in handled:
            if key in stored or key in self._reported or not isinstance(key, str):
                continue
            if getattr(getattr(handler, "__self__", None), "checks_keys_per_link", False):
                continue
            guess = closest_key(key, stored)
            if guess is None:
                continue
            self._reported.add(key)
            page = stored_keys.get(guess) if isinstance(stored_keys, Mapping) else None
            origin = getattr(page, "origin", None)
            came = f" (it came from node {origin!r})" if origin and origin != self.role else ""
            self.log.warning(
                f"{_describe_handler(handler)} handles pages under {key!r}, but nothing stored "
                f"{key!r} in the first {self.handlers_s:.1f} s, while {guess!r} was stored"
                f"{came}. Did you mean {guess!r}? Data keys must match exactly (capitals too). "
                f"{_SILENCE}"
            )

    def check_link(
        self,
        comms: str,
        peer: str,
        forwarded: Iterable[DataKey],
        handled: Iterable[Tuple[DataKey, TaskHandler]],
        stored_keys: Iterable[DataKey],
        received_keys: Iterable[DataKey],
    ) -> None:
        """Warn, once per key, about keys that should cross a link but have not.

        A comms component calls it ``link_s`` after a link came up: a key it
        forwards that nothing here stored, and a key a handler here waits for
        that nothing here stores and none arrived. With a close match it is a
        warning with "Did you mean", else info.

        ``forwarded``: the keys the comms component sends; ``handled``: ``(key,
        handler)`` for the other handlers of page keys; ``received_keys``: the
        keys of pages that arrived from ``peer``.

        Example::

            hints.check_link("'sockets_server_9001'", "node 'urov' at 127.0.0.1:9001", [],
                             [("sensor_data", show)], datastore, {"sensr_data"})
            # SensorDisplay.show (topside.py:20) handles pages under 'sensor_data', but ...
        """
        stored, received = _str_keys(stored_keys), sorted(_str_keys(received_keys))
        for key in forwarded:
            if self._is_news(key, stored):
                guess = closest_key(key, stored)
                say = self.log.warning if guess is not None else self.log.info
                say(
                    f"Comms component {comms} forwards pages under {key!r} to {peer}, but "
                    f"nothing on this node has stored {key!r} in the {self.link_s:.1f} s since "
                    f"that link came up, so none was sent.{suggestion(guess)} Stored keys: "
                    f"{_shown(stored)}. A comms component sends what is stored on its own node "
                    f"under exactly the keys it lists. {_SILENCE}"
                )
        for key, handler in handled:
            if self._is_news(key, stored):
                guess = closest_key(key, received) or closest_key(key, stored)
                say = self.log.warning if guess is not None else self.log.info
                say(
                    f"{_describe_handler(handler)} handles pages under {key!r}, but nothing on "
                    f"this node stores {key!r} and none has arrived from {peer} in the "
                    f"{self.link_s:.1f} s since it linked.{suggestion(guess)} Keys received "
                    f"from it: {_shown(received)}. A page crosses only if the other node stores "
                    f"it and its comms component lists exactly that key (e.g. "
                    f"sockets.client([{key!r}])). {_SILENCE}"
                )

    def _is_news(self, key: DataKey, stored: List[str]) -> bool:
        """True (and remembered) for a key not stored and not reported yet."""
        if key in stored or key in self._reported or not isinstance(key, str):
            return False
        self._reported.add(key)
        return True


_SILENCE = (
    "(This hint shows once per key, in DEBUG mode only; node.key_hints = None turns "
    "such hints off.)"
)


def _str_keys(keys: Iterable[DataKey]) -> List[str]:
    return [k for k in list(keys) if isinstance(k, str)]


def _describe_handler(handler: TaskHandler) -> str:
    """The student's handler with its file and line; one of SNR's components by its name."""
    owner = getattr(handler, "__self__", None)
    name = getattr(owner, "name", None)
    if isinstance(name, str) and is_snr(type(owner)):
        return f"{type(owner).__name__} {name!r}"
    return describe_callable(handler)


def _shown(keys: List[str]) -> str:
    """Up to 20 keys for a message."""
    more = f" and {len(keys) - 20} more" if len(keys) > 20 else ""
    return (", ".join(repr(k) for k in keys[:20]) or "none") + more
