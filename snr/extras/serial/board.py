"""The board protocol of the serial link: a ready line, heartbeats and a failsafe.

A microcontroller on a serial link restarts when the port opens (an Arduino
Uno resets for 1-3 s, printing boot noise), and its motors must stop when
the computer stops talking to it. Three small rules handle both; the board
side of each is in ``examples/boards/`` (Arduino and MicroPython):

* **Ready line**: once set up, the board prints `READY_LINE` (SNR's header
  line). The link writes nothing before it and skips every line before it.
* **Heartbeat**: each end sends ``{"key":"hb","data":<n>}`` every
  `HEARTBEAT_S` (0.2 s), so a quiet link is told from a dead one.
* **Failsafe**: the board stops its actuators when no page line (a command
  or a heartbeat) came for `FAILSAFE_S` (1.0 s); the link logs a board that
  sent nothing for as long.

`BoardWatch` holds the computer's side of these rules as plain state driven
by a clock, so it can be tested without a board, a port or any waiting.
``docs/serial.md`` describes the protocol for people writing a board's code.
"""

from __future__ import annotations

from typing import List, Optional

from snr.prelude import ConfigError, Page
from snr.std_mods.codec import data_json, dump_json, header_line

__all__ = [
    "FAILSAFE_S",
    "HEARTBEAT_KEY",
    "HEARTBEAT_S",
    "READY_LINE",
    "READY_TIMEOUT_S",
    "UNO_RX_BUFFER_BYTES",
    "BoardWatch",
    "compact_line",
    "heartbeat_line",
    "is_heartbeat_line",
]

READY_LINE = header_line()
"""What a board prints once it is ready: ``{"format":"snr-pages","version":1}``."""

HEARTBEAT_KEY = "hb"
"""The key of heartbeat pages; the link neither stores nor forwards them."""

HEARTBEAT_S = 0.2
"""How often each end sends a heartbeat: five times a second."""

FAILSAFE_S = 1.0
"""After this long with no page line from the other end, the board stops its actuators."""

READY_TIMEOUT_S = 5.0
"""How long to wait for the ready line: an Uno's reset takes 1-3 s."""

UNO_RX_BUFFER_BYTES = 64
"""An Arduino Uno's serial receive buffer: keep lines to it shorter than this."""

_READY_BYTES = READY_LINE.encode("ascii")
_HEARTBEAT_START = f'{{"key":"{HEARTBEAT_KEY}",'


def heartbeat_line(count: int) -> str:
    """The heartbeat line number ``count`` (without its newline).

    Example::

        heartbeat_line(7)   # '{"key":"hb","data":7}'
    """
    return f'{{"key":"{HEARTBEAT_KEY}","data":{int(count)}}}'


def is_heartbeat_line(text: str) -> bool:
    """True for a heartbeat line in the compact form the board helpers send.

    Example::

        is_heartbeat_line('{"key":"hb","data":3}')   # True
    """
    return text.startswith(_HEARTBEAT_START)


_TO_BOARD = "to a serial link"


def compact_line(page: Page) -> str:
    """``page`` as a page line with only its key and data: short enough for an Uno.

    The reader fills in the origin and the time, as for any board's line.

    Raises:
        NotSerializableError: the data is not JSON.

    Example::

        compact_line(Page("motor", [50, -50, 0], "pi", 0.0))
        # '{"key":"motor","data":[50,-50,0]}'
    """
    key = dump_json({"key": page.key}, f"the key {page.key!r:.40}")[:-1]  # b'{"key":"motor"'
    return (key + b',"data":' + data_json(page.key, page.data, to=_TO_BOARD) + b"}").decode("ascii")


class BoardWatch:
    """The computer's side of the board protocol, driven by the caller's clock.

    Call `opened` when the port opens, `line` for each line read (it says
    whether to use the line) and `tick` often; each returns what happened,
    for the caller to log. Times are ``time.monotonic()`` seconds.

    Args:
        ready_timeout_s: wait this long for `READY_LINE` after each opening
            (None: the board is ready at once).
        heartbeat_s: ask for a heartbeat this often (None: no heartbeats).
        answer_timeout_s: report a board that sent no line for this long
            (None: never).

    Example::

        watch = BoardWatch(ready_timeout_s=5.0, heartbeat_s=0.2, answer_timeout_s=1.0)
        watch.opened(now_s=0.0)
        watch.line(b"Booting", now_s=0.5)                                # 'boot'
        watch.line(b'{"format":"snr-pages","version":1}', now_s=1.5)     # 'ready'
        watch.tick(now_s=1.7)                                            # ['heartbeat']
        watch.tick(now_s=3.0)                                            # ['silent', ...]
    """

    def __init__(
        self,
        ready_timeout_s: Optional[float] = None,
        heartbeat_s: Optional[float] = None,
        answer_timeout_s: Optional[float] = None,
    ) -> None:
        for name, value in (
            ("ready_timeout_s", ready_timeout_s),
            ("heartbeat_s", heartbeat_s),
            ("answer_timeout_s", answer_timeout_s),
        ):
            if value is not None and not (isinstance(value, (int, float)) and value > 0):
                raise ConfigError(
                    f"{name}={value!r}; give a positive number of seconds, or None to turn it off."
                )
        self.ready_timeout_s = ready_timeout_s
        self.heartbeat_s = heartbeat_s
        self.answer_timeout_s = answer_timeout_s
        self.ready = ready_timeout_s is None
        self.answering = True
        self.boot_lines = 0  # lines skipped before the ready line, since the last opening
        self.last_silence_s = 0.0  # how long the last silence lasted, once it ended
        self._gave_up = False  # the ready line did not come in time
        self._ready_by_s = 0.0
        self._heard_s = 0.0
        self._next_heartbeat_s = 0.0

    def opened(self, now_s: float) -> None:
        """The port was (re)opened: the board is starting again."""
        self.ready = self.ready_timeout_s is None
        self.answering = True
        self.boot_lines = 0
        self._gave_up = False
        self._ready_by_s = now_s + (self.ready_timeout_s or 0.0)
        self._heard_s = now_s
        self._next_heartbeat_s = now_s

    def line(self, raw: bytes, now_s: float) -> str:
        """What to do with a line read (without its newline).

        Returns ``"boot"`` (noise before the ready line: skip it),
        ``"ready"`` (the ready line itself: skip it, the board is ready),
        ``"ready-again"`` (the ready line from a board that was ready: it
        restarted; skip it), or ``"use"``; ``"use-again"`` is ``"use"`` from
        a board that had gone silent.
        """
        again = not self.answering
        if again:
            self.last_silence_s = now_s - self._heard_s
        self._heard_s = now_s
        self.answering = True
        # Boot noise may come just before it, with no line break between.
        is_ready_line = raw.rstrip(b"\r").endswith(_READY_BYTES)
        if not self.ready:
            if is_ready_line:
                self.ready = True
                return "ready"
            self.boot_lines += 1
            return "boot"
        if is_ready_line and self._gave_up:  # late, but welcome
            self._gave_up = False
            return "ready"
        if is_ready_line and self.ready_timeout_s is not None:
            return "ready-again"
        return "use-again" if again else "use"

    def tick(self, now_s: float) -> List[str]:
        """What is due now: ``"ready-timeout"``, ``"silent"``, ``"heartbeat"``.

        ``"ready-timeout"`` comes once per opening; from then on the board
        counts as ready (it may run code without the ready line).
        ``"silent"`` comes once per silence, after the board is ready.
        """
        due: List[str] = []
        if not self.ready:
            if now_s < self._ready_by_s:
                return due
            self.ready = self._gave_up = True
            self._heard_s = now_s
            due.append("ready-timeout")
        timeout = self.answer_timeout_s
        if timeout is not None and self.answering and now_s - self._heard_s >= timeout:
            self.answering = False
            due.append("silent")
        if self.heartbeat_s is not None and now_s >= self._next_heartbeat_s:
            # From now, not from the last due time: no burst after a stall.
            self._next_heartbeat_s = now_s + self.heartbeat_s
            due.append("heartbeat")
        return due

    def silent_for_s(self, now_s: float) -> float:
        """How long the board has sent nothing."""
        return now_s - self._heard_s
