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
from typing import Any, Deque, Dict, List, Optional, Protocol, Sequence, Set, Tuple, Union

from snr.core import ThreadLoop, tasks
from snr.core.logs import LossReport, RepeatFilter
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
from snr.std_mods.comms.wire import (
    FrameDecoder,
    Hello,
    decode_body,
    encode_beat,
    encode_hello,
    encode_page,
)

__all__ = [
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "DEFAULT_DEAD_AFTER_S",
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

DEFAULT_MAX_BACKLOG_BYTES = 8 * 1024 * 1024
"""How many bytes of frames may wait for one slow peer before pages are dropped (8 MiB)."""

DEFAULT_DEAD_AFTER_S = 4.0
"""Seconds of silence after which a peer that promised beats counts as lost."""

Keys = Union[DataKey, Sequence[DataKey], None]
"""What a comms factory takes as ``keys``: one data key, a list of them, or None."""

_MAX_CHUNK_BYTES = 1024 * 1024  # the writer joins queued frames into chunks up to this size
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


_Entry = List[Any]  # [data key or None, frame or None once superseded]


class Outbox:
    """Frames waiting to be written to one peer, in the order they were queued; bounded.

    ``put`` runs on the node's thread. With ``now=True`` and nothing waiting,
    it writes the frame straight away without blocking (no thread switch: the
    lowest latency). Otherwise, or when the OS buffer is full, the frame is
    queued and the link's writer thread sends everything queued in one call
    (the highest throughput when many pages come at once). Either way frames
    leave in the order they were put.

    At most ``max_bytes`` wait. When a new page would go over, the newest
    page still waiting under the same key is dropped in its favour (newest
    wins per key: a robot wants the latest reading, not an old one); if none
    waits under that key, the new page is dropped. Every drop is counted in
    ``dropped`` and ``dropped_by_key``.

    Example::

        outbox.put(frame, now=True, key="depth_m")   # "sent", "queued", "replaced" or "dropped"
    """

    def __init__(self, transport: Transport, max_bytes: int) -> None:
        self.transport = transport
        self.max_bytes = max_bytes
        self.dropped = 0
        self.dropped_by_key: Dict[DataKey, int] = {}
        self._entries: Deque[_Entry] = collections.deque()
        self._newest: Dict[DataKey, _Entry] = {}
        self._queued_bytes = 0
        self._live = 0  # entries not superseded
        self._writing = False  # the writer thread holds a chunk it is sending
        self._closed = False
        self._changed = threading.Condition(threading.Lock())

    def put(self, frame: bytes, now: bool = False, key: Optional[DataKey] = None) -> str:
        """Send (if ``now``) or queue ``frame``; says what happened.

        Returns ``"sent"``, ``"queued"``, ``"replaced"`` (an older page under
        ``key`` was dropped for it), ``"dropped"`` (the backlog is full) or
        ``"closed"``.
        """
        with self._changed:
            if self._closed:
                return "closed"
            if now and not self._live and not self._writing and self.transport.can_try_send:
                try:
                    sent = self.transport.try_send(frame)
                except OSError:  # full (BlockingIOError) or broken: the writer deals with it
                    sent = 0
                if sent == len(frame):
                    return "sent"
                if sent:  # the rest must go next, before anything else, whatever the cap
                    self._append(None, frame[sent:])
                    return "queued"
            outcome = "queued"
            if self._queued_bytes + len(frame) > self.max_bytes:
                older = self._newest.get(key) if key is not None else None
                if older is None:
                    self._count_drop(key)
                    return "dropped"
                self._queued_bytes -= len(older[1])
                older[1] = None
                self._live -= 1
                self._count_drop(key)
                outcome = "replaced"
            self._append(key, frame)
            return outcome

    def _append(self, key: Optional[DataKey], frame: bytes) -> None:
        entry: _Entry = [key, frame]
        self._entries.append(entry)
        if key is not None:
            self._newest[key] = entry
        self._queued_bytes += len(frame)
        self._live += 1
        self._changed.notify()

    def _count_drop(self, key: Optional[DataKey]) -> None:
        self.dropped += 1
        if key is not None:
            self.dropped_by_key[key] = self.dropped_by_key.get(key, 0) + 1

    def take(self, timeout_s: Optional[float] = None) -> Optional[bytes]:
        """For the writer: the next chunk of frames; None once closed and empty.

        Blocks (without using CPU) until there is something to send; returns
        ``b""`` if ``timeout_s`` passes first (time for a beat).
        """
        with self._changed:
            self._writing = False
            if not self._live:
                if self._closed:
                    return None
                self._changed.wait(timeout_s)
                if not self._live:
                    return None if self._closed else b""
            parts: List[bytes] = []
            size = 0
            entries = self._entries
            while entries and size < _MAX_CHUNK_BYTES:
                entry = entries.popleft()
                frame = entry[1]
                if frame is None:
                    continue  # superseded by a newer page under its key
                key = entry[0]
                if key is not None and self._newest.get(key) is entry:
                    del self._newest[key]
                parts.append(frame)
                size += len(frame)
            self._queued_bytes -= size
            self._live -= len(parts)
            self._writing = True
        return parts[0] if len(parts) == 1 else b"".join(parts)

    def close(self, discard: bool) -> None:
        """Accept no more frames; with ``discard``, forget those still waiting."""
        with self._changed:
            self._closed = True
            if discard:
                self._entries.clear()
                self._newest.clear()
                self._queued_bytes = 0
                self._live = 0
            self._changed.notify_all()

    @property
    def queued_bytes(self) -> int:
        """Bytes of frames waiting to be sent."""
        return self._queued_bytes

    def __len__(self) -> int:
        """How many frames wait to be sent."""
        return self._live


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
    length header arrives, the peer falls silent, or the link is aborted, it
    stops the writer, closes the transport and tells the `CommsLoop`.

    Liveness: both sides promise a sign of life in their hello (``beat_s``)
    and the writer sends a beat frame whenever it has sent nothing for that long.
    A peer that promised beats and is then not heard from for
    ``max(dead_after_s, 3 * its beat_s)`` is declared lost — also while pages
    flow the other way, which is when a Wi-Fi link usually dies — and the
    log says how many pages may have been lost with it.

    Example::

        link = Link(comms_loop, transport)
        link.start()
        link.send(encode_page(page), key=page.key)
        link.close()              # flush, then end the connection

    Attributes:
        pages_sent: pages handed to the transport or queued for it.
        pages_received: pages that arrived.
        went_silent: the link was closed because the peer fell silent.
        loss: the `LossReport` of pages dropped because the peer fell behind.
    """

    flush_timeout_s: float = 1.0

    def __init__(self, owner: CommsLoop, transport: Transport) -> None:
        self.owner = owner
        self.transport = transport
        self.peer_role: Optional[str] = None
        self.peer_beat_s: Optional[float] = None
        self.state = LinkState.OPEN
        self.bad_frames = 0
        self.went_silent = False
        self.pages_sent = 0
        self.pages_received = 0
        self.opened_at = time.monotonic()
        self.last_heard = self.opened_at
        self._heard_anything = False
        self._sent_when_heard = 0
        self.loss = LossReport(
            owner.log,
            f"pages for {transport.peer}",
            "the peer is not taking them as fast as they are stored "
            f"({owner.max_backlog_bytes // 1024:,} KiB wait to be sent; the newest page "
            "under each key is kept)",
        )
        self.outbox = Outbox(transport, owner.max_backlog_bytes)
        self.outbox.put(encode_hello(owner.parent.role, owner.beat_s), now=False)
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

    def send(self, frame: bytes, now: bool = True, key: Optional[DataKey] = None) -> bool:
        """Send or queue a page's ``frame`` (node thread); False if it was dropped.

        A page that the full backlog cannot take, or a queued one it
        replaces, is counted and reported (at most once a second).
        """
        if self.state is not LinkState.OPEN:
            return False
        outcome = self.outbox.put(frame, now, key)
        if outcome in ("sent", "queued"):
            self.pages_sent += 1
            return True
        if outcome == "replaced":
            self.pages_sent += 1
            self.loss.dropped()
            return True
        if outcome == "dropped":
            self.loss.dropped()
        return False

    def _check_recovered(self) -> None:
        # Writer thread, after each write and each quiet beat interval: the
        # peer has caught up once everything queued went out and nothing was
        # dropped for a second.
        if self.loss.dropping and not len(self.outbox):
            self.loss.recovered(quiet_s=1.0)

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

    def stats(self) -> Dict[str, Any]:
        """The link's counters, e.g. for the console's ``stats`` command.

        Example::

            link.stats()["dropped"]   # pages dropped because the peer fell behind
        """
        return {
            "peer": self.label,
            "state": self.state.value,
            "pages_sent": self.pages_sent,
            "pages_received": self.pages_received,
            "dropped": self.outbox.dropped,
            "dropped_by_key": dict(self.outbox.dropped_by_key),
            "waiting_frames": len(self.outbox),
            "waiting_bytes": self.outbox.queued_bytes,
            "bad_frames": self.bad_frames,
            "heard_s_ago": round(time.monotonic() - self.last_heard, 3),
        }

    # -- writer thread --------------------------------------------------------
    def _write(self) -> None:
        beat_s = self.owner.beat_s
        try:
            chunk = self.outbox.take(beat_s)
            while chunk is not None:
                if chunk:
                    self.transport.send_all(chunk)
                elif self.peer_beat_s is not None:  # quiet for beat_s: a sign of life
                    self.transport.send_all(encode_beat())
                self._check_recovered()
                chunk = self.outbox.take(beat_s)
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
            if data is None:  # nothing for a while
                if self.state is not LinkState.OPEN:
                    return "the link was closed"
                silence = self._silence()
                if silence is not None:
                    return silence
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
            self.last_heard = time.monotonic()
            self._heard_anything = True
            self._sent_when_heard = self.pages_sent
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
                self.pages_received += len(pages)
                self.owner.deliver(self, pages)

    def _silence(self) -> Optional[str]:
        """Why the link is lost if the peer has been quiet too long, else None."""
        quiet_s = time.monotonic() - self.last_heard
        if not self._heard_anything and quiet_s > self.owner.hello_timeout_s:
            return (
                f"it sent nothing, not even a hello, within {self.owner.hello_timeout_s:g} s "
                "of connecting"
            )
        if self.peer_beat_s is None:
            return None  # a peer that promised no beats may be quiet for ever
        limit = max(self.owner.dead_after_s, 3 * self.peer_beat_s)
        if quiet_s <= limit:
            return None
        at_risk = self.pages_sent - self._sent_when_heard
        self.went_silent = True
        return (
            f"nothing heard from it for {quiet_s:.1f} s, though it promised a sign of life "
            f"every {self.peer_beat_s:g} s (the network path is gone, or the peer froze); "
            f"{at_risk} pages sent since it was last heard from may be lost"
        )

    def _decode_into(self, body: bytes, pages: List[Page]) -> None:
        try:
            message = decode_body(body)
        except WireFormatError as error:
            self._bad_frame(error)
            return
        if isinstance(message, Page):
            pages.append(message)
        elif isinstance(message, Hello):
            self.peer_role = message.role
            self.peer_beat_s = message.beat_s
            self.owner.on_hello(self)

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
        dead_after_s: a peer that promised beats and is silent this long is lost.
        beat_s: how often a quiet link sends a beat (a quarter of ``dead_after_s``,
            at most 1 s); promised to the peer in the hello.
    """

    hello_timeout_s: float = 5.0
    """A connection that sends nothing at all for this long is closed."""

    def __init__(
        self,
        factory: AbstractFactory,
        parent: AbstractNode,
        name: ComponentName,
        keys: Sequence[DataKey],
        max_backlog_bytes: int = DEFAULT_MAX_BACKLOG_BYTES,
        dead_after_s: float = DEFAULT_DEAD_AFTER_S,
    ) -> None:
        super().__init__(factory, parent, name)
        if not dead_after_s > 0:
            raise ConfigError(
                f"{type(self).__name__} {name!r} got dead_after_s={dead_after_s!r}; give the "
                "seconds of silence after which a peer counts as lost, e.g. 4.0."
            )
        self.keys: Tuple[DataKey, ...] = tuple(keys)
        self.max_backlog_bytes = max_backlog_bytes
        self.dead_after_s = dead_after_s
        self.beat_s = min(1.0, dead_after_s / 4)
        self.links: Tuple[Link, ...] = ()
        self._links_lock = threading.Lock()
        self._started: List[Link] = []  # every link whose threads may still run
        self._forwarded = frozenset(self.keys)
        # Pages a link delivered under a forwarded key, until forward_page sees
        # them: {id(page): (page, link)} so they are not sent back to that link.
        self._arrived: Dict[int, Tuple[Page, Link]] = {}
        self._unsent_reported = False
        self._unsendable_reported: Set[Tuple[DataKey, type]] = set()
        self.task_handlers = {(TaskType.store_page, key): self.forward_page for key in self.keys}
        if parent.profiler is not None:  # the profile also tells what was sent and dropped
            parent.profiler.add_report(name, self.stats_text)

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
        for link in targets:
            link.send(frame, True, page.key)  # a drop is counted and reported by the link
        return None

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

    # -- link threads: receiving ----------------------------------------------
    def deliver(self, link: Link, pages: List[Page]) -> None:
        """Store pages a link received (called on the link's reader thread).

        While the node's queue is over its high-water mark the reader waits
        here instead of reading on: the bytes stay in the OS, TCP slows the
        sender, and nothing is lost on this side.
        """
        if not pages:
            return
        while not self.parent.wait_for_room(0.25):
            if link.state is not LinkState.OPEN:
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
        if not self.is_terminated():
            self.on_link_lost(link, reason)
            self.schedule(tasks.event(COMMS_DISCONNECTED, [self.name, link.transport.peer]))

    def on_hello(self, link: Link) -> None:
        """The peer said which node it is (called on the link's reader thread)."""
        self.info("Linked to node %r at %s", link.peer_role, link.transport.peer)

    def on_link_lost(self, link: Link, reason: str) -> None:
        """Log that the peer went away (subclasses say what happens next)."""
        self.warn("Lost the link to %s: %s.", link.label, reason)

    def stats(self) -> List[Dict[str, Any]]:
        """The counters of every open link (see `Link.stats`).

        Example::

            for link in comms.stats():
                print(link["peer"], link["dropped"], link["dropped_by_key"])
        """
        return [link.stats() for link in self.links]

    def stats_text(self) -> str:
        """`stats` as lines for people: the console's ``stats`` and the profiler's dump.

        Example::

            print(comms.stats_text())
            # 1 link
            #   'receiver' at 127.0.0.1:9000 (open): sent 1,204, received 0, dropped 0, ...
        """
        links = self.stats()
        lines = [f"{len(links)} link{'s' if len(links) != 1 else ''}"]
        for link in links:
            by_key = ", ".join(f"{key}: {n}" for key, n in link["dropped_by_key"].items())
            lines.append(
                f"  {link['peer']} ({link['state']}): sent {link['pages_sent']:,}, "
                f"received {link['pages_received']:,}, dropped {link['dropped']:,}"
                f"{f' ({by_key})' if by_key else ''}, waiting {link['waiting_frames']} "
                f"frames, bad frames {link['bad_frames']}, "
                f"heard {link['heard_s_ago']:.1f} s ago"
            )
        return "\n".join(lines)

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
