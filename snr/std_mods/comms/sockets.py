"""TCP comms: `SocketsPair` and its server and client loops (thesis 5.1, 5.4.1; docs/comms.md).

The client connects (and reconnects, with backoff) and forwards the pages
stored under its keys; the server stores what its clients send and forwards
its own keys, if given, to every client.

Example::

    sockets = snr.SocketsPair(server_tuple=("localhost", 9000))
    components = {
        "input_device": [..., sockets.client(["controller_data"])],
        "receiver": [sockets.server(), ...],
    }
"""

from __future__ import annotations

import logging
import os
import select
import socket
import time
from typing import Optional, Tuple

from snr.core.checks.os_errors import explain_os_error
from snr.core.logs import LossReport
from snr.prelude import AbstractNode, CommsError, ConfigError
from snr.std_mods.comms.comms_loop import (
    DEFAULT_DEAD_AFTER_S,
    DEFAULT_MAX_BACKLOG_BYTES,
    Keys,
    Link,
    LinkState,
)
from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, SCRIPT_FOLDER
from snr.std_mods.comms.io_loop import SocketTransport
from snr.std_mods.comms.pipe import _CommsFactory, _FactoryLoop

__all__ = [
    "DEFAULT_MAX_CONNECTIONS",
    "SocketsClientFactory",
    "SocketsClientLoop",
    "SocketsPair",
    "SocketsServerFactory",
    "SocketsServerLoop",
]

Address = Tuple[str, int]

DEFAULT_MAX_CONNECTIONS = 64
"""How many clients a sockets server takes at once (see `SocketsServerLoop`)."""

_CONNECT_TIMEOUT_S = 0.5
_FIRST_RETRY_S = 0.05
_MAX_RETRY_S = 1.0
_STABLE_S = 1.0  # a link that lasted this long (after a hello) resets the backoff


def _describe(address: Address) -> str:
    return f"{address[0]}:{address[1]}"


def _listen(address: Address, role: str) -> socket.socket:
    """A listening socket on ``address``, or a CommsError saying what to do."""
    listener: Optional[socket.socket] = None
    try:
        family, _, _, _, sockaddr = socket.getaddrinfo(*address, type=socket.SOCK_STREAM)[0]
        listener = socket.socket(family, socket.SOCK_STREAM)
        if os.name != "nt":  # lets a restarted server reuse the port at once
            listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(sockaddr)
        listener.listen()
    except OSError as error:
        if listener is not None:
            listener.close()
        raise CommsError(
            explain_os_error(
                error,
                action="listen",
                target=_describe(address),
                who=f"The sockets server of node {role!r}",
                setting="SocketsPair(server_tuple=(host, port)), on both sides",
            )
        ) from error
    listener.setblocking(False)  # it waits in select, with the stop's wake-up socket
    return listener


class SocketsServerLoop(_FactoryLoop):
    """Accepts clients and links to each; built by ``SocketsPair.server()``.

    It listens as the node starts (a port in use stops the node with a
    `CommsError`); its own thread accepts, the node's ``IOLoop`` serves the
    links. At ``max_connections`` the oldest connection that has not said
    hello makes room for a newcomer (counted in ``closed_silent``); when every
    one has, the newcomer is closed (counted in ``refused``).

    Example::

        sockets = SocketsPair(server_tuple=("localhost", 9000))
        {"receiver": [sockets.server(), ...]}
    """

    side = "server"
    peer_noun = "client"

    def __init__(self, factory: SocketsServerFactory, parent: AbstractNode) -> None:
        where = f"The sockets server of node {parent.role!r} ({_describe(factory.address)})"
        super().__init__(factory, parent, where)
        self.address = factory.address
        self.max_connections = cap = factory.max_connections
        self.refused = LossReport(
            self.log,
            "connections",
            f"this server already has {cap} clients, the most it takes, "
            "and every one has said hello (SocketsPair(..., max_connections=N) changes that)",
            verb="Refused",
        )
        self.closed_silent = LossReport(
            self.log,
            "connections that had not said hello",
            f"this server has {cap} clients, the most it takes, and new "
            "ones came: the oldest that had not said hello made room for each, so a real node "
            "always gets in (SocketsPair(..., max_connections=N) changes the cap)",
            verb="Closed",
        )
        self._listener: Optional[socket.socket] = None
        self._stop_r: Optional[socket.socket] = None  # halt() writes to _stop_w: accepting ends
        self._stop_w: Optional[socket.socket] = None

    def begin(self) -> None:
        """Start listening (on the node's thread, so errors stop the node)."""
        # Each socket is stored as soon as made, so terminate() closes it even if
        # the next one fails (e.g. socketpair() with too many files open).
        self._listener = _listen(self.address, self.parent.role)
        self._stop_r, self._stop_w = socket.socketpair()
        self.info("Listening for sockets clients on %s", _describe(self.address))

    def loop(self) -> None:
        """Wait for a client (or the stop) and accept it."""
        listener, stop = self._listener, self._stop_r
        if listener is None or stop is None:
            return
        try:
            if listener not in select.select([listener, stop], [], [])[0]:  # halt(): stopping
                if not self.is_terminated():  # the stop was taken back (cancel_stop)
                    stop.recv(64)
                return
            sock, peer = listener.accept()
        except BlockingIOError:  # the client gave up before we took it
            return
        except OSError as error:
            if not self.is_terminated():
                self.warn("Accepting a client failed: %s; still listening.", error)
                self.wait_s(0.1)
            return
        if self.is_terminated():
            sock.close()
            return
        ended = (LinkState.ENDING, LinkState.CLOSED)  # aborted links go in a moment
        if sum(1 for link in self.links if link.state not in ended) >= self.max_connections:
            # Full: the oldest connection with no hello (or no proof yet) makes room.
            silent = [
                link
                for link in self.links
                if link.state is LinkState.HELLO
                or (link.peer_role is None and link.state is LinkState.OPEN)
            ]
            if not silent:
                sock.close()  # the client sees the connection end and retries later
                self.refused.dropped()
                return
            silent[0].abort(
                f"it had not said hello in {time.monotonic() - silent[0].opened_at:.1f} s and "
                f"the server, full ({self.max_connections} clients), made room for a new one"
            )
            self.closed_silent.dropped()
        if self.refused.dropping:
            self.refused.recovered()
        link = self.open_link(SocketTransport(sock, _describe(peer[:2]), self.dead_after_s))
        self.dbg("Accepted a connection from %s", link.transport.peer)

    def on_hello(self, link: Link) -> None:
        self.say(
            "Clients connected",
            logging.INFO,
            "Client node %s connected from %s",
            link.peer_name,
            link.transport.peer,
        )

    def on_link_lost(self, link: Link, reason: str) -> None:
        self.say(
            "Clients disconnected",
            logging.WARNING if link.went_silent else logging.INFO,  # a silent death is news
            "Client %s disconnected: %s. Still listening.",
            link.label,
            reason,
        )

    def halt(self) -> None:
        """Stop accepting, then flush and close every client link."""
        if self._stop_w is not None:
            try:
                self._stop_w.send(b"\0")  # ends the wait for a client
            except OSError:
                pass
        super().halt()

    def terminate(self) -> None:
        """Close the listening socket and every link."""
        super().terminate()
        for end in (self._listener, self._stop_r, self._stop_w):
            if end is not None:
                end.close()


class SocketsClientLoop(_FactoryLoop):
    """Connects to a sockets server and keeps connecting; built by ``client()``.

    It retries with backoff (0.05 s, doubling, at most 1 s), back to 0.05 s
    only after a link that lasted a second past the server's hello, so a
    server that accepts and hangs up (a full one) is tried once a second.

    Example::

        sockets = SocketsPair(server_tuple=("localhost", 9000))
        {"input_device": [..., sockets.client(["controller_data"])]}
    """

    side = "client"
    peer_noun = "sockets server"

    def __init__(self, factory: SocketsClientFactory, parent: AbstractNode) -> None:
        where = f"The sockets client of node {parent.role!r} (to {_describe(factory.address)})"
        super().__init__(factory, parent, where)
        self.address = factory.address
        self.link: Optional[Link] = None
        self._retry_s = _FIRST_RETRY_S
        self._waiting_reported = self._ever_connected = False
        self._loss_reported = False  # the current outage has been logged

    def loop(self) -> None:
        """Watch the current link, or try to connect once (then back off)."""
        link = self.link
        if link is not None:
            if not link.is_closed():
                link.wait_closed(None)  # it ends, or halt() closes it
                return
            self.link = None
            if link.hello_at is not None and time.monotonic() - link.hello_at >= _STABLE_S:
                self._retry_s = _FIRST_RETRY_S  # it worked for a while: try again at once
            else:  # a server that accepts and then hangs up (e.g. full) is not hammered
                self._back_off()
                return
        try:
            sock = socket.create_connection(self.address, timeout=_CONNECT_TIMEOUT_S)
            if sock.getsockname() == sock.getpeername():  # TCP "simultaneous open": no server
                sock.close()
                raise ConnectionRefusedError(0, "connected to itself")
        except OSError as error:
            if not self._waiting_reported and not self._ever_connected:
                self._waiting_reported = True
                self.info(
                    "Waiting for the sockets server at %s (%s); retrying until it is up.",
                    _describe(self.address),
                    error.strerror or str(error),
                )
            self._back_off()
            return
        if self.is_terminated():
            sock.close()
            return
        self._waiting_reported = False
        self.link = self.open_link(
            SocketTransport(sock, _describe(self.address), self.dead_after_s)
        )
        self.dbg("TCP connection to %s made", _describe(self.address))

    def _back_off(self) -> None:
        self.wait_s(self._retry_s)
        self._retry_s = min(self._retry_s * 2, _MAX_RETRY_S)

    def on_hello(self, link: Link) -> None:
        verb = "Reconnected" if self._ever_connected else "Connected"
        self._ever_connected = True
        self._loss_reported = False
        self.say(
            "Connections to the sockets server",
            logging.INFO,
            "%s to the sockets server, node %s at %s",
            verb,
            link.peer_name,
            link.transport.peer,
        )

    def on_link_lost(self, link: Link, reason: str) -> None:
        if self._loss_reported and link.peer_role is None:  # no hello, outage already said
            self.dbg("Connection to %s failed again: %s", link.label, reason)
            return
        self._loss_reported = True
        if link.peer_said_bye:  # its node stopped in order: news, not a fault
            level, what = logging.INFO, "The sockets server %s closed the link"
        else:
            level, what = logging.WARNING, "Lost the link to the sockets server %s"
        self.say(
            "Links to the sockets server ended",
            level,
            what + ": %s. Reconnecting in the background; pages stored meanwhile are not sent.",
            link.label,
            reason,
        )


class _SocketsFactory(_CommsFactory):
    side = "side"  # "server" or "client": part of the default component name

    def __init__(
        self,
        address: Address,
        keys: Keys = None,
        name: Optional[str] = None,
        max_backlog_bytes: int = DEFAULT_MAX_BACKLOG_BYTES,
        dead_after_s: float = DEFAULT_DEAD_AFTER_S,
        max_connections: int = DEFAULT_MAX_CONNECTIONS,
        system: Optional[str] = SCRIPT_FOLDER,
        secret: Optional[str] = FROM_ENVIRONMENT,
    ) -> None:
        self.address = address
        where = f"{type(self).__name__} for {_describe(address)}"
        name = name or f"sockets_{self.side}_{address[1]}"
        super().__init__(keys, where, name, max_backlog_bytes, dead_after_s, system, secret)
        self.max_connections = max_connections

    def __repr__(self) -> str:  # never the secret: a repr may end up in a log
        return f"{type(self).__name__}({_describe(self.address)}, keys={list(self.keys)})"


class SocketsServerFactory(_SocketsFactory):
    """Builds a `SocketsServerLoop`; usually made by ``SocketsPair.server()``.

    Example::

        SocketsServerFactory(("localhost", 9000), keys=["sensor_data"])
    """

    side = "server"

    def get(self, parent: AbstractNode) -> SocketsServerLoop:
        return SocketsServerLoop(self, parent)


class SocketsClientFactory(_SocketsFactory):
    """Builds a `SocketsClientLoop`; usually made by ``SocketsPair.client(keys)``.

    Example::

        SocketsClientFactory(("localhost", 9000), keys=["controller_data"])
    """

    side = "client"

    def get(self, parent: AbstractNode) -> SocketsClientLoop:
        return SocketsClientLoop(self, parent)


class SocketsPair:
    """The two ends of one TCP connection between nodes (thesis listings 5.1, 5.3).

    Args:
        server_tuple: ``(host, port)`` the server listens on and clients
            connect to, e.g. ``("192.168.1.10", 9000)`` or ``("localhost", 9000)``.
        max_backlog_bytes: how much may wait for one slow peer before pages are
            dropped (newest page per key kept; counted and logged).
        dead_after_s: seconds of silence after which a peer counts as lost.
        max_connections: how many clients the server takes at once (64).
        system: the system both ends name in their hello; a peer of another
            system, or of none, is refused. Default: the config's ``name``,
            else the script's folder. None: no check (older SNR nodes).
        secret: the secret both ends prove they know (docs/comms.md, "Who
            may connect"). Default: ``$SNR_SECRET``, else the file of
            ``python -m snr secret new``, else none. None: none.

    Example::

        sockets = snr.SocketsPair(server_tuple=("localhost", 9000))
        components = {
            "input_device": [..., sockets.client(["controller_data"])],
            "receiver": [sockets.server(), ...],
        }
    """

    def __init__(
        self,
        server_tuple: Address,
        max_backlog_bytes: int = DEFAULT_MAX_BACKLOG_BYTES,
        dead_after_s: float = DEFAULT_DEAD_AFTER_S,
        max_connections: int = DEFAULT_MAX_CONNECTIONS,
        system: Optional[str] = SCRIPT_FOLDER,
        secret: Optional[str] = FROM_ENVIRONMENT,
    ) -> None:
        well_formed = isinstance(server_tuple, tuple) and len(server_tuple) == 2
        host, port = server_tuple if well_formed else ("", 0)
        # Any int but a bool, so an IntEnum of the robot's ports is a port too.
        if (
            not isinstance(host, str)
            or isinstance(port, bool)
            or not isinstance(port, int)
            or not 0 < port < 65536
        ):
            raise ConfigError(
                f"SocketsPair(server_tuple={server_tuple!r}) needs a (host, port) tuple: "
                "a host name or IP address string and a port from 1 to 65535, e.g. "
                '("localhost", 9000).'
            )
        self.server_tuple: Address = server_tuple
        self.max_backlog_bytes = max_backlog_bytes
        self.dead_after_s = dead_after_s
        self.max_connections = max_connections
        self.system = system
        self.secret = secret

    def _settings(self) -> Tuple[int, float, int, Optional[str], Optional[str]]:
        """What both sides are built with, besides the address, keys and name."""
        return (
            self.max_backlog_bytes,
            self.dead_after_s,
            self.max_connections,
            self.system,
            self.secret,
        )

    def server(self, keys: Keys = None, name: Optional[str] = None) -> SocketsServerFactory:
        """The factory for the listening side; ``keys`` it forwards to clients.

        Example::

            sockets.server()                  # only receives
            sockets.server(["sensor_data"])   # also sends sensor_data to clients
        """
        return SocketsServerFactory(self.server_tuple, keys, name, *self._settings())

    def client(self, keys: Keys = None, name: Optional[str] = None) -> SocketsClientFactory:
        """The factory for the connecting side; ``keys`` (one or a list) it forwards.

        Example::

            sockets.client(["controller_data"])
            sockets.client("controller_input")
        """
        return SocketsClientFactory(self.server_tuple, keys, name, *self._settings())

    def __repr__(self) -> str:
        return f"SocketsPair(server_tuple={self.server_tuple!r})"
