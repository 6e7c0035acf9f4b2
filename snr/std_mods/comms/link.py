"""Links and the comms loop: what pipe and socket comms have in common.

A `Link` is one live connection to one peer node. It owns a *transport* (a
TCP socket or a pipe end), a reader thread that cuts incoming bytes into
frames and hands pages to its `CommsLoop`, and an `Outbox` whose writer thread
sends frames in the order they were queued.

A `CommsLoop` (thesis 6.4.1) is the component a node gets: it forwards every
page stored under its keys to each open link, and stores every page a link
receives, with the page's original origin and time.

How a page travels::

    node thread                          peer's reader thread      peer's node thread
    store_page → CommsLoop.forward_page  →  frame bytes  →  decode → schedule(store_page)
                 (encodes the very page       (outbox / writer         → datastore
                  that was stored)             thread, in order)       → process_data

Example (what `SocketsPair` and `PipeLoopFactory` build for you)::

    class MyLoop(CommsLoop):
        def begin(self) -> None:
            self.open_link(my_transport)

        def loop(self) -> None:
            self.wait_s(0.5)
"""

from __future__ import annotations

import collections
import enum
import logging
import threading
import time
from typing import Deque, Dict, List, Optional, Protocol, Sequence, Set, Tuple, Union

from snr.core import ThreadLoop, tasks
from snr.core.logs import RepeatFilter
from snr.prelude import (
    AbstractFactory,
    AbstractNode,
    ComponentName,
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
from snr.std_mods.comms.wire import FrameDecoder, Hello, decode_body, encode_hello, encode_page

__all__ = [
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "DEFAULT_MAX_BACKLOG_BYTES",
    "CommsLoop",
    "Keys",
    "Link",
    "LinkState",
    "Outbox",
    "Transport",
    "normalize_keys",
]

COMMS_CONNECTED = "comms_connected"
"""Event a comms loop schedules when a link opens: ``[component name, peer address]``.

Example::

    self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.on_connected}
"""

COMMS_DISCONNECTED = "comms_disconnected"
"""Event a comms loop schedules when a link closes: ``[component name, peer address]``."""

DEFAULT_MAX_BACKLOG_BYTES = 64 * 1024 * 1024
"""How many bytes of frames may wait for a slow peer before new pages are dropped."""

Keys = Union[DataKey, Sequence[DataKey], None]
"""What a comms factory takes as ``keys``: one data key, a list of them, or None."""

_MAX_CHUNK_BYTES = 1024 * 1024  # the writer joins queued frames into chunks up to this size
_BUSY_QUEUE_LENGTH = 8  # tasks waiting on the node above which frames are batched
_SHOWN_BAD_FRAMES = 5  # per link, log the first few bad frames in full, then a count every 5 s


def normalize_keys(keys: Keys, where: str) -> Tuple[str, ...]:
    """``keys`` as a tuple of data keys: a single key, a list of keys, or None.

    Example::

        normalize_keys("depth", "client")             # ('depth',)
        normalize_keys(["a", "b"], "client")          # ('a', 'b')
    """
    if keys is None:
        return ()
    listed = [keys] if isinstance(keys, str) else keys
    if not isinstance(listed, (list, tuple)):
        raise ConfigError(
            f"{where} got keys={keys!r} ({type(keys).__name__}). Give one data key or "
            'a list of them, e.g. ["controller_data"].'
        )
    for key in listed:
        if not isinstance(key, str) or not key:
            raise ConfigError(
                f"{where} got {key!r} among its keys; every key must be a non-empty "
                'string naming data to forward, e.g. ["controller_data"].'
            )
    return tuple(dict.fromkeys(listed))  # without duplicates, in order


class Transport(Protocol):
    """A byte pipe to one peer: a TCP socket or a multiprocessing pipe end.

    Example: ``SocketTransport(sock, "127.0.0.1:9000")`` in ``sockets.py``.
    """

    peer: str
    """Where the peer is, for log messages, e.g. ``"127.0.0.1:9000"``."""

    can_try_send: bool
    """True when ``try_send`` can write without blocking (sockets on POSIX)."""

    def send_all(self, data: bytes) -> None:
        """Write all of ``data``, blocking until it is handed to the OS."""

    def try_send(self, data: bytes) -> int:
        """Write what fits without blocking; how many bytes went."""

    def receive(self) -> Optional[bytes]:
        """Some bytes; ``b""`` at end of stream; None if nothing came in a while."""

    def end_writing(self) -> None:
        """Tell the peer nothing more will be sent (after a graceful flush)."""

    def interrupt(self) -> None:
        """Wake a blocked ``receive`` or ``send_all`` and make them fail."""

    def close(self) -> None:
        """Release the socket or pipe."""


class Outbox:
    """Frames waiting to be written to one peer, in the order they were queued.

    ``put`` runs on the node's thread. With ``now=True`` and nothing waiting,
    it writes the frame straight away without blocking (no thread switch: the
    lowest latency). Otherwise, or when the OS buffer is full, the frame is
    queued and the link's writer thread sends everything queued in one call
    (the highest throughput when many pages come at once). Either way frames
    leave in the order they were put.

    Example::

        outbox.put(frame, now=True)     # False when the backlog limit is reached
    """

    def __init__(self, transport: Transport, max_bytes: int) -> None:
        self.transport = transport
        self.max_bytes = max_bytes
        self._frames: Deque[bytes] = collections.deque()
        self._queued_bytes = 0
        self._writing = False  # the writer thread holds a chunk it is sending
        self._closed = False
        self._changed = threading.Condition(threading.Lock())

    def put(self, frame: bytes, now: bool = False) -> bool:
        """Send (if ``now``) or queue ``frame``; False if closed or backlog full."""
        with self._changed:
            if self._closed:
                return False
            if now and not self._frames and not self._writing and self.transport.can_try_send:
                try:
                    sent = self.transport.try_send(frame)
                except OSError:  # full (BlockingIOError) or broken: the writer deals with it
                    sent = 0
                if sent == len(frame):
                    return True
                frame = frame[sent:]  # the rest must go next, before anything else
            elif self._queued_bytes + len(frame) > self.max_bytes:
                return False
            self._frames.append(frame)
            self._queued_bytes += len(frame)
            self._changed.notify()
            return True

    def take(self) -> Optional[bytes]:
        """For the writer: the next chunk of frames; None once closed and empty.

        Blocks (without using CPU) until there is something to send.
        """
        with self._changed:
            self._writing = False
            while not self._frames:
                if self._closed:
                    return None
                self._changed.wait()
            parts: List[bytes] = []
            size = 0
            while self._frames and size < _MAX_CHUNK_BYTES:
                frame = self._frames.popleft()
                parts.append(frame)
                size += len(frame)
            self._queued_bytes -= size
            self._writing = True
            return parts[0] if len(parts) == 1 else b"".join(parts)

    def close(self, discard: bool) -> None:
        """Accept no more frames; with ``discard``, forget those still waiting."""
        with self._changed:
            self._closed = True
            if discard:
                self._frames.clear()
                self._queued_bytes = 0
            self._changed.notify_all()

    def __len__(self) -> int:
        return len(self._frames)


class LinkState(enum.Enum):
    """OPEN → CLOSING (flushing, after ``close()``) → CLOSED.

    Example::

        link.state is LinkState.OPEN
    """

    OPEN = "open"
    CLOSING = "closing"
    CLOSED = "closed"


class Link:
    """One live connection to one peer, with a reader and a writer thread.

    The reader thread owns the link's end: when the peer goes away, a bad
    length header arrives, or the link is aborted, it stops the writer,
    closes the transport and tells the `CommsLoop`.

    Example::

        link = Link(comms_loop, transport)
        link.start()
        link.send(encode_page(page))
        link.close()              # flush, then end the connection
    """

    flush_timeout_s: float = 1.0

    def __init__(self, owner: CommsLoop, transport: Transport) -> None:
        self.owner = owner
        self.transport = transport
        self.peer_role: Optional[str] = None
        self.state = LinkState.OPEN
        self.bad_frames = 0
        self.outbox = Outbox(transport, owner.max_backlog_bytes)
        self.outbox.put(encode_hello(owner.parent.role), now=False)
        self._closed = threading.Event()
        thread_name = f"snr-{owner.parent.role}-{owner.name}-{transport.peer}"
        self._reader = threading.Thread(target=self._read, name=thread_name + "-r", daemon=True)
        self._writer = threading.Thread(target=self._write, name=thread_name + "-w", daemon=True)

    @property
    def label(self) -> str:
        """The peer for log lines: ``"receiver at 127.0.0.1:9000"``."""
        if self.peer_role:
            return f"{self.peer_role!r} at {self.transport.peer}"
        return self.transport.peer

    def start(self) -> None:
        """Start the reader and writer threads."""
        self._writer.start()
        self._reader.start()

    def send(self, frame: bytes, now: bool = True) -> bool:
        """Send or queue ``frame`` (node thread); False if closing or backed up."""
        return self.state is LinkState.OPEN and self.outbox.put(frame, now)

    def close(self) -> None:
        """Send what is queued, then end the connection (graceful)."""
        if self.state is LinkState.OPEN:
            self.state = LinkState.CLOSING
            self.outbox.close(discard=False)

    def abort(self) -> None:
        """End the connection now, dropping what is queued."""
        self.state = LinkState.CLOSED
        self.outbox.close(discard=True)
        self.transport.interrupt()

    def is_closed(self) -> bool:
        """True once the reader has finished and the transport is closed."""
        return self._closed.is_set()

    def wait_closed(self, timeout_s: Optional[float]) -> bool:
        """Wait up to ``timeout_s`` for the link to close; True if it has."""
        return self._closed.wait(timeout_s)

    def is_alive(self) -> bool:
        """True while the reader or the writer thread runs."""
        return self._reader.is_alive() or self._writer.is_alive()

    def join(self, timeout_s: Optional[float]) -> None:
        """Wait for both threads to end."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        for thread in (self._reader, self._writer):
            if thread.is_alive() and thread is not threading.current_thread():
                thread.join(None if deadline is None else max(0.0, deadline - time.monotonic()))

    # -- writer thread --------------------------------------------------------
    def _write(self) -> None:
        try:
            chunk = self.outbox.take()
            while chunk is not None:
                self.transport.send_all(chunk)
                chunk = self.outbox.take()
            if self.state is LinkState.CLOSING:
                self.transport.end_writing()
        except OSError:  # the peer is gone: wake the reader, which reports it
            self.transport.interrupt()

    # -- reader thread --------------------------------------------------------
    def _read(self) -> None:
        reason = "the link was closed"
        try:
            reason = self._read_frames()
        except OSError as error:
            reason = f"{type(error).__name__}: {error}" if self.state is LinkState.OPEN else reason
        except Exception as error:  # a bug must not kill the node silently
            reason = f"unexpected {type(error).__name__}: {error}"
            self.owner.log.exception("Link to %s failed", self.label)
        finally:
            if self.state is LinkState.CLOSING:
                self._writer.join(self.flush_timeout_s)  # let queued frames go out
            self.abort()
            self._writer.join(self.flush_timeout_s)
            self.transport.close()
            self._closed.set()
            self.owner.link_closed(self, reason)

    def _read_frames(self) -> str:
        decoder = FrameDecoder()
        while True:
            data = self.transport.receive()
            if data is None:  # nothing for a while (pipes poll)
                if self.state is not LinkState.OPEN:
                    return "the link was closed"
                continue
            if not data:
                if decoder.pending_bytes():
                    self._bad_frame(
                        WireFormatError(
                            "the connection ended in the middle of a frame "
                            f"({decoder.pending_bytes()} bytes of it arrived)"
                        )
                    )
                return "the peer closed the connection"
            decoder.feed(data)
            pages: List[Page] = []
            try:
                body = decoder.next_frame()
                while body is not None:
                    self._decode_into(body, pages)
                    body = decoder.next_frame()
            except WireFormatError as error:  # a bad length: the stream is lost
                self._bad_frame(error, resetting=True)
                self.owner.deliver(self, pages)
                return f"reset after a bad frame ({error})"
            if pages:
                self.owner.deliver(self, pages)

    def _decode_into(self, body: bytes, pages: List[Page]) -> None:
        try:
            message = decode_body(body)
        except WireFormatError as error:
            self._bad_frame(error)
            return
        if isinstance(message, Hello):
            self.peer_role = message.role
            self.owner.on_hello(self)
        else:
            pages.append(message)

    def _bad_frame(self, error: WireFormatError, resetting: bool = False) -> None:
        self.bad_frames += 1
        repeats: Optional[RepeatFilter] = getattr(self, "_bad_frame_repeats", None)
        if repeats is None:  # made on the first bad frame: most links never see one
            repeats = self._bad_frame_repeats = RepeatFilter(
                self.owner.log, first=_SHOWN_BAD_FRAMES
            )
        what = "reset the connection" if resetting else "dropped the frame"
        count = self.bad_frames
        more = f"; {count} bad frames from this peer so far" if count > 1 else ""
        message = "Bad frame from %s: %s (%s; the node keeps running%s; see docs/wire-format.md)"
        args = (self.label, error, what, more)
        if resetting:  # the last word on this connection: always said, with the count
            self.owner.log.warning(message, *args)
            repeats.flush()
            return
        what = f"Bad frames from {self.label}"
        repeats.report("bad frame", what, logging.WARNING, message, *args)


class CommsLoop(ThreadLoop):
    """Base of the comms components: forwards pages by key over its links.

    Subclasses open links (``open_link``) from ``begin()`` or ``loop()``:
    a sockets server per accepted client, a sockets client per connection,
    a pipe loop once. Pages stored under ``keys`` go to every open link,
    except back to the link they came from or to the node they came from.

    Example::

        SocketsPair(("localhost", 9000)).client(["controller_data"])  # builds one

    Attributes:
        keys: the data keys forwarded to peers.
        links: the links not yet closed (read-only tuple, replaced on change).
    """

    def __init__(
        self,
        factory: AbstractFactory,
        parent: AbstractNode,
        name: ComponentName,
        keys: Sequence[DataKey],
        max_backlog_bytes: int = DEFAULT_MAX_BACKLOG_BYTES,
    ) -> None:
        super().__init__(factory, parent, name)
        self.keys: Tuple[DataKey, ...] = tuple(keys)
        self.max_backlog_bytes = max_backlog_bytes
        self.links: Tuple[Link, ...] = ()
        self._links_lock = threading.Lock()
        self._started: List[Link] = []  # every link whose threads may still run
        self._forwarded = frozenset(self.keys)
        # Pages a link delivered under a forwarded key, until forward_page sees
        # them: {id(page): (page, link)} so they are not sent back to that link.
        self._arrived: Dict[int, Tuple[Page, Link]] = {}
        self._unsent_reported = False
        self._unsendable_reported: Set[Tuple[DataKey, type]] = set()
        self._backlog_reported: Set[int] = set()
        self.task_handlers = {(TaskType.store_page, key): self.forward_page for key in self.keys}

    # -- node thread: sending -------------------------------------------------
    def forward_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Send the page just stored to every open link it did not come from."""
        page = task.val_list[0] if task.val_list else None
        if not isinstance(page, Page):
            return None  # the node core has already reported the bad task
        arrived = self._arrived.pop(id(page), None)
        source = arrived[1] if arrived is not None and arrived[0] is page else None
        targets = [
            link
            for link in self.links
            if link is not source and link.state is LinkState.OPEN and link.peer_role != page.origin
        ]
        if not targets:
            if source is None and not any(link.state is LinkState.OPEN for link in self.links):
                self._report_unsent(page)
            return None
        try:
            frame = encode_page(page)
        except NotSerializableError as error:
            self._report_unsendable(page, error)
            return None
        now = self._node_is_nearly_idle()
        for link in targets:
            if not link.send(frame, now) and link.state is LinkState.OPEN:
                self._report_backlog(link, page)
        return None

    def _node_is_nearly_idle(self) -> bool:
        # A long task queue means more pages are probably coming: let the
        # writer thread batch them into few large writes. Otherwise send now.
        queue = getattr(self.parent, "queue", None)
        return queue is None or len(queue) < _BUSY_QUEUE_LENGTH

    def _report_unsent(self, page: Page) -> None:
        if not self._unsent_reported:
            self._unsent_reported = True
            self.info(
                "No peer is connected, so the page under %r (and any others stored "
                "before a peer connects) is not sent. Pages are sent live, never late.",
                page.key,
            )

    def _report_unsendable(self, page: Page, error: NotSerializableError) -> None:
        kind = (page.key, type(page.data))
        if kind not in self._unsendable_reported:
            self._unsendable_reported.add(kind)
            self.err("%s The page was dropped; the node keeps running.", error)

    def _report_backlog(self, link: Link, page: Page) -> None:
        if id(link) not in self._backlog_reported:
            self._backlog_reported.add(id(link))
            self.warn(
                "%s is not keeping up: %d MiB of pages wait to be sent to it, so new "
                "pages (first %r) are dropped until it catches up. Store pages less "
                "often, or check the network.",
                link.label,
                self.max_backlog_bytes // (1024 * 1024),
                page.key,
            )

    # -- link threads: receiving ----------------------------------------------
    def deliver(self, link: Link, pages: List[Page]) -> None:
        """Store pages a link received (called on the link's reader thread)."""
        if not pages:
            return
        batch: List[Task] = []
        for page in pages:
            if page.key in self._forwarded:
                self._arrived[id(page)] = (page, link)
            batch.append(Task(TaskType.store_page, page.key, [page]))
        self.schedule(batch)

    # -- opening and closing links --------------------------------------------
    def open_link(self, transport: Transport) -> Link:
        """Start a link over ``transport`` and start forwarding pages to it."""
        link = Link(self, transport)
        with self._links_lock:
            self.links = (*self.links, link)
            self._started = [old for old in self._started if old.is_alive()] + [link]
        self._unsent_reported = False
        link.start()
        self.schedule(tasks.event(COMMS_CONNECTED, [self.name, transport.peer]))
        return link

    def link_closed(self, link: Link, reason: str) -> None:
        """A link has closed (called on its reader thread); log it once."""
        with self._links_lock:
            self.links = tuple(other for other in self.links if other is not link)
        self._backlog_reported.discard(id(link))
        if not self.is_terminated():
            self.on_link_lost(link, reason)
            self.schedule(tasks.event(COMMS_DISCONNECTED, [self.name, link.transport.peer]))

    def on_hello(self, link: Link) -> None:
        """The peer said which node it is (called on the link's reader thread)."""
        self.info("Linked to node %r at %s", link.peer_role, link.transport.peer)

    def on_link_lost(self, link: Link, reason: str) -> None:
        """Log that the peer went away (subclasses say what happens next)."""
        self.warn("Lost the link to %s: %s.", link.label, reason)

    # -- shutdown -------------------------------------------------------------
    def halt(self) -> None:
        """Flush and close every link (the node is stopping)."""
        for link in self.links:
            link.close()

    def terminate(self) -> None:
        """Wait (bounded) for links to finish closing, then force the rest."""
        deadline = time.monotonic() + Link.flush_timeout_s
        for link in self.links:
            if not link.wait_closed(max(0.0, deadline - time.monotonic())):
                link.abort()
        with self._links_lock:
            started = list(self._started)
        for link in started:  # closed links too: their threads may be finishing
            link.join(max(0.1, deadline - time.monotonic()))
