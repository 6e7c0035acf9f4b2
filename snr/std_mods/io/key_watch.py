"""`KeyWatches`: the console's ``echo KEY`` and ``hz KEY``, like ``ros2 topic echo/hz``.

While a console watches a key, the command processor registers a handler
for ``(store_page, KEY)``; it sees each page right after the node core has
stored it, on the node's thread, and costs the node nothing once the watch
ends (the handler is removed). A timer schedules a *tick* task every
`TICK_S` while any watch is open, so a watch ends on time even when no page
comes.

What each command replies, and when, is in its help (``COMMANDS`` in
``command_table.py``). Pages that come between two ``echo KEY`` of the same
console (within `ECHO_KEEP_S`) wait for the next one, up to `ECHO_MAX_PAGES`;
more are counted and the reply says how many were skipped. ``hz`` keeps
constant memory however fast the key is.

Example::

    127.0.0.1:9123> hz depth 2
    depth: 10.0 Hz over 2.0 s (20 pages); period mean 100.0 ms, min 98.7 ms, ...
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Deque, Dict, List, Optional, Tuple

from snr.core.checks.error_text import did_you_mean
from snr.core.checks.step_mode import console_priority
from snr.core.component import Component
from snr.prelude import DataKey, Page, SomeTasks, Task, TaskId, TaskType
from snr.std_mods.io.console_protocol import ConsoleSession, Reply, Status

__all__ = [
    "ECHO_BATCH_S",
    "ECHO_DEFAULT_PAGES",
    "ECHO_KEEP_S",
    "ECHO_MAX_PAGES",
    "ECHO_WAIT_S",
    "HZ_DEFAULT_WINDOW_S",
    "HZ_MAX_WINDOW_S",
    "MAX_WATCHES",
    "TICK_S",
    "KeyWatches",
    "WatchRefused",
]

ECHO_DEFAULT_PAGES = 20
"""Pages one ``echo KEY`` reply carries at most, unless it asks for another number."""

ECHO_MAX_PAGES = 100
"""The most pages one ``echo`` reply carries, and waits between two ``echo`` of a console."""

ECHO_BATCH_S = 0.25
"""An ``echo`` reply goes out this long after its first page (or when it is full)."""

ECHO_WAIT_S = 1.0
"""An ``echo`` reply with no page goes out after this long, saying so."""

ECHO_KEEP_S = 2.0
"""A console's echo of a key is dropped when it asks for no more pages for this long."""

HZ_DEFAULT_WINDOW_S = 2.0
"""How long ``hz KEY`` counts pages when no window is given."""

HZ_MAX_WINDOW_S = 60.0
"""The longest window ``hz`` accepts (a reply waits that long)."""

MAX_WATCHES = 32
"""How many ``echo``/``hz`` may be open on one node at once; more are refused."""

TICK_S = 0.05
"""How often an open watch checks its time limits (so a reply is at most this late)."""


class WatchRefused(Exception):
    """A watch cannot start (too many open); the message is the console's reply.

    Example::

        try:
            watches.hz("depth", 2.0, session)
        except WatchRefused as refused:
            print(refused)   # Too many echo and hz at once on this node (32); ...
    """


@dataclass
class _Echo:
    key: DataKey
    console: str
    pages: Deque[Tuple[Page, float]] = field(default_factory=lambda: deque(maxlen=ECHO_MAX_PAGES))
    skipped: int = 0
    session: Optional[ConsoleSession] = None  # of the request waiting for pages
    wanted: int = ECHO_DEFAULT_PAGES
    asked_at: float = 0.0
    first_at: Optional[float] = None
    idle_since: float = 0.0


@dataclass
class _Rate:
    key: DataKey
    session: ConsoleSession
    window_s: float
    ends_at: float
    count: int = 0
    last_at: Optional[float] = None
    periods: int = 0
    mean: float = 0.0
    m2: float = 0.0  # Welford's running sum of squared differences
    low: float = math.inf
    high: float = 0.0

    def add(self, now: float) -> None:
        self.count += 1
        if self.last_at is not None:
            period = now - self.last_at
            self.periods += 1
            delta = period - self.mean
            self.mean += delta / self.periods
            self.m2 += delta * (period - self.mean)
            self.low, self.high = min(self.low, period), max(self.high, period)
        self.last_at = now


class KeyWatches:
    """The open ``echo`` and ``hz`` watches of one command processor.

    All methods run on the node's thread (in the processor's handlers),
    except the timer, which only schedules a tick task.

    Example::

        watches = KeyWatches(processor, "console_tick:console", preview=repr)
        watches.hz("depth", 2.0, session)    # the reply goes to session in 2 s
    """

    def __init__(
        self, owner: Component, tick_name: str, preview: Callable[[Any], str] = repr
    ) -> None:
        self.owner = owner
        self.tick_name = tick_name
        self.preview = preview
        #: The time limits (module constants); a test may shorten them.
        self.echo_batch_s, self.echo_wait_s, self.echo_keep_s = (
            ECHO_BATCH_S,
            ECHO_WAIT_S,
            ECHO_KEEP_S,
        )
        self._echoes: Dict[Tuple[str, DataKey], _Echo] = {}
        self._rates: List[_Rate] = []
        self._timer: Optional[threading.Timer] = None
        self._closed = False

    # -- commands ----------------------------------------------------------------
    def echo(self, key: DataKey, wanted: int, session: ConsoleSession) -> Optional[Reply]:
        """Start (or continue) this console's echo of ``key``; a reply now, or None (later)."""
        console = str(session)
        echo = self._echoes.get((console, key))
        if echo is None:
            self._check_room()
            echo = self._echoes[(console, key)] = _Echo(key, console)
            self.owner.task_handlers[(TaskType.store_page, key)] = self.on_page
        elif echo.session is not None:  # a second request while one waits: answer that one
            self._answer_echo(echo)
        now = time.perf_counter()
        echo.session, echo.wanted, echo.asked_at = session, wanted, now
        echo.first_at = now if echo.pages else None
        if len(echo.pages) >= wanted:
            return self._echo_reply(echo)
        self._arm()
        return None

    def hz(self, key: DataKey, window_s: float, session: ConsoleSession) -> None:
        """Count the pages of ``key`` for ``window_s``; the reply goes to ``session`` then."""
        self._check_room()
        self._rates.append(_Rate(key, session, window_s, time.perf_counter() + window_s))
        self.owner.task_handlers[(TaskType.store_page, key)] = self.on_page
        self._arm()

    def _check_room(self) -> None:
        if len(self._echoes) + len(self._rates) >= MAX_WATCHES:
            raise WatchRefused(
                f"Too many echo and hz at once on this node ({MAX_WATCHES}); wait for one "
                "to finish, or stop an echo with Ctrl-C."
            )

    # -- handlers (node thread) ----------------------------------------------------
    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        """A page of a watched key was stored: note it for every watch of that key."""
        page = task.page()
        if page is None:
            return None
        now = time.perf_counter()
        for rate in self._rates:
            if rate.key == page.key:
                rate.add(now)
        for echo in list(self._echoes.values()):
            if echo.key != page.key:
                continue
            if len(echo.pages) == echo.pages.maxlen:
                echo.skipped += 1  # the oldest page falls out of the deque
            echo.pages.append((page, time.time() - page.created_at_s))
            if echo.session is not None:
                if echo.first_at is None:
                    echo.first_at = now
                if len(echo.pages) >= echo.wanted:
                    self._answer_echo(echo)
        return None

    def on_tick(self, task: Task, key: TaskId) -> SomeTasks:
        """Send the replies that are due; forget echoes nobody asks for any more."""
        self._timer = None
        now = time.perf_counter()
        for rate in [r for r in self._rates if now >= r.ends_at]:
            self._rates.remove(rate)
            self._unwatch(rate.key)
            rate.session.send(Reply(Status.OK, self._rate_text(rate)))
        for echo in list(self._echoes.values()):
            if echo.session is not None:
                batch_due = echo.first_at is not None and now - echo.first_at >= self.echo_batch_s
                if batch_due or now - echo.asked_at >= self.echo_wait_s:
                    self._answer_echo(echo)
            elif now - echo.idle_since >= self.echo_keep_s:
                del self._echoes[(echo.console, echo.key)]
                self._unwatch(echo.key)
        if self._echoes or self._rates:
            self._arm()
        return None

    def close(self) -> None:
        """Stop the timer (the node is stopping); open watches get no reply."""
        self._closed = True
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    # -- helpers ---------------------------------------------------------------------
    def _unwatch(self, key: DataKey) -> None:
        """Stop seeing the pages of ``key`` once no watch of it is left."""
        keys = [rate.key for rate in self._rates] + [echo.key for echo in self._echoes.values()]
        if key not in keys:
            self.owner.task_handlers.pop((TaskType.store_page, key), None)

    def _arm(self) -> None:
        if self._timer is None and not self._closed:
            self._timer = threading.Timer(TICK_S, self._tick)
            self._timer.daemon = True
            self._timer.start()

    def _tick(self) -> None:
        """The timer's task; urgent while the node is paused, as the console's commands."""
        priority = console_priority(self.owner.parent)
        self.owner.schedule(Task(TaskType.event, self.tick_name, priority=priority))

    def _answer_echo(self, echo: _Echo) -> None:
        session = echo.session
        if session is not None:  # always, as the callers check first
            session.send(self._echo_reply(echo))

    def _echo_reply(self, echo: _Echo) -> Reply:
        echo.session, echo.first_at = None, None
        echo.idle_since = time.perf_counter()
        lines = []
        if echo.skipped:
            lines.append(
                f"... {echo.skipped} pages of {echo.key!r} not shown: they came faster than "
                "this console asked for them."
            )
            echo.skipped = 0
        for _ in range(min(echo.wanted, len(echo.pages))):
            page, age_s = echo.pages.popleft()
            lines.append(
                f"{page.key} = {self.preview(page.data)}  "
                f"(from {page.origin!r}, {max(0.0, age_s) * 1000:.0f} ms old)"
            )
        if not lines:
            lines.append(
                f"No page under {echo.key!r} in the last {self.echo_wait_s:g} s."
                f"{self._hint(echo.key)}"
            )
        return Reply(Status.OK, "\n".join(lines))

    def _rate_text(self, rate: _Rate) -> str:
        head = f"{rate.key}: "
        if rate.count == 0:
            return f"{head}no page in {rate.window_s:g} s.{self._hint(rate.key)}"
        if rate.periods == 0:
            return f"{head}1 page in {rate.window_s:g} s: too few to measure a period."
        std = math.sqrt(rate.m2 / rate.periods)
        return (
            f"{head}{1.0 / rate.mean:.3g} Hz over {rate.window_s:g} s ({rate.count} pages); "
            f"period mean {_ms(rate.mean)}, min {_ms(rate.low)}, max {_ms(rate.high)}, "
            f"std {_ms(std)} (jitter)"
        )

    def _hint(self, key: DataKey) -> str:
        datastore = getattr(self.owner.parent, "datastore", {})
        if key in datastore:
            return ""
        maybe = did_you_mean(key, datastore) if isinstance(key, str) else ""
        return (
            f" The node has no data under {key!r} yet.{maybe} `dump datastore` lists the "
            "keys; `graph` shows who stores what."
        )


def _ms(seconds: float) -> str:
    return f"{seconds * 1000:.1f} ms"
