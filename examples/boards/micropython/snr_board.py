"""SNR pages over a serial port, for a MicroPython board (Pico, ESP32...).

Copy this file to the board. It speaks the board protocol of SNR's serial
link (``docs/serial.md``): it prints the ready line once set up, sends a
heartbeat every 200 ms, hands each page from the computer to ``on_page``,
and calls ``on_failsafe`` (stop the motors!) when no page line, command or
heartbeat, came for 1000 ms; while it hears nothing, it repeats the ready
line every 1000 ms, so a computer that opens the port without resetting the
board (a GPIO UART) hears it too. It runs under CPython too, which is how SNR's
tests run it.

Example (``main.py`` on a Pico wired to the Pi's GPIO UART)::

    from machine import UART
    from snr_board import SnrBoard

    def on_page(key, data):
        if key == "motor":
            set_motors(data)          # your code

    board = SnrBoard(UART(0, 115200), on_page, on_failsafe=stop_motors)
    board.begin()
    while True:
        board.poll()                  # often: every few milliseconds
        board.send("depth_m", read_depth())
"""

import json
import time

try:
    from typing import Any, Callable, List, Optional
except ImportError:  # MicroPython: annotations are not evaluated there
    pass

READY_LINE = '{"format":"snr-pages","version":1}'
"""Printed once the board is set up; the computer writes nothing before it."""

HEARTBEAT_KEY = "hb"
"""The key of heartbeat pages: ``{"key":"hb","data":<count>}``."""

HEARTBEAT_MS = 200
"""How often the board sends a heartbeat."""

FAILSAFE_MS = 1000
"""With no page line for this long, the board calls ``on_failsafe``."""

MAX_LINE_BYTES = 128
"""A longer line is skipped (up to its newline) and counted in ``bad_lines``."""


def _clock_functions() -> "List[Any]":
    """``[ticks_ms, ticks_add, ticks_diff]``: MicroPython's, or made from CPython's clock."""
    found = [getattr(time, name, None) for name in ("ticks_ms", "ticks_add", "ticks_diff")]
    if None not in found:
        return found  # their values wrap around: only ticks_add and ticks_diff do sums

    def cpython_ticks_ms() -> int:
        return int(time.monotonic() * 1000)

    def cpython_ticks_add(ticks: int, delta: int) -> int:
        return ticks + delta

    def cpython_ticks_diff(later: int, earlier: int) -> int:
        return later - earlier

    return [cpython_ticks_ms, cpython_ticks_add, cpython_ticks_diff]


ticks_ms, ticks_add, ticks_diff = _clock_functions()


class SnrBoard:
    """The board's end of an SNR serial link.

    Args:
        port: the serial port: a ``machine.UART``, or anything with
            ``any()`` (bytes waiting), ``read(n)`` and ``write(data)``.
        on_page: called as ``on_page(key, data)`` for each page received.
        on_failsafe: called with no arguments when the computer went quiet
            for ``FAILSAFE_MS``, and once in ``begin()``: stop the actuators.
        clock_ms: the clock (``ticks_ms``); tests pass their own.
        failsafe_ms: the failsafe time; keep `FAILSAFE_MS` unless the
            computer's link is set to match.
        heartbeat_ms: how often to send a heartbeat.

    Example::

        board = SnrBoard(UART(0, 115200), on_page, on_failsafe=stop_motors)
        board.begin()
        while True:
            board.poll()

    Attributes:
        failsafe_active: True from a failsafe until the next page line.
        failsafes: how many times the failsafe fired (not counting ``begin``).
        pages_received: pages handed to ``on_page`` (heartbeats are not).
        bad_lines: lines that were not pages, or too long.
    """

    def __init__(
        self,
        port: "Any",
        on_page: "Callable[[str, Any], None]",
        on_failsafe: "Callable[[], None]",
        clock_ms: "Optional[Callable[[], int]]" = None,
        failsafe_ms: int = FAILSAFE_MS,
        heartbeat_ms: int = HEARTBEAT_MS,
    ) -> None:
        self.port = port
        self.on_page = on_page
        self.on_failsafe = on_failsafe
        self.clock_ms = clock_ms or ticks_ms
        self.failsafe_ms = failsafe_ms
        self.heartbeat_ms = heartbeat_ms
        self.failsafe_active = True
        self.failsafes = 0
        self.pages_received = 0
        self.bad_lines = 0
        self.heartbeats_sent = 0
        self._buffer = b""
        self._skipping = False  # inside a line that was too long
        self._heard_ms = 0
        self._next_heartbeat_ms = 0
        self._next_ready_ms = 0

    def begin(self) -> None:
        """Stop the actuators, then print the ready line: call it at the end of setting up."""
        self.on_failsafe()
        self.failsafe_active = True
        now = self.clock_ms()
        self._heard_ms = now
        self._next_heartbeat_ms = now
        self._next_ready_ms = ticks_add(now, self.failsafe_ms)
        self._write_line(READY_LINE)

    def poll(self) -> None:
        """Read what came, handle whole lines, send a heartbeat when due, check the failsafe."""
        waiting = self.port.any()
        if waiting:
            chunk = self.port.read(waiting)
            if chunk:
                self._take(chunk)
        now = self.clock_ms()
        if not self.failsafe_active and ticks_diff(now, self._heard_ms) >= self.failsafe_ms:
            self.failsafe_active = True
            self.failsafes += 1
            self.on_failsafe()
            self._next_ready_ms = now
        if self.failsafe_active and ticks_diff(now, self._next_ready_ms) >= 0:
            self._write_line(READY_LINE)  # "I am here, and nobody talks to me"
            self._next_ready_ms = ticks_add(now, self.failsafe_ms)
        if ticks_diff(now, self._next_heartbeat_ms) >= 0:
            self._write_line('{"key":"hb","data":' + str(self.heartbeats_sent) + "}")
            self.heartbeats_sent += 1
            self._next_heartbeat_ms = ticks_add(now, self.heartbeat_ms)

    def send(self, key: str, data: "Any") -> None:
        """Send one page, e.g. ``send("depth_m", 2.41)``: keep it short (see docs/serial.md)."""
        self._write_line('{"key":' + json.dumps(key) + ',"data":' + json.dumps(data) + "}")

    def _write_line(self, line: str) -> None:
        self.port.write((line + "\n").encode())

    def _take(self, chunk: bytes) -> None:
        self._buffer += chunk
        while True:
            end = self._buffer.find(b"\n")
            if end < 0:
                break
            line, self._buffer = self._buffer[:end], self._buffer[end + 1 :]
            if self._skipping:  # the end of a line that was too long
                self._skipping = False
            elif len(line) > MAX_LINE_BYTES:
                self.bad_lines += 1
            else:
                self._handle_line(line)
        if len(self._buffer) > MAX_LINE_BYTES:
            self.bad_lines += 1
            self._buffer = b""
            self._skipping = True

    def _handle_line(self, line: bytes) -> None:
        try:
            fields = json.loads(line.decode())
        except ValueError:  # noise, a cut line, a wrong baud rate (UnicodeError is one)
            self.bad_lines += 1
            return
        if not isinstance(fields, dict) or "key" not in fields or "data" not in fields:
            if not (isinstance(fields, dict) and "format" in fields):  # the header is fine
                self.bad_lines += 1
            return
        self._heard_ms = self.clock_ms()
        self.failsafe_active = False  # the actuators wait for the next command
        key = fields["key"]
        if key == HEARTBEAT_KEY:
            return
        self.pages_received += 1
        self.on_page(key, fields["data"])


def demo() -> None:
    """On a Pico: echo each page back as ``<key>_echo`` and blink when the failsafe fires.

    Example (``main.py`` on the board)::

        from snr_board import demo
        demo()
    """
    import machine  # type: ignore[import-not-found]  # MicroPython only

    led = machine.Pin("LED", machine.Pin.OUT)
    board = SnrBoard(
        machine.UART(0, 115200),
        on_page=lambda key, data: board.send(key + "_echo", data),
        on_failsafe=lambda: led.toggle(),
    )
    board.begin()
    while True:
        board.poll()
        time.sleep_ms(2)  # type: ignore[attr-defined]  # MicroPython's
