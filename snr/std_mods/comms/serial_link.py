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

pyserial is an optional dependency: ``pip install 'snr[serial]'``.
"""

from __future__ import annotations

import collections
import errno
import json
import sys
from typing import Any, List, Optional, Sequence

from snr.core import LoopFactory, ThreadLoop
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
from snr.prelude.errors import closest_match
from snr.std_mods.codec import header_line, page_from_line, page_to_line

__all__ = [
    "SERIAL_MODES",
    "SerialLinkFactory",
    "SerialLinkLoop",
    "available_ports",
    "describe_open_error",
    "import_pyserial",
    "open_serial_port",
]

SERIAL_MODES = ("pages", "lines")
"""The ways a serial link can talk: JSON page lines, or raw text lines."""

MAX_LINE_BYTES = 64 * 1024
"""A longer line is discarded: without a newline it is probably noise."""

_ECHO_GUARD_SIZE = 10_000
_RECONNECT_MAX_S = 5.0


def import_pyserial() -> Any:
    """The ``serial`` module, or a CommsError saying how to install it.

    Example::

        serial = import_pyserial()
        serial.serial_for_url("loop://")
    """
    try:
        import serial
        import serial.tools.list_ports
    except ImportError as error:
        raise CommsError(
            "The serial link needs the pyserial package, which is not installed. Install "
            "it with:  pip install 'snr[serial]'   (or: pip install pyserial)"
        ) from error
    return serial


def available_ports() -> List[str]:
    """The serial ports of this computer, e.g. ``['/dev/ttyACM0 (Arduino Uno)']``.

    Example::

        print(available_ports())
    """
    serial = import_pyserial()
    ports = []
    for info in sorted(serial.tools.list_ports.comports(), key=lambda p: p.device):
        described = info.description and info.description != "n/a"
        ports.append(f"{info.device} ({info.description})" if described else info.device)
    return ports


def _ports_hint() -> str:
    try:
        ports = available_ports()
    except Exception:  # listing is only a hint; never hide the real error
        return ""
    if not ports:
        return " No serial ports were found on this computer: is the device plugged in?"
    return " Serial ports on this computer: " + ", ".join(ports) + "."


def describe_open_error(port: str, error: Exception) -> CommsError:
    """A CommsError that explains why ``port`` could not be opened, and the fix.

    Example::

        describe_open_error("/dev/ttyUSB0", SerialException(13, "denied"))
        # CommsError("Permission denied opening serial port '/dev/ttyUSB0'. ...")
    """
    code = getattr(error, "errno", None)
    text = str(error)
    if code in (errno.EACCES, errno.EPERM) or "PermissionError" in text or "denied" in text:
        return CommsError(
            f"Permission denied opening serial port {port!r}. On Linux, serial ports belong "
            "to the 'dialout' group: add yourself with  sudo usermod -a -G dialout $USER  "
            "then log out and back in (`groups` should list dialout). On Windows this "
            "means another program (e.g. a serial monitor) has the port open: close it."
        )
    if code == errno.EBUSY:
        return CommsError(
            f"Serial port {port!r} is busy: another program has it open (a serial monitor, "
            "another SNR node?). Close that program and try again."
        )
    if code in (errno.ENOENT, errno.ENODEV, errno.ENXIO) or "FileNotFoundError" in text:
        return CommsError(
            f"Serial port {port!r} does not exist.{_ports_hint()} Check the cable and the "
            "name: Linux /dev/ttyUSB0 or /dev/ttyACM0, macOS /dev/cu.usbmodem..., Windows "
            "COM3."
        )
    return CommsError(f"Cannot open serial port {port!r}: {text}.{_ports_hint()}")


def open_serial_port(
    port: str, baudrate: int, read_timeout_s: float, write_timeout_s: float
) -> Any:
    """Open ``port`` (a device or pyserial URL) or raise a CommsError that explains.

    Example::

        link = open_serial_port("loop://", 115200, 0.1, 1.0)
    """
    serial = import_pyserial()
    try:
        return serial.serial_for_url(
            port, baudrate=baudrate, timeout=read_timeout_s, write_timeout=write_timeout_s
        )
    except ValueError as error:  # bad URL scheme, impossible baud rate
        raise CommsError(
            f"Cannot open serial port {port!r} at {baudrate} baud: {error}. Give a device "
            "name such as '/dev/ttyACM0' or 'COM3', or a pyserial URL such as 'loop://'."
        ) from error
    except (serial.SerialException, OSError) as error:
        raise describe_open_error(port, error) from error


class SerialLinkLoop(ThreadLoop):
    """Reads lines from the port on its thread; writes pages from handlers.

    If the device disappears (unplugged), the loop logs it and tries to
    reopen the port with a growing pause (up to 5 s) until the node stops.

    Example::

        SerialLinkFactory("/dev/ttyACM0", send_keys=["motor_speed"], mode="lines")
    """

    def __init__(self, factory: SerialLinkFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.link = factory
        self.serial = import_pyserial()
        self.port: Any = None
        self.lines_received = 0
        self.lines_sent = 0
        self._buffer = bytearray()
        self._bad_lines = 0
        self._send_keys = set(factory.send_keys)
        self._received: collections.OrderedDict[int, Page] = collections.OrderedDict()
        self._reported_send_failure = False
        self.task_handlers = {
            (TaskType.store_page, key): self.send_page for key in factory.send_keys
        }

    # -- starting and stopping ------------------------------------------------
    def begin(self) -> None:
        """Open the port now, so a wrong port name stops the node at start-up."""
        self._open()

    def _open(self) -> None:
        link = self.link
        self.port = open_serial_port(
            link.port, link.baudrate, link.read_timeout_s, link.write_timeout_s
        )
        self._buffer.clear()
        self._reported_send_failure = False
        if link.mode == "pages":  # lets the other end check the format version
            self._write_line(header_line())

    def terminate(self) -> None:
        """Close the port."""
        port, self.port = self.port, None
        if port is not None:
            port.close()
            self.info(
                "Closed serial port %r: sent %d lines, received %d",
                self.link.port,
                self.lines_sent,
                self.lines_received,
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

    def _take(self, chunk: bytes) -> None:
        buffer = self._buffer
        buffer += chunk
        start = 0
        while True:
            end = buffer.find(b"\n", start)
            if end < 0:
                break
            self._handle_line(bytes(buffer[start:end]))
            start = end + 1
        del buffer[:start]
        if len(buffer) > MAX_LINE_BYTES:
            self._bad_line(
                f"<{len(buffer)} bytes with no newline>",
                "discarded: too long for a line. Check that both ends use the same baud "
                f"rate ({self.link.baudrate})",
            )
            buffer.clear()

    def _handle_line(self, raw: bytes) -> None:
        text = raw.decode("utf-8", errors="replace").rstrip("\r")
        self.lines_received += 1
        if self.link.mode == "lines":
            self.store_data(self.link.receive_key, text)
            return
        if not text.strip():
            return
        try:
            page = page_from_line(raw, default_origin=self.name)
        except WireFormatError as error:
            self._bad_line(text, f"{error}; stored as text under {self.link.receive_key!r}")
            self.store_data(self.link.receive_key, text)
            return
        if page is None:
            return  # the other end's header line
        if not page.origin:
            page.origin = self.name
        if page.key in self._send_keys:  # do not send it straight back
            self._received[id(page)] = page
            if len(self._received) > _ECHO_GUARD_SIZE:
                self._received.popitem(last=False)  # one call: safe beside pop()
        self.store_page(page)

    def _bad_line(self, text: str, why: str) -> None:
        self._bad_lines += 1
        count = self._bad_lines
        if count & (count - 1) == 0:  # 1st, 2nd, 4th, 8th...: noise cannot flood the log
            self.warn(
                "Line from serial port %r is not a page (%d such lines so far): %.80r: %s",
                self.link.port,
                count,
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

    # -- writing (the node's thread) -------------------------------------------
    def send_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Write the stored page (or its data, in lines mode) as one line."""
        page = task.val_list[0] if task.val_list else None
        if not isinstance(page, Page):
            self.warn("A store_page task for %r carries %r, not a Page; not sent", task.name, page)
            return None
        if self._received.pop(id(page), None) is page:
            return None  # it came from the port; sending it back would echo forever
        try:
            line = self._encode(page)
        except NotSerializableError as error:
            self.err("Did not send a page over serial: %s", error)
            return None
        self._write_line(line)
        return None

    def _encode(self, page: Page) -> str:
        if self.link.mode == "pages":
            return page_to_line(page)
        data = page.data
        if isinstance(data, str):
            if "\n" in data or "\r" in data:
                raise NotSerializableError(
                    f"the text under {page.key!r} contains a line break, which would split "
                    "it into two lines: send one line per page, or use mode='pages'."
                )
            return data
        try:
            return json.dumps(data, separators=(",", ":"))
        except (TypeError, ValueError) as error:
            raise NotSerializableError(
                f"the data under {page.key!r} is a {type(data).__name__}, which cannot be "
                f"written as a line ({error}). Send strings, numbers, lists or dicts."
            ) from error

    def _write_line(self, line: str) -> None:
        port = self.port
        try:
            if port is None:
                raise CommsError("the port is not open (reconnecting)")
            port.write((line + "\n").encode("utf-8"))
        except (self.serial.SerialException, OSError, CommsError) as error:
            if not self._reported_send_failure:  # once per outage, not once per page
                self._reported_send_failure = True
                self.err(
                    "Could not write to serial port %r: %s. Lines are dropped until it "
                    "works again (is the device reading its serial port?).",
                    self.link.port,
                    error,
                )
            return
        self.lines_sent += 1
        if self._reported_send_failure:
            self._reported_send_failure = False
            self.info("Writing to serial port %r works again", self.link.port)


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
        write_timeout_s: how long a write may wait for a busy device.
        name: the loop's name (default ``"serial_link"``).

    Raises:
        CommsError: pyserial is not installed (says how to install it); when
            the node starts, the port does not exist (lists the ports found) or
            permission is denied (explains the ``dialout`` group).

    Example::

        # an Arduino that reads motor speeds and prints sensor readings
        SerialLinkFactory("/dev/ttyACM0", 115200, send_keys=["motor_speed"],
                          receive_key="arduino_line", mode="lines")
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
        self.name = name or "serial_link"
        self._check()

    def _check(self) -> None:
        me = f"SerialLinkFactory({self.port!r})"
        if self.mode not in SERIAL_MODES:
            guess = closest_match(str(self.mode), SERIAL_MODES)
            hint = f" Did you mean {guess!r}?" if guess else ""
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

    def get(self, parent: AbstractNode) -> SerialLinkLoop:
        return SerialLinkLoop(self, parent)

    def __repr__(self) -> str:
        return f"SerialLinkFactory({self.port!r}, {self.baudrate}, mode={self.mode!r})"
