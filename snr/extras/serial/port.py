"""Opening a serial port: pyserial (an optional extra), the ports there are, errors that explain.

What `SerialLinkLoop` (``serial_link_loop.py``) uses to open its port, kept
apart so that a program can list ports or open one the same way.
pyserial is an optional dependency: ``pip install 'snr-robotics[serial]'``.

Example::

    print(available_ports())                        # ['/dev/ttyACM0 (Arduino Uno)']
    port = open_serial_port("loop://", 115200, 0.1, 1.0)
"""

from __future__ import annotations

from typing import Any, List, Optional

from snr.core.checks.os_errors import explain_os_error
from snr.prelude import CommsError
from snr.prelude.install import install_hint

__all__ = [
    "available_ports",
    "describe_open_error",
    "import_pyserial",
    "open_serial_port",
]


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
            f"it with:  {install_hint('serial')}   (or: pip install pyserial)"
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


def _ports_or_none() -> Optional[List[str]]:
    try:
        return list(available_ports())
    except Exception:  # listing is only a hint; never hide the real error
        return None


def describe_open_error(port: str, error: Exception, role: str = "") -> CommsError:
    """A CommsError that explains why ``port`` could not be opened, and the fix.

    Example::

        describe_open_error("/dev/ttyUSB0", SerialException(13, "denied"), "urov")
        # CommsError("The serial link of node 'urov' cannot open serial port
        #  /dev/ttyUSB0: permission denied. On Linux, ...")
    """
    return CommsError(
        explain_os_error(
            error,
            action="open",
            target=port,
            who=f"The serial link of node {role!r}" if role else "The serial link",
            setting="SerialLinkFactory(port=...)",
            ports=_ports_or_none(),
        )
    )


def open_serial_port(
    port: str, baudrate: int, read_timeout_s: float, write_timeout_s: float, role: str = ""
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
        raise describe_open_error(port, error, role) from error
