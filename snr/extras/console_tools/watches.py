"""The console's ``echo KEY`` and ``hz KEY``, like ``ros2 topic echo`` and ``ros2 topic hz``.

The kernel's console loads this module through the entry point group
``snr.console_commands`` when a console starts (`load_extra_commands`), and
the module registers its commands with `command`, as the kernel registers
its own: a student sees them in ``help`` like any other (docs/console.md).

While a console watches a key, its command processor handles ``(store_page,
KEY)``: it sees each page right after the node core stored it, and the
handler is removed when the watch ends, so a node nobody watches pays
nothing.

Example::

    $ snr-console -c "hz depth 2"
    depth: 10 Hz over 2 s (21 pages); period mean 100.0 ms, min 97.1 ms, max 103.2 ms, ...
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Deque, Dict, List, Optional, Tuple

from snr.core.checks.error_text import did_you_mean
from snr.core.checks.step_mode import console_priority
from snr.prelude import DataKey, Page, SomeTasks, Task, TaskId, TaskType
from snr.std_mods.io.command_processor import (
    COMMANDS,
    Answer,
    CommandFailed,
    CommandProcessorEndpoint,
    command,
    number_argument,
    preview,
)
from snr.std_mods.io.console_protocol import ConsoleSession, Reply, Status

__all__ = [
    "ECHO_DEFAULT_PAGES",
    "ECHO_MAX_PAGES",
    "HZ_DEFAULT_WINDOW_S",
    "HZ_MAX_WINDOW_S",
    "MAX_WATCHES",
    "KeyWatches",
    "watches_of",
]

ECHO_DEFAULT_PAGES = 20
"""Pages one ``echo KEY`` reply carries at most, unless it asks for another number."""

ECHO_MAX_PAGES = 100
"""The most pages one ``echo`` reply carries, and waits between two ``echo`` of a console."""

HZ_DEFAULT_WINDOW_S = 2.0
"""How long ``hz KEY`` counts pages when no window is given (``snr-console`` waits as long)."""

HZ_MAX_WINDOW_S = 60.0
"""The longest window ``hz`` accepts (a reply waits that long)."""

MAX_WATCHES = 32
"""How many ``echo``/``hz`` may be open on one node at once; more are refused."""

_TICK_S = 0.05  # how often open watches check their time limits (a reply is at most this late)


@command(
    "echo KEY [N]",
    "Show the next pages stored under KEY (snr-console repeats it until Ctrl-C).",
    f"One reply carries at most N pages (default {ECHO_DEFAULT_PAGES}, at most "
    f"{ECHO_MAX_PAGES}): it comes\nwhen N pages have come, a quarter second after the "
    "first, or after 1 s\nwithout one. Pages that come between two `echo KEY` wait "
    "for the next one,\nso repeating it shows every page.",
)
def _echo(p: CommandProcessorEndpoint, args: str) -> Answer:
    """``echo KEY [N]``: the next pages of KEY (the reply waits for them)."""
    words = args.split()
    if not 1 <= len(words) <= 2:
        raise CommandFailed(f"Usage: {COMMANDS['echo'].usage}, e.g. `echo depth`.")
    wanted = ECHO_DEFAULT_PAGES
    if len(words) == 2:
        wanted = int(number_argument(words[1], "echo", "N", 1, ECHO_MAX_PAGES, int))
    return watches_of(p).echo(words[0], wanted, _console(p))


def _hz_window_s(words: List[str]) -> float:
    """``hz``'s window from the words after its name; CommandFailed says what is wrong."""
    if not 1 <= len(words) <= 2:
        raise CommandFailed(f"Usage: {COMMANDS['hz'].usage}, e.g. `hz depth 2`.")
    if len(words) == 1:
        return HZ_DEFAULT_WINDOW_S
    return number_argument(words[1], "hz", "WINDOW_S", 0.1, HZ_MAX_WINDOW_S, float)


def _hz_reply_after_s(words: List[str]) -> float:
    """How long ``hz``'s reply takes: its window (0 if the node refuses the words at once)."""
    try:
        return _hz_window_s(words)
    except CommandFailed:
        return 0.0


@command(
    "hz KEY [WINDOW_S]",
    "Measure how often KEY is stored, and the jitter of the time between pages.",
    f"Counts pages for WINDOW_S seconds (default {HZ_DEFAULT_WINDOW_S:g}, at most "
    f"{HZ_MAX_WINDOW_S:g}), then replies with\nthe rate and the period's mean, min, max "
    "and standard deviation, timed when\nthis node stores each page.",
    reply_after_s=_hz_reply_after_s,
)
def _hz(p: CommandProcessorEndpoint, args: str) -> Answer:
    """``hz KEY [WINDOW_S]``: the rate and jitter of KEY (the reply comes after the window)."""
    words = args.split()
    window_s = _hz_window_s(words)  # first: it says what is wrong with the words
    watches_of(p).hz(words[0], window_s, _console(p))
    return None


def _console(p: CommandProcessorEndpoint) -> ConsoleSession:
    """The session of the command being run, for a reply that comes later."""
    if p.session is None:
        raise CommandFailed(
            "`echo` and `hz` reply once pages have come, so they need a console to reply to: "
            "type them in snr-console or a LocalConsoleFactory console."
        )
    return p.session


def watches_of(processor: CommandProcessorEndpoint) -> KeyWatches:
    """The open ``echo`` and ``hz`` watches of ``processor`` (made on first use).

    Example::

        watches_of(processor).echo_wait_s = 0.05   # a quicker "no page" reply, in a test
    """
    watches = processor.state.get("watches")
    if not isinstance(watches, KeyWatches):
        watches = processor.state["watches"] = KeyWatches(processor)
    return watches


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

    While any watch is open a timer schedules a tick task every 50 ms, so a
    watch ends on time even when no page comes. Pages that come between two
    ``echo KEY`` of one console (within 2 s) wait for the next one, up to
    `ECHO_MAX_PAGES`; more are counted, and the reply says how many were
    skipped. ``hz`` keeps constant memory however fast the key is. All of it
    runs on the node's thread, but the timer, which only schedules the tick.

    Example::

        watches_of(processor).hz("depth", 2.0, session)   # the reply goes to session in 2 s
    """

    def __init__(self, owner: CommandProcessorEndpoint) -> None:
        self.owner = owner
        self.tick_name = f"{owner.task_name}:tick"
        owner.task_handlers[(TaskType.event, self.tick_name)] = self.on_tick
        #: When an echo reply goes out: this long after its first page, or with no
        #: page after echo_wait_s; a console's echo is dropped after echo_keep_s unasked.
        self.echo_batch_s, self.echo_wait_s, self.echo_keep_s = 0.25, 1.0, 2.0
        self._echoes: Dict[Tuple[str, DataKey], _Echo] = {}
        self._rates: List[_Rate] = []
        self._timer: Optional[threading.Timer] = None
        self._closed = False

    def echo(self, key: DataKey, wanted: int, session: ConsoleSession) -> Optional[Reply]:
        """Start (or continue) this console's echo of ``key``; a reply now, or None (later)."""
        console = str(session)
        echo = self._echoes.get((console, key))
        if echo is None:
            self._check_room()
            echo = self._echoes[(console, key)] = _Echo(key, console)
            self.owner.task_handlers[(TaskType.store_page, key)] = self.on_page
        elif echo.session is not None:  # a second request while one waits: answer that one
            echo.session.send(self._echo_reply(echo))
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
            raise CommandFailed(
                f"Too many echo and hz at once on this node ({MAX_WATCHES}); wait for one "
                "to finish, or stop an echo with Ctrl-C."
            )

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
                    echo.session.send(self._echo_reply(echo))
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
                    echo.session.send(self._echo_reply(echo))
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

    def _unwatch(self, key: DataKey) -> None:
        """Stop seeing the pages of ``key`` once no watch of it is left."""
        keys = [rate.key for rate in self._rates] + [echo.key for echo in self._echoes.values()]
        if key not in keys:
            self.owner.task_handlers.pop((TaskType.store_page, key), None)

    def _arm(self) -> None:
        if self._timer is None and not self._closed:
            self._timer = threading.Timer(_TICK_S, self._tick)
            self._timer.daemon = True
            self._timer.start()

    def _tick(self) -> None:
        """The timer's task; urgent while the node is paused, as the console's commands."""
        priority = console_priority(self.owner.parent)
        self.owner.schedule(Task(TaskType.event, self.tick_name, priority=priority))

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
                f"{page.key} = {preview(page.data)}  "
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
