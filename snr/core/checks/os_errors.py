"""One explanation for every OSError a student meets: a port, a connection, a serial port.

Every component that listens, connects or opens a serial port words its failure
with `explain_os_error` (docs/errors.md, 12).

Example::

    raise CommsError(explain_os_error(
        error, action="listen", target=f"{host}:{port}",
        who=f"The sockets server of node {role!r}",
        setting="SocketsPair(server_tuple=(host, port))",
    )) from error
"""

from __future__ import annotations

import errno
import os
import socket
from typing import List, Literal, Optional, Sequence, Set, Tuple

__all__ = ["OsAction", "explain_os_error"]

OsAction = Literal["listen", "connect", "open"]
"""What failed: listening on a port, connecting to one, or opening a serial port."""

_VERBS = {"listen": "listen on", "connect": "connect to", "open": "open serial port"}
_NO_DEVICE = {errno.ENOENT, errno.ENODEV, errno.ENXIO}
_DENIED = {errno.EACCES, errno.EPERM}
# (action or None for any, errnos, what is wrong and what to do): the first that fits.
_PROBLEMS: List[Tuple[Optional[str], Set[int], str]] = [
    (
        "listen",
        {errno.EADDRINUSE, getattr(errno, "WSAEADDRINUSE", errno.EADDRINUSE)},
        "port {port} is in use. Another program, or another SNR node still running (check "
        "your other terminals), is listening there. Stop it (`lsof -i :{port}` on Linux and "
        "macOS, `netstat -ano` on Windows, names it), or choose another port in {where}.",
    ),
    (
        "listen",
        {errno.EADDRNOTAVAIL},
        "{host!r} is not an address of this machine. Listen on 'localhost', on '0.0.0.0' "
        "(every network interface) or on this machine's own IP address; the side that "
        "connects is the one that names the other machine.",
    ),
    (
        "listen",
        _DENIED,
        "permission denied: ports below 1024 need administrator rights. Use a port from 1024 "
        "to 65535 in {where}.",
    ),
    (
        "connect",
        {errno.ECONNREFUSED},
        "the connection was refused: nothing is listening there. Start the node that listens "
        "on port {port} first, and check that both sides use the same host and port in "
        "{where}.",
    ),
    (
        "connect",
        {
            errno.ETIMEDOUT,
            errno.EHOSTUNREACH,
            errno.ENETUNREACH,
            getattr(errno, "EHOSTDOWN", errno.EHOSTUNREACH),
        },
        "the other machine did not answer. Check that it is switched on and on the same "
        "network, and that its address is right (try `ping` with it).",
    ),
    (
        None,
        {errno.ECONNRESET, errno.EPIPE, errno.ECONNABORTED},
        "the other side closed the connection. The other node probably stopped or crashed: "
        "its terminal says why.",
    ),
    (
        "open",
        _NO_DEVICE,
        "there is no such serial port. Check the cable and the name: Linux /dev/ttyUSB0 or "
        "/dev/ttyACM0, macOS /dev/cu.usbmodem..., Windows COM3.",
    ),
    (
        "open",
        _DENIED,
        "permission denied. On Linux, serial ports belong to the 'dialout' group: add "
        "yourself with `sudo usermod -a -G dialout $USER`, then log out and back in "
        "(`groups` should list dialout). On Windows, another program (a serial monitor?) "
        "has the port open: close it.",
    ),
    (
        "open",
        {errno.EBUSY},
        "another program has it open (a serial monitor, another SNR node?). Close that "
        "program and try again.",
    ),
]


def _errno_of(error: BaseException) -> Optional[int]:
    code = getattr(error, "errno", None)
    if isinstance(code, int):
        return code
    # pyserial wraps the OS error in text only on some systems.
    text = f"{type(error).__name__}: {error}"
    if isinstance(error, FileNotFoundError) or "No such file" in text or "FileNotFound" in text:
        return errno.ENOENT
    if isinstance(error, PermissionError) or "denied" in text or "PermissionError" in text:
        return errno.EACCES
    return None


def _problem(error: BaseException, action: OsAction, target: str, setting: str) -> str:
    """What is wrong and what to do, in plain words: the part after ``cannot ... X:``."""
    host, _, port = target.rpartition(":")
    if not port.isdigit():
        host, port = target, "PORT"
    if isinstance(error, socket.gaierror):
        return (
            f"the host name {host!r} cannot be found. Check its spelling, or use the "
            "machine's IP address, e.g. '192.168.1.20' ('localhost' is this machine)."
        )
    code = _errno_of(error)
    where = setting or "the config"
    for happens_to, codes, text in _PROBLEMS:
        if happens_to in (None, action) and code in codes:
            return text.format(host=host, port=port, where=where)
    reason = os.strerror(code) if code is not None else str(error)
    return f"{reason[:1].lower()}{reason[1:]}. Check the host, port or device name in {where}."


def explain_os_error(
    error: BaseException,
    *,
    action: OsAction,
    target: str,
    who: str,
    setting: str = "",
    ports: Optional[Sequence[str]] = None,
) -> str:
    """The message for an OSError of listening, connecting or opening a serial port.

    ``target`` is ``"host:port"`` or a serial port, ``who`` the sentence's subject
    (``"The sockets server of node 'urov'"``), ``setting`` where to change it
    ("the config" if empty), ``ports`` the serial ports there are (None: unknown).

    Example::

        explain_os_error(OSError(errno.EADDRINUSE, "Address already in use"),
                         action="listen", target="127.0.0.1:9000",
                         who="The sockets server of node 'urov'")
        # "The sockets server of node 'urov' cannot listen on 127.0.0.1:9000: port 9000
        #  is in use. Another program, ..."
    """
    text = f"{who} cannot {_VERBS[action]} {target}: {_problem(error, action, target, setting)}"
    if action == "open" and ports is not None and _errno_of(error) in _NO_DEVICE:
        found = ", ".join(ports) if ports else "none (is the device plugged in?)"
        text += f" Serial ports on this computer: {found}."
    return text
