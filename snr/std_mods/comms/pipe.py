"""Pipe comms: link two nodes run by `MultiProcRunner` on one machine (thesis 6.4.1).

Each end of a ``multiprocessing.Pipe()`` goes to one role's config. Frames
are the same as over TCP (docs/wire-format.md), sent as bytes messages::

    here, there = multiprocessing.Pipe()
    components = {
        "topside": [PipeLoopFactory(here, ["controller_input"]), ...],
        "urov": [PipeLoopFactory(there, ["sensor_data"]), ...],
    }
    snr.MultiProcRunner(["topside", "urov"], components).run()

A pipe cannot be reconnected: once its other end is closed in every process,
the loop logs it and stops; the node keeps running. (A process that still holds
the other end, such as the parent, keeps the pipe open.)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional

from snr.core import LoopFactory
from snr.prelude import AbstractNode, ConfigError
from snr.std_mods.comms.link import (
    DEFAULT_DEAD_AFTER_S,
    DEFAULT_MAX_BACKLOG_BYTES,
    CommsLoop,
    Keys,
    Link,
    normalize_keys,
)

if TYPE_CHECKING:  # multiprocessing costs ~14 ms to import; the caller made the pipe
    from multiprocessing.connection import Connection

__all__ = ["PipeLoop", "PipeLoopFactory", "PipeTransport"]

_POLL_S = 0.25  # how often a waiting reader checks whether it should stop


class PipeTransport:
    """One end of a ``multiprocessing.Pipe()`` as a link ``Transport``.

    Example::

        here, there = multiprocessing.Pipe()
        PipeTransport(here)
    """

    can_try_send = False  # Connection.send_bytes always blocks: the writer thread sends

    def __init__(self, connection: Connection, peer: str = "pipe") -> None:
        self.connection = connection
        self.peer = peer
        self._interrupted = False

    def send_all(self, data: bytes) -> None:
        """Send ``data`` as one message (blocks while the pipe is full)."""
        self.connection.send_bytes(data)

    def try_send(self, data: bytes) -> int:
        """Not possible on a pipe; the outbox never calls it."""
        raise BlockingIOError("pipes cannot send without blocking")

    def receive(self) -> Optional[bytes]:
        """The next message; ``b""`` once the other end is closed; None after a wait."""
        if self._interrupted:
            return b""
        try:
            if not self.connection.poll(_POLL_S):
                return None
            return self.connection.recv_bytes()
        except EOFError:
            return b""

    def end_writing(self) -> None:
        """Pipes have no half-close; the reader stops on its next poll."""

    def interrupt(self) -> None:
        """Make the reader stop at its next poll (within 0.25 s)."""
        self._interrupted = True

    def close(self) -> None:
        """Close this end of the pipe."""
        self.connection.close()


class PipeLoop(CommsLoop):
    """Forwards pages over one end of a pipe; built by `PipeLoopFactory`.

    Example::

        PipeLoopFactory(connection, ["controller_input"]).get(node)
    """

    def __init__(self, factory: PipeLoopFactory, parent: AbstractNode) -> None:
        super().__init__(
            factory,
            parent,
            factory.name,
            factory.keys,
            factory.max_backlog_bytes,
            factory.dead_after_s,
        )
        self.connection = factory.connection
        self.link: Optional[Link] = None

    def begin(self) -> None:
        """Open the link at once: the pipe is connected from the start."""
        self.link = self.open_link(PipeTransport(self.connection))

    def loop(self) -> None:
        """Wait; stop once the pipe has closed (a pipe cannot reconnect)."""
        if self.link is None or self.link.wait_closed(0.5):
            self.set_terminate_flag("the pipe closed")

    def on_link_lost(self, link: Link, reason: str) -> None:
        self.warn(
            "The pipe to %s closed: %s. Pipes cannot reconnect, so pages under %s are "
            "no longer forwarded; the node keeps running.",
            link.label,
            reason,
            list(self.keys),
        )


class PipeLoopFactory(LoopFactory):
    """Builds a `PipeLoop` on one end of a ``multiprocessing.Pipe()``.

    Args:
        connection: this node's end of the pipe.
        keys: the data key (or list of keys) to forward to the other end.
        name: the component name (default ``"pipe_loop"``).
        max_backlog_bytes: how much may wait for a slow peer before pages are dropped.
        dead_after_s: seconds of silence after which the other end counts as lost.

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
    ) -> None:
        super().__init__()
        if not all(hasattr(connection, m) for m in ("send_bytes", "recv_bytes", "poll")):
            raise ConfigError(
                f"PipeLoopFactory got {connection!r} ({type(connection).__name__}) as its "
                "connection. Pass one end of multiprocessing.Pipe(): "
                "`here, there = multiprocessing.Pipe()`, then PipeLoopFactory(here, keys)."
            )
        self.connection: Any = connection
        self.keys = normalize_keys(keys, "PipeLoopFactory")
        self.name = name or "pipe_loop"
        self.max_backlog_bytes = max_backlog_bytes
        self.dead_after_s = dead_after_s

    def get(self, parent: AbstractNode) -> PipeLoop:
        return PipeLoop(self, parent)
