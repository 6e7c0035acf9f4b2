"""Pipe comms: link two nodes run by `MultiProcRunner` on one machine (thesis 6.4.1).

The frames are TCP's (docs/wire-format.md). A pipe cannot reconnect: once its
other end is closed, the loop logs it and stops, and the node keeps running.

Example::

    here, there = multiprocessing.Pipe()
    components = {
        "topside": [PipeLoopFactory(here, ["controller_input"]), ...],
        "urov": [PipeLoopFactory(there, ["sensor_data"]), ...],
    }
"""

from __future__ import annotations

import os
import socket
import threading
from typing import TYPE_CHECKING, Any, Optional

from snr.core import LoopFactory
from snr.prelude import AbstractNode, ConfigError, WireFormatError
from snr.std_mods.codec import Message, decode_body, load_object, page_from_fields
from snr.std_mods.comms.comms_loop import (
    DEFAULT_DEAD_AFTER_S,
    DEFAULT_MAX_BACKLOG_BYTES,
    CommsLoop,
    Keys,
    Link,
    normalize_keys,
)
from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, find_secret, resolve_system
from snr.std_mods.comms.io_loop import SocketTransport

if TYPE_CHECKING:  # multiprocessing costs ~14 ms to import; the caller made the pipe
    from multiprocessing.connection import Connection

__all__ = ["PipeLoop", "PipeLoopFactory", "PipeTransport"]

_POLL_S = 0.25  # how often a bridge thread waiting on the pipe checks whether to stop
_BRIDGE_BYTES = 256 * 1024


class _CommsFactory(LoopFactory):
    """What the pipe and sockets factories share: the settings of their links."""

    def __init__(
        self,
        keys: Keys,
        where: str,
        name: str,
        max_backlog_bytes: int,
        dead_after_s: float,
        system: Optional[str],
        secret: Optional[str],
    ) -> None:
        super().__init__()
        self.keys = normalize_keys(keys, where)
        self.name = name
        self.max_backlog_bytes = max_backlog_bytes
        self.dead_after_s = dead_after_s
        self.system = system
        self.secret = secret


class _FactoryLoop(CommsLoop):
    """A comms loop built by a `_CommsFactory`: its settings, system and secret."""

    def __init__(self, factory: _CommsFactory, parent: AbstractNode, where: str) -> None:
        super().__init__(
            factory,
            parent,
            factory.name,
            factory.keys,
            factory.max_backlog_bytes,
            factory.dead_after_s,
        )
        self.system = resolve_system(factory.system, parent.config, where)
        self.secret = find_secret(factory.secret, where)


class PipeTransport(SocketTransport):
    """One end of a ``multiprocessing.Pipe()`` as a link ``Transport``: a byte stream of frames.

    On POSIX a two-way pipe is a socket pair, served like a TCP connection.
    Elsewhere (a Windows named pipe) a socket pair stands in for it, and two
    small threads copy bytes between the two (``bridged`` is then True).

    Example::

        here, there = multiprocessing.Pipe()
        PipeTransport(here)
    """

    def __init__(self, connection: Connection, peer: str = "pipe", bridge: bool = False) -> None:
        self.connection = connection
        self.peer = peer
        sock = None if bridge else _as_socket(connection)
        self.bridged = sock is None
        if sock is None:
            sock, self._far = socket.socketpair()
        sock.setblocking(False)
        self.sock = sock
        if self.bridged:  # they copy until close() closes self.sock
            self._threads = [
                threading.Thread(target=copy, name=f"snr-pipe-{name}", daemon=True)
                for name, copy in (("in", self._pipe_to_socket), ("out", self._socket_to_pipe))
            ]
            for thread in self._threads:
                thread.start()

    def end_writing(self) -> None:
        """Nothing: the other process may still use its end, so the pipe stays as it is."""

    def close(self) -> None:
        """Close this end of the pipe (and stop the copying threads, if any)."""
        self.sock.close()
        if self.bridged:
            for thread in self._threads:
                if thread is not threading.current_thread():
                    thread.join(_POLL_S * 2)
            self._far.close()
        self.connection.close()

    def _pipe_to_socket(self) -> None:
        try:
            while self.sock.fileno() != -1:
                if self.connection.poll(_POLL_S):
                    self._far.sendall(self.connection.recv_bytes())
        except (EOFError, OSError):
            pass
        finally:  # the link sees end of stream
            try:
                self._far.shutdown(socket.SHUT_WR)
            except OSError:
                pass

    def _socket_to_pipe(self) -> None:
        try:
            while data := self._far.recv(_BRIDGE_BYTES):
                self.connection.send_bytes(data)
        except OSError:
            pass


def _as_socket(connection: Connection) -> Optional[socket.socket]:
    """This pipe end's own socket (a duplicate of its descriptor), or None if it is not one."""
    if os.name == "nt":
        return None  # a named pipe's handle, not a socket
    try:
        fd = os.dup(connection.fileno())
    except OSError:
        return None
    try:
        sock = socket.socket(fileno=fd)
    except OSError:  # not a socket (an os.pipe end)
        os.close(fd)
        return None
    if sock.type != socket.SOCK_STREAM:
        sock.close()
        return None
    return sock


class PipeLoop(_FactoryLoop):
    """Forwards pages over one end of a pipe; built by `PipeLoopFactory`.

    Example::

        PipeLoopFactory(connection, ["controller_input"]).get(node)
    """

    def __init__(self, factory: PipeLoopFactory, parent: AbstractNode) -> None:
        where = f"The pipe loop {factory.name!r} of node {parent.role!r}"
        super().__init__(factory, parent, where)
        self.connection = factory.connection
        self.peer_name = factory.peer
        self.link: Optional[Link] = None

    def begin(self) -> None:
        """Open the link at once: the pipe is connected from the start."""
        self.link = self.open_link(PipeTransport(self.connection, self.peer_name))

    def loop(self) -> None:
        """Wait; stop once the pipe has closed (a pipe cannot reconnect)."""
        if self.link is None or self.link.wait_closed(None):
            self.set_terminate_flag("the pipe closed")

    def decode_message(self, body: bytes) -> Message:
        """A frame's message; on a pipe also a page in `Page.serialize()`'s text.

        Code of the 2021 release sends ``page.serialize().encode()`` into a
        pipe: a page's fields with no ``"v"``, checked as strictly as a frame's.

        Example::

            there.send_bytes(Page("depth", 2.5, "old_code", 0.0).serialize().encode())
        """
        try:
            return decode_body(body)
        except WireFormatError:
            try:
                fields = load_object(body)
            except WireFormatError:
                fields = {}
            if "v" in fields or "key" not in fields:
                raise  # not a 2021 page either: the frame's own error says why
            return page_from_fields(fields, default_origin=self.parent.role)

    def on_link_lost(self, link: Link, reason: str) -> None:
        say = self.info if link.peer_said_bye else self.warn  # a goodbye is no fault
        say(
            "The pipe to %s closed: %s. Pipes cannot reconnect, so pages under %s are "
            "no longer forwarded; the node keeps running.",
            link.label,
            reason,
            list(self.keys),
        )


class PipeLoopFactory(_CommsFactory):
    """Builds a `PipeLoop` on one end of a ``multiprocessing.Pipe()``.

    Args:
        connection: this node's end of the pipe.
        keys: the data key (or list of keys) to forward to the other end.
        name: the component name (default ``"pipe_loop"``).
        max_backlog_bytes: how much may wait for a slow peer before pages are dropped.
        dead_after_s: seconds of silence after which the other end counts as lost.
        peer: what the logs call the other end (default ``"pipe"``).
        system: the system both ends name (as for `SocketsPair`). Default
            None, no check: only the program that made the pipe reaches it,
            and 2021 code that writes pages with no hello keeps working.
        secret: the secret both ends prove they know (as for `SocketsPair`;
            default ``$SNR_SECRET`` or the secret file). None: none.

    Example::

        here, there = multiprocessing.Pipe()
        {"a": [PipeLoopFactory(here, "ping")], "b": [PipeLoopFactory(there, "pong")]}
    """

    def __init__(
        self,
        connection: Connection,
        keys: Keys = None,
        name: Optional[str] = None,
        max_backlog_bytes: int = DEFAULT_MAX_BACKLOG_BYTES,
        dead_after_s: float = DEFAULT_DEAD_AFTER_S,
        peer: str = "pipe",
        system: Optional[str] = None,
        secret: Optional[str] = FROM_ENVIRONMENT,
    ) -> None:
        if not all(hasattr(connection, m) for m in ("send_bytes", "recv_bytes", "poll")):
            raise ConfigError(
                f"PipeLoopFactory got {connection!r} ({type(connection).__name__}) as its "
                "connection. Pass one end of multiprocessing.Pipe(): "
                "`here, there = multiprocessing.Pipe()`, then PipeLoopFactory(here, keys)."
            )
        if not (getattr(connection, "readable", True) and getattr(connection, "writable", True)):
            raise ConfigError(
                "PipeLoopFactory got a one-way pipe end (multiprocessing.Pipe(duplex=False)); "
                "links talk both ways (each side says hello and sends beats). Use "
                "`here, there = multiprocessing.Pipe()`, which is two-way."
            )
        super().__init__(
            keys,
            "PipeLoopFactory",
            name or "pipe_loop",
            max_backlog_bytes,
            dead_after_s,
            system,
            secret,
        )
        self.connection: Any = connection
        self.peer = peer

    def get(self, parent: AbstractNode) -> PipeLoop:
        return PipeLoop(self, parent)
