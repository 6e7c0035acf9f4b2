"""`MemoryLinkPair`: link two nodes of one process in memory, with the real link code, no port.

Example::

    pair = MemoryLinkPair()
    config = Config({"a": [ticker, pair.first("tick")], "b": [pair.second(), counter]})
    # run Node("a", config) and Node("b", config) on two threads; pages under
    # "tick" stored on "a" are stored on "b" too. pair.cut() ends the link.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
from multiprocessing.connection import Connection
from typing import Tuple

from snr.prelude import AbstractNode, ConfigError
from snr.std_mods.comms.comms_loop import (
    DEFAULT_DEAD_AFTER_S,
    DEFAULT_MAX_BACKLOG_BYTES,
    CommsLoop,
    Keys,
    Link,
)
from snr.std_mods.comms.io_loop import SocketTransport
from snr.std_mods.comms.pipe import PipeLoop, PipeLoopFactory

__all__ = [
    "MemoryLinkFactory",
    "MemoryLinkLoop",
    "MemoryLinkPair",
    "memory_transport_pair",
]


def memory_transport_pair(
    names: Tuple[str, str] = ("memory-a", "memory-b"),
) -> Tuple[SocketTransport, SocketTransport]:
    """Two connected in-memory transport ends (as trio's ``memory_stream_pair``).

    A local socket pair, served as a TCP `SocketTransport` is (the TCP
    options do not apply and are skipped). Each end's ``peer`` is the name of
    the *other* end, for log messages.

    Example::

        here, there = memory_transport_pair()
        link = comms_loop.open_link(here)   # a CommsLoop of your own
    """
    first, second = socket.socketpair()
    return (
        SocketTransport(first, names[1], DEFAULT_DEAD_AFTER_S),
        SocketTransport(second, names[0], DEFAULT_DEAD_AFTER_S),
    )


class MemoryLinkLoop(PipeLoop):
    """Forwards pages over one end of a `MemoryLinkPair`; built by `MemoryLinkFactory`.

    A `PipeLoop` that logs a lost peer as a network link does ("Lost the link to ...").

    Example::

        MemoryLinkPair().first(["controller_input"]).get(node)
    """

    def on_link_lost(self, link: Link, reason: str) -> None:
        CommsLoop.on_link_lost(self, link, reason)


class MemoryLinkFactory(PipeLoopFactory):
    """Builds a `MemoryLinkLoop` on one end of a `MemoryLinkPair` (made by the pair).

    Each end serves one node once: a second ``get`` (a second node, or a
    reload) raises ConfigError, since the first loop owns the end.

    Example::

        pair = MemoryLinkPair()
        {"a": [pair.first("ping")], "b": [pair.second("pong")]}
    """

    _taken = False

    def take_transport(self) -> Connection:
        """The end this factory holds, once.

        Raises:
            ConfigError: it was already taken by an earlier loop.
        """
        if self._taken:
            raise ConfigError(
                f"The memory link {self.name!r} was already used by a node; each end of a "
                "MemoryLinkPair serves one node once. Make a new MemoryLinkPair() for each run."
            )
        self._taken = True
        return self.connection  # type: ignore[no-any-return]

    def get(self, parent: AbstractNode) -> MemoryLinkLoop:
        self.take_transport()
        return MemoryLinkLoop(self, parent)


class MemoryLinkPair:
    """Two comms components linked in memory, for two nodes of one process.

    Args:
        max_backlog_bytes: how much may wait for a slow peer before pages are dropped.
        dead_after_s: seconds of silence after which the other end counts as lost.

    Example::

        pair = MemoryLinkPair(dead_after_s=0.5)
        config = Config({"a": [pair.first("ping")], "b": [pair.second("pong")]})
        ...
        pair.cut()   # both sides see the peer go, as when a cable is pulled
        pair.close() # once the nodes have stopped
    """

    def __init__(
        self,
        max_backlog_bytes: int = DEFAULT_MAX_BACKLOG_BYTES,
        dead_after_s: float = DEFAULT_DEAD_AFTER_S,
    ) -> None:
        self.max_backlog_bytes = max_backlog_bytes
        self.dead_after_s = dead_after_s
        self._ends: Tuple[Connection, Connection] = multiprocessing.Pipe()

    def first(self, keys: Keys = None, name: str = "memory_link_a") -> MemoryLinkFactory:
        """The factory for the first node's end, forwarding ``keys`` to the second."""
        return self._factory(0, keys, name)

    def second(self, keys: Keys = None, name: str = "memory_link_b") -> MemoryLinkFactory:
        """The factory for the second node's end, forwarding ``keys`` to the first."""
        return self._factory(1, keys, name)

    def _factory(self, end: int, keys: Keys, name: str) -> MemoryLinkFactory:
        other = ("memory-a", "memory-b")[1 - end]  # the logs name the other end
        return MemoryLinkFactory(
            self._ends[end], keys, name, self.max_backlog_bytes, self.dead_after_s, other
        )

    def cut(self) -> None:
        """Break the connection both ways at once: each side reads end of stream.

        No goodbye is sent: each side logs a lost link, as when a peer crashes.
        """
        for end in self._ends:
            try:  # shut the socket down through a second descriptor of it
                with socket.socket(fileno=os.dup(end.fileno())) as sock:
                    sock.shutdown(socket.SHUT_RDWR)
            except OSError:  # that end is already closed
                pass

    def close(self) -> None:
        """Close both ends, used or not (a link closes its own end when its node stops).

        Call it once the nodes have stopped, e.g. ``self.addCleanup(pair.close)``.
        """
        for end in self._ends:
            end.close()
