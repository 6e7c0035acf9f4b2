"""`SerialLinkFactory`: exchange pages or text lines with a microcontroller.

The link opens a serial port (or any pyserial URL, such as ``loop://``) and
talks in lines, in one of two modes:

* ``"pages"``: the JSON-lines page format of recordings (see
  ``docs/recording.md``). Pages stored under ``send_keys`` are written one
  per line; every page line read is stored under its own key. A
  microcontroller may send as little as ``{"key":"temp_c","data":21.5}``.
  Lines that are not pages (e.g. debug prints) are stored as text under
  ``receive_key``.
* ``"lines"``: raw text. The data of pages under ``send_keys`` is written as
  a line (strings as they are, other values as JSON); every line read is
  stored as a string under ``receive_key``.

With ``ready_timeout_s``, ``heartbeat_s`` and ``answer_timeout_s`` the link
also follows the board protocol of `snr.extras.serial.board`: it
waits for the board's ready line after each opening, sends heartbeats, and
reports a board that stopped answering (whose own failsafe then stops its
motors).

pyserial is an optional dependency: ``pip install 'snr-robotics[serial]'``.
"""

from __future__ import annotations

import collections
import logging
import sys
import threading
import time
from typing import Any, List, Optional, Sequence

from snr.core import LoopFactory, ThreadLoop, tasks
from snr.core.checks.error_text import did_you_mean
from snr.core.logs import LossReport, RepeatFilter
from snr.extras.serial.board import (
    HEARTBEAT_KEY,
    BoardWatch,
    compact_line,
    heartbeat_line,
    is_heartbeat_line,
)
from snr.extras.serial.port import import_pyserial, open_serial_port
from snr.prelude import (
    AbstractNode,
    CommsError,
    ConfigError,
    DataKey,
    NotSerializableError,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    WireFormatError,
)
from snr.std_mods.codec import data_json, header_line, page_from_line, page_to_line
from snr.std_mods.comms import Outbox

__all__ = [
    "DEFAULT_OUTBOX_BYTES",
    "SERIAL_MODES",
    "SerialLinkFactory",
    "SerialLinkLoop",
]

SERIAL_MODES = ("pages", "lines")
"""The ways a serial link can talk: JSON page lines, or raw text lines."""

MAX_LINE_BYTES = 64 * 1024
"""A longer line is discarded: without a newline it is probably noise."""

DEFAULT_OUTBOX_BYTES = 8 * 1024
"""How many bytes of lines may wait for the device: about 0.7 s of a 115200 baud link."""

_ECHO_GUARD_SIZE = 10_000
_RECONNECT_MAX_S = 5.0
_FLUSH_S = 0.25  # after halt, how long lines already queued may still go out
_WRITER_WAKE_S = 0.1  # how often a writer holding lines for a starting board looks up


class SerialLinkLoop(ThreadLoop):
    """Reads lines from the port on its thread; a writer thread writes queued lines.

    The ``store_page`` handler only encodes the page and puts the line in a
    bounded `Outbox` (the one every link uses), so a device that stops
    reading never slows the node. When the outbox is full the newest line per
    key is kept and the drops are counted in ``dropped`` and logged at most
    once a second.

    If the device disappears (unplugged), the reading thread logs it and
    reopens the port with a growing pause (up to 5 s) until the node stops:
    that is the link's one reconnect; the writer only writes to whatever
    port is open.

    Example::

        SerialLinkFactory("/dev/ttyACM0", send_keys=["motor_speed"], mode="lines")

    Attributes:
        lines_received: lines read from the port.
        lines_sent: lines the device took.
        bad_lines: lines read that could not be used as pages.
        boot_lines: lines skipped before the board's ready line.
        heartbeats_received: heartbeat lines read (not stored).
        heartbeats_sent: heartbeat lines queued for the board.
    """

    def __init__(self, factory: SerialLinkFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.link = factory
        self.serial = import_pyserial()
        self.port: Any = None
        self.lines_received = 0
        self.lines_sent = 0
        self.bad_lines = 0
        self.boot_lines = 0
        self.heartbeats_received = 0
        self.heartbeats_sent = 0
        self._watch = BoardWatch(
            factory.ready_timeout_s, factory.heartbeat_s, factory.answer_timeout_s
        )
        self._ready = threading.Event()  # the writer writes only while it is set
        self._heartbeat_event = f"{factory.name}_heartbeat"
        self._buffer = bytearray()
        self._send_keys = set(factory.send_keys)
        self._received: collections.OrderedDict[int, Page] = collections.OrderedDict()
        self._writer: Optional[threading.Thread] = None
        self._flush_until = 0.0
        self._cut = False  # a write timed out, maybe part-way through a line
        self._write_failure_said = False
        self._loss = LossReport(
            self.log,
            f"lines for serial port {factory.port!r}",
            "the device is not reading them (or the port is being reopened); the newest "
            f"line per key is kept, up to {factory.outbox_bytes:,} bytes",
        )
        self._outbox = Outbox(factory.outbox_bytes, self._loss)
        self._repeats = RepeatFilter(self.log)
        self.task_handlers = {
            (TaskType.store_page, key): self.send_page for key in factory.send_keys
        }
        if factory.heartbeat_s is not None:
            # Queued by the node's thread, so a node that hangs stops the
            # heartbeats and the board's failsafe stops the motors.
            self.task_handlers[(TaskType.event, self._heartbeat_event)] = self.send_heartbeat

    @property
    def dropped(self) -> int:
        """Lines not sent: the outbox overflowed, a write timed out, or the port was closed.

        Example::

            link = node.components["serial_link"]
            print(link.dropped, "lines dropped,", link.lines_sent, "sent")
        """
        return self._loss.total

    # -- starting and stopping ------------------------------------------------
    def begin(self) -> None:
        """Open the port now (a wrong port name stops the node at start-up); start the writer."""
        self._outbox = Outbox(self.link.outbox_bytes, self._loss)
        if self.port is None:  # still open after a refused reload: reopening resets boards
            self._open()
        self._writer = threading.Thread(
            target=self._write_lines,
            name=f"snr-{self.parent.role}-{self.name}-w",
            daemon=True,
        )
        self._writer.start()

    def _open(self) -> None:
        link = self.link
        port = open_serial_port(
            link.port, link.baudrate, link.read_timeout_s, link.write_timeout_s, self.parent.role
        )
        self._buffer.clear()
        self._cut = False
        self._watch.opened(time.monotonic())
        if self._watch.ready:
            self._ready.set()
        else:
            self._ready.clear()  # the board resets on opening: hold the lines for it
        self.port = port
        if link.mode == "pages":  # lets the other end check the format version
            self._outbox.put_first((header_line() + "\n").encode("utf-8"))

    def halt(self) -> None:
        """Take no more lines; those queued may go out for a moment (see ``join``)."""
        self._flush_until = time.monotonic() + _FLUSH_S
        self._outbox.close()

    def join(self, timeout_s: Optional[float] = None) -> None:
        """Wait (up to ``timeout_s``) for the reading thread and the writer thread.

        The writer sends what was queued before ``halt`` for at most 0.25 s;
        then the rest is dropped (and counted) and a write still blocked on
        the device is cancelled.
        """
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        super().join(timeout_s)
        self._stop_writer(deadline)

    def _stop_writer(self, deadline: Optional[float]) -> None:
        writer = self._writer
        if writer is None or writer is threading.current_thread():
            return
        if not self._outbox.closed:  # not halted: the writer is meant to keep going
            writer.join(None if deadline is None else max(0.0, deadline - time.monotonic()))
            return
        flush_end = self._flush_until
        if deadline is not None:
            flush_end = min(flush_end, deadline)
        writer.join(max(0.0, flush_end - time.monotonic()))
        if not writer.is_alive():
            return
        left = self._outbox.close(discard=True)
        if left:
            self._loss.dropped(left)
        cancel = getattr(self.port, "cancel_write", None)
        if cancel is not None:
            try:
                cancel()  # wakes a write that waits for the device (POSIX, Windows)
            except Exception:  # the port is going away anyway
                pass
        writer.join(None if deadline is None else max(0.0, deadline - time.monotonic()))

    def is_alive(self) -> bool:
        """True while the reading thread or the writer thread runs."""
        writer = self._writer
        return super().is_alive() or (writer is not None and writer.is_alive())

    def terminate(self) -> None:
        """Stop the writer (bounded by ``write_timeout_s``), then close the port."""
        self.halt()
        self._flush_until = time.monotonic()  # no more flushing: the link is going away
        self._stop_writer(time.monotonic() + self.link.write_timeout_s + 0.1)
        self._repeats.flush()
        port, self.port = self.port, None
        if port is not None:
            port.close()
            self.info(
                "Closed serial port %r: sent %d lines, received %d, dropped %d",
                self.link.port,
                self.lines_sent,
                self.lines_received,
                self.dropped,
            )

    # -- reading (the loop's thread) -----------------------------------------
    def loop(self) -> None:
        port = self.port
        if port is None:
            self._reconnect()
            return
        try:
            # Blocks at most read_timeout_s, so the loop notices a stop quickly.
            chunk = port.read(port.in_waiting or 1)
        except (self.serial.SerialException, OSError, TypeError) as error:
            # TypeError: pyserial on a port closed under it by the shutdown
            if not self.is_terminated():
                self._lost(error)
            return
        if chunk:
            self._take(chunk)
        self._follow_board(time.monotonic())

    def _follow_board(self, now_s: float) -> None:
        """Act on what the board protocol says is due (nothing, without it)."""
        for due in self._watch.tick(now_s):
            if due == "ready-timeout":
                self.err(
                    "The board on serial port %r sent no ready line within %.1f s (%d other "
                    "lines came). Its code should print %s once set up (see "
                    "examples/boards/); check the baud rate (%d). Sending to it anyway.",
                    self.link.port,
                    self.link.ready_timeout_s,
                    self._watch.boot_lines,
                    header_line(),
                    self.link.baudrate,
                )
                self._ready.set()
            elif due == "silent":
                self.warn(
                    "The board on serial port %r stopped answering: no line for %.1f s. Its "
                    "failsafe should have stopped its actuators. Still listening.",
                    self.link.port,
                    self._watch.silent_for_s(now_s),
                )
            elif due == "heartbeat":
                self.schedule(tasks.event(self._heartbeat_event))

    def _take(self, chunk: bytes) -> None:
        buffer = self._buffer
        buffer += chunk
        start = 0
        while True:
            end = buffer.find(b"\n", start)
            if end < 0:
                break
            raw = bytes(buffer[start:end])
            start = end + 1
            try:
                self._handle_line(raw)
            except Exception as error:  # one odd line must never stop the reading
                self._bad_line(
                    "failed",
                    raw.decode("utf-8", errors="replace"),
                    f"{type(error).__name__}: {error}; skipped",
                )
        del buffer[:start]
        if len(buffer) > MAX_LINE_BYTES:
            self._bad_line(
                "too long",
                f"<{len(buffer)} bytes with no newline>",
                "discarded: too long for a line. Check that both ends use the same baud "
                f"rate ({self.link.baudrate})",
            )
            buffer.clear()

    def _handle_line(self, raw: bytes) -> None:
        text = raw.decode("utf-8", errors="replace").rstrip("\r")
        self.lines_received += 1
        if not self._board_says(raw, text):
            return
        if is_heartbeat_line(text):
            self.heartbeats_received += 1
            return
        if self.link.mode == "lines":
            self.store_data(self.link.receive_key, text)
            return
        if not text.strip():
            return
        try:
            page = page_from_line(raw, default_origin=self.name)
        except Exception as error:  # not JSON, not a page, too deep, inf...: never fatal
            why = (
                error if isinstance(error, WireFormatError) else f"{type(error).__name__}: {error}"
            )
            self._bad_line(
                "not a page", text, f"{why}; stored as text under {self.link.receive_key!r}"
            )
            self.store_data(self.link.receive_key, text)
            return
        if page is None:
            return  # the other end's header line
        if page.key == HEARTBEAT_KEY:  # a heartbeat written another way
            self.heartbeats_received += 1
            return
        if not page.origin:
            page.origin = self.name
        if page.key in self._send_keys:  # do not send it straight back
            self._received[id(page)] = page
            if len(self._received) > _ECHO_GUARD_SIZE:
                self._received.popitem(last=False)  # one call: safe beside pop()
        self.store_page(page)

    def _board_says(self, raw: bytes, text: str) -> bool:
        """Follow the board protocol for one line; True if the line is to be used."""
        verdict = self._watch.line(raw, time.monotonic())
        if verdict == "boot":
            self.boot_lines += 1
            self.dbg("Skipped a line before the board was ready: %.80r", text)
            return False
        if verdict == "ready":
            self.info(
                "The board on serial port %r is ready (%d lines of boot output skipped)",
                self.link.port,
                self._watch.boot_lines,
            )
            self._ready.set()
            return False
        if verdict == "ready-again":
            self._repeats.report(
                ("ready again",),
                f"Ready lines again from the board on serial port {self.link.port!r}",
                logging.WARNING,
                "The board on serial port %r sent its ready line again: it restarted (its "
                "reset button, a watchdog, its power dipping as motors start?), or its "
                "failsafe fired as it heard nothing from this link.",
                self.link.port,
            )
            return False
        if verdict == "use-again":
            self.info(
                "The board on serial port %r answers again, after %.1f s of silence",
                self.link.port,
                self._watch.last_silence_s,
            )
        return True

    def _bad_line(self, kind: str, text: str, why: str) -> None:
        self.bad_lines += 1
        self._repeats.report(
            ("bad line", kind),
            f"Lines from serial port {self.link.port!r} that are {kind}",
            logging.WARNING,
            "Line from serial port %r is %s: %.80r: %s",
            self.link.port,
            kind,
            text,
            why,
        )

    def _lost(self, error: Exception) -> None:
        self.err(
            "Lost serial port %r: %s. Check the cable; trying to reopen it.",
            self.link.port,
            error,
        )
        port, self.port = self.port, None
        if port is not None:
            try:
                port.close()
            except Exception:  # already gone; closing is only tidying up
                pass

    def _reconnect(self) -> None:
        pause_s = 0.25
        while not self.wait_s(pause_s):
            try:
                self._open()
            except CommsError as error:
                self.dbg("Still cannot reopen %r: %s", self.link.port, error)
                pause_s = min(pause_s * 2, _RECONNECT_MAX_S)
                continue
            self.info("Reopened serial port %r", self.link.port)
            return

    # -- sending: the node's thread queues, the writer thread writes -----------
    def send_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Queue the stored page (or its data, in lines mode) as one line; never blocks."""
        page = task.page()
        if page is None:
            what = task.val_list
            self.warn("A store_page task for %r carries %r, not a Page; not sent", task.name, what)
            return None
        if self._received.pop(id(page), None) is page:
            return None  # it came from the port; sending it back would echo forever
        try:
            line = self._encode(page)
        except NotSerializableError as error:
            self.err("Did not send a page over serial: %s", error)
            return None
        self._outbox.put((line + "\n").encode("utf-8"), page.key)  # drops are counted there
        return None

    def send_heartbeat(self, task: Task, key: TaskId) -> SomeTasks:
        """Queue the next heartbeat line (on the node's thread: proof it still runs)."""
        line = heartbeat_line(self.heartbeats_sent)
        self.heartbeats_sent += 1
        self._outbox.put((line + "\n").encode("ascii"), HEARTBEAT_KEY)
        return None

    def _encode(self, page: Page) -> str:
        if self.link.mode == "pages":
            return compact_line(page) if self.link.compact else page_to_line(page)
        data = page.data
        if isinstance(data, str):
            if "\n" in data or "\r" in data:
                raise NotSerializableError(
                    f"the text under {page.key!r} contains a line break, which would split "
                    "it into two lines: send one line per page, or use mode='pages'."
                )
            return data
        return data_json(page.key, data, to="to a serial link").decode("ascii")

    def _write_lines(self) -> None:
        """The writer thread: write queued lines until the outbox is closed and empty."""
        outbox = self._outbox
        while True:
            if not self._ready.wait(_WRITER_WAKE_S):  # the board is starting up
                if outbox.closed:
                    left = outbox.close(discard=True)
                    if left:
                        self._loss.dropped(left)
                    return
                continue
            data = outbox.take(_WRITER_WAKE_S)
            if data is None:
                if outbox.closed:
                    return
                continue
            if outbox.closed and time.monotonic() > self._flush_until:
                self._loss.dropped(1 + outbox.close(discard=True))
                return
            try:
                self._write(data)
                if not outbox and self._loss.dropping and not self._cut:
                    self._loss.recovered()  # caught up: the device reads again
            except Exception:  # a bug must not end the writing silently
                self.log.exception("Writing a line to serial port %r failed", self.link.port)

    def _write(self, data: bytes) -> None:
        port = self.port
        if self._cut:  # end the cut-off line, so it is not glued onto this one
            data = b"\n" + data
        try:
            if port is None:
                raise CommsError("the port is not open (reconnecting)")
            written = port.write(data)
        except self.serial.SerialTimeoutException:
            self._cut = True
            self._loss.dropped()
            return
        except Exception as error:  # SerialException, OSError, a port closed under it
            self._cut = True
            self._loss.dropped()
            if not self._write_failure_said and not self.is_terminated():
                self._write_failure_said = True  # once per outage, not once per line
                self.warn("Cannot write to serial port %r: %s", self.link.port, error)
            return
        if written is not None and written < len(data):  # the write was cancelled
            self._cut = True
            self._loss.dropped()
            return
        self._cut = False
        self._write_failure_said = False
        self.lines_sent += 1


class SerialLinkFactory(LoopFactory):
    """Builds a `SerialLinkLoop` that talks to a device over a serial port.

    Args:
        port: the device (``"/dev/ttyACM0"``, ``"COM3"``) or a pyserial URL
            (``"loop://"`` echoes back what is written: handy in tests).
        baudrate: bits per second; must match the device (``Serial.begin``).
        send_keys: data keys whose pages are written to the port.
        receive_key: where lines read are stored (``"lines"`` mode), or lines
            that are not pages (``"pages"`` mode).
        mode: ``"pages"`` (JSON page lines) or ``"lines"`` (raw text).
        read_timeout_s: how long one read waits; the loop stops within it.
        write_timeout_s: how long one line's write may wait for a device that
            stopped reading before the line is dropped (on the writer
            thread: the node never waits for the device).
        outbox_bytes: how many bytes of lines may wait for the device
            (default 8 KiB); when full, the newest line per key is kept and
            the drops are counted (``dropped``) and logged.
        name: the loop's name (default ``"serial_link"``).
        ready_timeout_s: after each opening, wait up to this long for the
            board's ready line (``board_protocol.READY_LINE``), skipping the lines before it and
            writing nothing; None (the default): do not wait. 5 s covers an
            Uno's reset.
        heartbeat_s: send a heartbeat line (``{"key":"hb","data":<n>}``) this
            often, e.g. 0.2; None: send none. The board's failsafe relies on it.
        answer_timeout_s: log a warning when the board sent no line for this
            long (its failsafe time, e.g. 1.0), and again when it answers;
            None: never.
        compact: in pages mode, write only each page's key and data
            (``{"key":"motor","data":[50,-50,0]}``), short enough for a small
            board's receive buffer.

    Raises:
        CommsError: pyserial is not installed (says how to install it); when
            the node starts, the port does not exist (lists the ports found) or
            permission is denied (explains the ``dialout`` group).

    Example::

        # an Arduino that reads motor speeds and prints sensor readings
        SerialLinkFactory("/dev/ttyACM0", 115200, send_keys=["motor_speed"],
                          receive_key="arduino_line", mode="lines")
        # a board running examples/boards/: handshake, heartbeats, failsafe
        SerialLinkFactory("/dev/serial/by-id/usb-Arduino_Uno_1234-if00",
                          send_keys=["motor"], ready_timeout_s=5.0,
                          heartbeat_s=0.2, answer_timeout_s=1.0, compact=True)
    """

    def __init__(
        self,
        port: str,
        baudrate: int = 115200,
        send_keys: Sequence[DataKey] = (),
        receive_key: DataKey = "serial_in",
        mode: str = "pages",
        read_timeout_s: float = 0.1,
        write_timeout_s: float = 1.0,
        name: Optional[str] = None,
        outbox_bytes: int = DEFAULT_OUTBOX_BYTES,
        ready_timeout_s: Optional[float] = None,
        heartbeat_s: Optional[float] = None,
        answer_timeout_s: Optional[float] = None,
        compact: bool = False,
    ) -> None:
        super().__init__(sys.modules[__name__])
        import_pyserial()  # fail now, with the install command, not at start-up
        self.port = port
        self.baudrate = baudrate
        keys = [send_keys] if isinstance(send_keys, str) else send_keys  # one key is fine
        self.send_keys: List[DataKey] = list(keys)
        self.receive_key = receive_key
        self.mode = mode
        self.read_timeout_s = read_timeout_s
        self.write_timeout_s = write_timeout_s
        self.outbox_bytes = outbox_bytes
        self.ready_timeout_s = ready_timeout_s
        self.heartbeat_s = heartbeat_s
        self.answer_timeout_s = answer_timeout_s
        self.compact = compact
        self.name = name or "serial_link"
        self._check()

    def _check(self) -> None:
        me = f"SerialLinkFactory({self.port!r})"
        if self.mode not in SERIAL_MODES:
            hint = did_you_mean(str(self.mode), SERIAL_MODES)
            raise ConfigError(f"{me}: mode={self.mode!r} is not one of {SERIAL_MODES}.{hint}")
        if self.mode == "lines" and self.receive_key in self.send_keys:
            raise ConfigError(
                f"{me}: receive_key {self.receive_key!r} is also in send_keys, so every line "
                "read would be written straight back. Use a different receive_key."
            )
        if not 0 < self.read_timeout_s <= 1.0:
            raise ConfigError(
                f"{me}: read_timeout_s={self.read_timeout_s}; use a value in (0, 1] so the "
                "link stops quickly when the node does."
            )
        if not 0 < self.write_timeout_s <= 10.0:
            raise ConfigError(
                f"{me}: write_timeout_s={self.write_timeout_s}; use a value in (0, 10]: a "
                "write that may wait forever would keep the link from stopping."
            )
        if isinstance(self.outbox_bytes, bool) or not (
            isinstance(self.outbox_bytes, int) and self.outbox_bytes > 0
        ):
            raise ConfigError(
                f"{me}: outbox_bytes={self.outbox_bytes!r}; give a positive whole number of "
                f"bytes (default {DEFAULT_OUTBOX_BYTES})."
            )
        if self.compact and self.mode != "pages":
            raise ConfigError(f"{me}: compact=True writes page lines: use it with mode='pages'.")
        try:
            BoardWatch(self.ready_timeout_s, self.heartbeat_s, self.answer_timeout_s)
        except ConfigError as error:
            raise ConfigError(f"{me}: {error}") from None

    def get(self, parent: AbstractNode) -> SerialLinkLoop:
        return SerialLinkLoop(self, parent)

    def __repr__(self) -> str:
        return f"SerialLinkFactory({self.port!r}, {self.baudrate}, mode={self.mode!r})"
