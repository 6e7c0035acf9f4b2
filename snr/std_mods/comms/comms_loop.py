"""`CommsLoop`, `Link`, `Outbox`: how a node forwards pages by key to its peers.

A `CommsLoop` (thesis 6.4.1) forwards every page stored under its keys to
each open `Link` (one connection to one peer, over a `Transport` of
``io_loop.py``) and stores every page a link receives, with its origin and
time. A link queues frames in its `Outbox` and has no thread of its own: the
node's one `IOLoop` reads and writes it. `SocketsServerLoop`,
`SocketsClientLoop` and `PipeLoop` differ only in how they open their links
(a page's whole trip: docs/design.md).

Example::

    class MyLoop(CommsLoop):
        def begin(self) -> None:
            self.open_link(my_transport)

        def loop(self) -> None:
            self.wait_s(0.5)
"""

from __future__ import annotations

import collections
import enum
import functools
import logging
import selectors
import threading
import time
from typing import Any, Callable, Deque, Dict, List, Optional, Sequence, Set, Tuple, Union

from snr.core import Node, ThreadLoop, tasks
from snr.core.logs import LossReport
from snr.prelude import (
    AbstractFactory,
    AbstractNode,
    CommsError,
    ComponentName,
    ConfigError,
    DataKey,
    NotSerializableError,
    Page,
    SomeTasks,
    Task,
    TaskHandler,
    TaskId,
    TaskType,
    WireFormatError,
)
from snr.std_mods.codec import (
    Beat,
    Bye,
    FrameDecoder,
    Hello,
    Message,
    Proof,
    decode_body,
    encode_beat,
    encode_bye,
    encode_page,
)
from snr.std_mods.comms.handshake import Handshake, Refused
from snr.std_mods.comms.io_loop import IOLoop, IOTimer, Transport, unread_bytes
from snr.std_mods.comms.rate_limited_log import RateLimitedLog

__all__ = [
    "CLOSED",
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "DEFAULT_DEAD_AFTER_S",
    "DEFAULT_MAX_BACKLOG_BYTES",
    "FIRST",
    "QUEUED",
    "SENT",
    "CommsLoop",
    "Keys",
    "Link",
    "LinkState",
    "Outbox",
    "Write",
    "normalize_keys",
    "shown_role",
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

_STORE_PAGE = TaskType.store_page
_PAGE_TASKS = (_STORE_PAGE, TaskType.process_data)
_NEWS_TICK_S = 0.5  # while news is counted, how often the counts are looked at
_MAX_REFUSED_NOTED = 10_000  # refused peers remembered (so each is logged once)

Keys = Union[DataKey, Sequence[DataKey], None]
"""What a comms factory takes as ``keys``: one data key, a list of them, or None."""


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


class CommsLoop(ThreadLoop):
    """Base of the comms components: forwards the pages stored under ``keys`` over its links.

    Subclasses open links (``open_link``) from ``begin()`` or ``loop()``. A
    page goes to every open link but the one it came from and its origin's.

    Example::

        SocketsPair(("localhost", 9000)).client(["controller_data"])  # builds one

    Attributes:
        keys: the data keys forwarded to peers.
        links: the links not yet closed (read-only tuple, replaced on change).
        closed_totals: the counters of the closed links, added up.
        dead_after_s: a peer that promised beats and is silent this long is lost.
        beat_s: how often a quiet link sends a beat (a quarter of
            ``dead_after_s``, at most 1 s); promised in the hello.
    """

    hello_timeout_s: float = 5.0
    """A connection that sends no well-formed frame (not even a hello) for this long is closed."""

    recovered_after_s: float = 1.0
    """After drops, a link logs "Recovered" once nothing was dropped for this long."""

    checks_keys_per_link = True
    """In DEBUG mode its keys are checked once a link is up (`check_link`), not at start."""

    side: str = "pipe"
    """Which end of its links it is: ``"server"``, ``"client"`` or ``"pipe"`` (in the proofs)."""

    peer_noun: str = "peer"
    """What its log lines call the other end, e.g. ``"client"``."""

    system: Optional[str] = None
    """The system its hellos name; peers of another (or none) are refused. None: no check."""

    secret: Optional[bytes] = None
    """The secret its links prove and ask peers to prove; None: no authentication."""

    decode_message = staticmethod(decode_body)  # a function of the body alone, not a method
    """How its links read a frame's body: `decode_body`; the pipe accepts 2021 pages too.

    Example::

        comms.decode_message(b'{"v":1,"kind":"beat"}')   # Beat()
    """

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
        self.news = RateLimitedLog(self.log, burst=20, window_s=10.0)
        self.bad_frame_news = RateLimitedLog(self.log, burst=5, window_s=5.0)
        self.refusal_news = RateLimitedLog(self.log, burst=5, window_s=5.0)
        self._news_lock = threading.Lock()
        self._news_ticking = False  # the I/O thread says the counts (see say)
        self.closed_totals: Dict[str, int] = dict.fromkeys(
            ("links", "pages_sent", "pages_received", "dropped", "bad_frames", "refused"), 0
        )
        # (peer's host, its role, why) -> how many times it was refused: said once each
        self.refused_peers: Dict[Tuple[str, str, str], int] = {}
        self.io_loop: Optional[IOLoop] = None  # the node's, while this component runs
        self._links_lock = threading.Lock()
        self._forwarded = frozenset(self.keys)
        # Pages a link delivered under a forwarded key, not to be sent back to it.
        self._arrived: Dict[int, Tuple[Page, Link]] = {}
        self._unsent_reported = False
        self._unsendable_reported: Set[Tuple[DataKey, type]] = set()
        self.task_handlers = {(_STORE_PAGE, key): self.forward_page for key in self.keys}
        self.burst_handlers = {(_STORE_PAGE, key): self.forward_burst for key in self.keys}
        if parent.profiler is not None:
            parent.profiler.add_report(name, self.stats_text)

    def forward_burst(self, run: List[Task]) -> SomeTasks:
        """`forward_page` for a run of stored pages under one key, queued in one go.

        With one open link and no received page to keep from echoing back
        (the usual pair), the frames go to its outbox together; else page by page.

        Example (the node calls it; a test may too)::

            comms.forward_burst([tasks.store_page(page) for page in pages])
        """
        links = self.links
        if len(links) != 1 or self._arrived or links[0].state is not _OPEN:
            for task in run:
                self.forward_page(task, (_STORE_PAGE, task.name))
            return None
        peer = links[0].peer_role
        frames: List[bytes] = []
        for task in run:
            page = task.page()
            if page is not None and page.origin != peer:  # (None: the node core said so)
                try:
                    frames.append(encode_page(page))
                except NotSerializableError as error:
                    self._report_unsendable(page, error)
        if frames:
            links[0].send_burst(frames, run[0].name)
        return None

    def forward_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Send the page just stored to every open link it did not come from, encoded once.

        Example::

            comms.forward_page(tasks.store_page(page), (TaskType.store_page, "depth"))
        """
        page = task.page()
        if page is None:
            return None  # the node core has already reported the bad task
        source = None
        if self._arrived:  # a page from a link, under a key this node forwards
            arrived = self._arrived.pop(id(page), None)
            if arrived is not None and arrived[0] is page:
                source = arrived[1]
        origin = page.origin
        frame = None
        for link in self.links:
            if link is source or link.state is not _OPEN or link.peer_role == origin:
                continue  # no echo: not to where it came from, nor to its origin
            if frame is None:
                try:
                    frame = encode_page(page)
                except NotSerializableError as error:
                    self._report_unsendable(page, error)
                    return None
            link.send(frame, page.key)  # a drop is counted and reported by the link
        if (
            frame is None
            and source is None
            and not self._unsent_reported
            and not any(link.state is _OPEN for link in self.links)
        ):
            self._unsent_reported = True
            self.info(
                "No peer is connected, so the page under %r (and any others stored "
                "before a peer connects) is not sent. Pages are sent live, never late.",
                page.key,
            )
        return None

    def _report_unsendable(self, page: Page, error: NotSerializableError) -> None:
        kind = (page.key, type(page.data))
        if kind not in self._unsendable_reported:
            self._unsendable_reported.add(kind)
            self.err("%s The page was dropped; the node keeps running.", error)

    def deliver(self, link: Link, pages: List[Page]) -> None:
        """Store pages a link received (on the thread that read them; the queue has room).

        Example (what a `Link` does with the pages of one read)::

            self.owner.deliver(self, pages)
        """
        forwarded = self._forwarded
        if forwarded:
            for page in pages:
                if page.key in forwarded:
                    self._arrived[id(page)] = (page, link)
        if len(pages) == 1:  # the usual read when pages come one at a time
            self.parent.schedule(Task(_STORE_PAGE, pages[0].key, pages))
        elif not link.io.in_loop_thread():  # the idle node's thread read them: one task
            self.schedule(tasks.store_pages(pages))
        else:  # the I/O thread: one task each, so the queue's high-water mark counts pages
            self.schedule([Task(_STORE_PAGE, page.key, [page]) for page in pages])

    def start_thread(self) -> None:
        """Acquire the node's I/O loop (links need it from ``begin()`` on), then start."""
        if self.io_loop is None:
            self.io_loop = IOLoop.acquire(self.parent)
        try:
            super().start_thread()
        except BaseException:
            self._release_io_loop()
            raise

    def _release_io_loop(self) -> None:
        with self._links_lock:
            io, self.io_loop = self.io_loop, None
        if io is not None:
            io.release()

    def open_link(self, transport: Transport) -> Link:
        """Start a link over ``transport`` and start forwarding pages to it.

        Raises:
            CommsError: the component is not running (the transport is closed).
        """
        with self._links_lock:
            try:
                link = Link(self, transport)
            except CommsError:
                transport.close()
                raise
            self.links = (*self.links, link)
        self._unsent_reported = False
        link.start()
        if not link.handshake.needed:  # pages may pass at once (else: at the hello)
            self.announce(link)
        return link

    def announce(self, link: Link) -> None:
        """The link is open for pages (its handshake is done): schedule ``COMMS_CONNECTED``."""
        self.schedule(tasks.event(COMMS_CONNECTED, [self.name, link.transport.peer]))

    def on_refused(self, link: Link, refusal: Refused) -> None:
        """A peer was refused (I/O thread): log it once per peer (host, role, why), count it.

        Example (what the log says)::

            Refused client 'topside' at 10.0.0.7:51234 (this node: 'urov', system 'team7'):
            it belongs to system 'team3', ...
        """
        key = (link.transport.peer.rsplit(":", 1)[0], link.peer_role or "", refusal.kind)
        with self._links_lock:
            seen = self.refused_peers.get(key, 0)
            if seen == 0 and len(self.refused_peers) >= _MAX_REFUSED_NOTED:
                self.refused_peers.clear()  # a flood of peers: remember the newest ones
            self.refused_peers[key] = seen + 1
        if not seen:
            self.say(
                "Peers refused",
                logging.WARNING,
                "Refused %s %s at %s (this node: %r, system %r): %s. The connection was "
                "closed; nothing it sent was stored.",
                self.peer_noun,
                link.peer_name if link.peer_role else "(no hello yet)",
                link.transport.peer,
                self.parent.role,
                self.system,
                refusal.reason,
                news=self.refusal_news,
            )

    def link_closed(self, link: Link, reason: str) -> None:
        """A link has closed (called on the I/O thread); log it once."""
        with self._links_lock:
            self.links = tuple(other for other in self.links if other is not link)
            totals = self.closed_totals
            totals["links"] += 1
            totals["pages_sent"] += link.pages_sent
            totals["pages_received"] += link.pages_received
            totals["dropped"] += link.outbox.dropped
            totals["bad_frames"] += link.bad_frames
            totals["refused"] += link.refusal is not None
        if link.refusal is None and not self.is_terminated():  # (refused: said by on_refused)
            self.on_link_lost(link, reason)
            if link.handshake.done:  # only a link that was open for pages is news to handlers
                self.schedule(tasks.event(COMMS_DISCONNECTED, [self.name, link.transport.peer]))

    def say(
        self, what: str, level: int, msg: str, *args: Any, news: Optional[RateLimitedLog] = None
    ) -> None:
        """Log news of links (connects, hellos, losses) in full, unless it comes in a flood.

        ``what`` names the kind of news: up to 20 lines of a kind in 10 s are
        logged in full, then they are counted and the count is logged every
        10 s (`RateLimitedLog`; ``news`` is another such log, e.g. the bad frames').

        Example::

            self.say("Links lost", logging.WARNING, "Lost the link to %s", link.label)
        """
        if (news or self.news).report(what, level, msg, *args):
            with self._news_lock:  # counted: the I/O thread says the counts later
                io = self.io_loop
                if self._news_ticking or io is None:
                    return
                self._news_ticking = True
            io.call_soon(lambda: io.call_later(_NEWS_TICK_S, self._tick_news))

    def _tick_news(self) -> None:
        """I/O thread: say what a flood left counted; again soon while news may be pending."""
        io = self.io_loop
        with self._news_lock:  # (say looks at _news_ticking under it, after counting)
            waiting = [news.tick() for news in (self.news, self.bad_frame_news, self.refusal_news)]
            self._news_ticking = io is not None and any(waiting)
        if io is not None and self._news_ticking:
            io.call_later(_NEWS_TICK_S, self._tick_news)

    def on_hello(self, link: Link) -> None:
        """The peer said which node it is (called on the node's I/O thread)."""
        self.say(
            "Links made",
            logging.INFO,
            "Linked to node %s at %s",
            link.peer_name,
            link.transport.peer,
        )

    def on_link_lost(self, link: Link, reason: str) -> None:
        """Log that the peer went away: a warning, unless it said goodbye (stopped in order)."""
        if link.peer_said_bye:
            self.say("Links ended", logging.INFO, "The link to %s ended: %s.", link.label, reason)
        else:
            self.say("Links lost", logging.WARNING, "Lost the link to %s: %s.", link.label, reason)

    def watch_link(self, link: Link) -> None:
        """In DEBUG mode, have `check_link` look at ``link``'s keys a while after its hello.

        The robot forwards ``"sensr_data"`` and the topside handles
        ``"sensor_data"``: nothing is shown and nothing is said (thesis listing
        5.1). So ``node.key_hints.link_s`` after a link's hello (I/O thread),
        the keys are compared with what was stored and received.

        Example::

            self.owner.watch_link(self)   # what a Link does when the peer's hello arrives
        """
        node, io = self.parent, self.io_loop
        if not isinstance(node, Node) or node.key_hints is None or io is None:
            return
        if link.keys_received is None:
            link.keys_received = set()  # from now on the link notes what arrives

        def ask() -> None:  # on the I/O thread: hand the check to the node's thread
            if not link.is_closed() and not self.is_terminated():
                check = functools.partial(self.check_link, link)
                self.schedule(tasks.event(tasks.CHECK_WIRING, [check]))

        io.call_later(node.key_hints.link_s, ask)

    def check_link(self, link: Link) -> None:
        """On the node's thread: report keys that should have crossed ``link`` by now.

        The keys received over every link to the same peer count together (listing
        5.1 has two); while one is younger than the delay, its own check comes later.

        Example::

            comms.check_link(link)   # see MissingKeyHints.check_link for the messages
        """
        node = self.parent
        if not isinstance(node, Node) or node.key_hints is None or link.is_closed():
            return
        if node.components.get(self.name) is not self:
            return  # removed or reloaded since
        hints = node.key_hints
        handled: List[Tuple[DataKey, TaskHandler]] = []
        peer_links: List[Link] = []
        for component in list(node.components.values()):
            if isinstance(component, CommsLoop):  # its keys are checked as sent, not wanted
                peer_links += [
                    other for other in component.links if other.peer_role == link.peer_role
                ]
                continue
            for task_id, handler in list(component.task_handlers.items()):
                if isinstance(task_id, tuple) and task_id[0] in _PAGE_TASKS:
                    handled.append((task_id[1], handler))
        now = time.monotonic()
        received: Set[DataKey] = set()
        for other in peer_links:
            if not other.is_closed() and now - other.opened_at < hints.link_s:
                handled = []  # a newer link to the same node: its own check comes later
            received.update(other.keys_received or ())
        places = sorted({other.transport.peer for other in peer_links} | {link.transport.peer})
        peer = f"node {link.peer_name} at {' and '.join(places)}"
        hints.check_link(repr(self.name), peer, self.keys, handled, node.datastore, received)

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
        closed = dict(self.closed_totals)
        if closed["links"]:
            lines.append(
                f"  {closed['links']:,} closed: sent {closed['pages_sent']:,}, received "
                f"{closed['pages_received']:,}, dropped {closed['dropped']:,}, "
                f"bad frames {closed['bad_frames']:,}"
            )
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

    def halt(self) -> None:
        """Flush and close every link (the node is stopping)."""
        for link in self.links:
            link.close()

    def terminate(self) -> None:
        """Wait (bounded) for links to finish closing, force the rest, give back the I/O loop."""
        deadline = time.monotonic() + Link.flush_timeout_s
        for link in self.links:
            if not link.wait_closed(max(0.0, deadline - time.monotonic())):
                link.abort()
        for link in self.links:  # aborted ones end on the I/O thread's next pass
            link.wait_closed(max(0.1, deadline - time.monotonic()))
        self._release_io_loop()
        for news in (self.news, self.bad_frame_news, self.refusal_news):
            news.flush()  # what a flood of connections or bad frames left unsaid


# -- the outbox: frames waiting for one peer

SENT = "sent"
"""`Outbox.put`: written to the peer at once."""

FIRST = "first"
"""`Outbox.put`: queued into an empty outbox (the caller wakes its writer)."""

QUEUED = "queued"
"""`Outbox.put`: queued behind other frames (a writer is on its way)."""

CLOSED = "closed"
"""`Outbox.put`: not taken, the outbox is closed."""

Write = Callable[[bytes], int]
"""Writes what fits now and says how many bytes went (``socket.send``); BlockingIOError if none."""

_MAX_CHUNK_BYTES = 1024 * 1024  # write_to joins waiting frames up to this size: one system call


class _Entry:
    """One waiting frame: its key (None: never pushed out) and its bytes (None once gone)."""

    __slots__ = ("data", "key")

    def __init__(self, key: Optional[DataKey], data: Optional[bytes]) -> None:
        self.key = key
        self.data = data


class Outbox:
    """Frames waiting to be written to one peer, oldest first; bounded, newest per key wins.

    Every link queues here: TCP, pipe and serial (docs/design.md, "One outbox
    for every link"). A frame that does not fit pushes out the oldest frame
    waiting under its own key, else the oldest of the key with the most
    waiting; frames with no key are never pushed out. ``put`` never blocks.
    Every change and write happens under one lock, so frames leave in order
    and whole, from any thread.

    Example::

        outbox = Outbox(1024, LossReport(log, "lines", "the board is not reading"))
        if outbox.put(frame, key="depth_m", write=sock.send) == FIRST:
            ...  # ask the writer to call outbox.write_to(sock.send)

    Attributes:
        max_bytes: how many bytes of frames may wait.
        loss: where drops are reported (the numbers, at most once a second).
        dropped: frames pushed out so far.
        dropped_by_key: the same, per data key.
        last_sent_at: when bytes last went to the peer (``time.monotonic()``).
    """

    def __init__(self, max_bytes: int, loss: LossReport) -> None:
        self.max_bytes = max_bytes
        self.loss = loss
        self.dropped = 0
        self.dropped_by_key: Dict[DataKey, int] = {}
        self.last_sent_at = time.monotonic()
        self.closed = False
        self._entries: Deque[_Entry] = collections.deque()  # pushed-out ones stay, data None
        self._by_key: Dict[DataKey, Deque[_Entry]] = {}  # waiting ones only, oldest first
        self._live = 0  # entries still waiting
        self._bytes = 0
        self._lock = threading.Lock()
        self._ready = threading.Condition(self._lock)  # for a writer thread in ``take``

    def put(
        self, frame: bytes, key: Optional[DataKey] = None, write: Optional[Write] = None
    ) -> str:
        """Queue ``frame``, or with ``write`` and nothing waiting, write it at once.

        Returns `SENT`, `FIRST` (queued into an empty outbox: wake the
        writer), `QUEUED` or `CLOSED`. The rest of a frame written in part
        waits first in line.

        Example::

            outbox.put(b"speed 1\\n", key="speed")   # "first"
        """
        with self._lock:
            if self.closed:
                return CLOSED
            if write is not None and not self._live:
                try:
                    sent = write(frame)
                except OSError:  # full (BlockingIOError) or broken: the writer finds out
                    sent = 0
                if sent:
                    self.last_sent_at = time.monotonic()
                    if sent == len(frame):
                        return SENT
                    frame, key = frame[sent:], None  # the rest, never pushed out
            return self._queue((frame,), key)

    def put_all(self, frames: List[bytes], key: DataKey) -> str:
        """`put` for a run of frames under ``key``, in order, with one lock; nothing is written.

        Example::

            outbox.put_all([encode_page(page) for page in pages], "depth")
        """
        with self._lock:
            return CLOSED if self.closed else self._queue(frames, key)

    def _queue(self, frames: Sequence[bytes], key: Optional[DataKey]) -> str:
        first = not self._live
        for frame in frames:
            if self._bytes + len(frame) > self.max_bytes:
                self._make_room(len(frame), key)
            entry = _Entry(key, frame)
            self._entries.append(entry)
            if key is not None:
                waiting = self._by_key.get(key)
                if waiting is None:
                    self._by_key[key] = collections.deque((entry,))
                else:
                    waiting.append(entry)
            self._live += 1
            self._bytes += len(frame)
        if first:
            self._ready.notify()  # for a writer thread waiting in take()
        return FIRST if first else QUEUED

    def put_first(self, frame: bytes) -> None:
        """Queue ``frame`` first in line, never to be pushed out (e.g. a header).

        Example::

            outbox.put_first(b'{"format":"snr-pages","version":1}\\n')
        """
        with self._lock:
            if not self.closed:
                self._entries.appendleft(_Entry(None, frame))
                self._live += 1
                self._bytes += len(frame)
                self._ready.notify()

    def _make_room(self, size: int, key: Optional[DataKey]) -> None:
        """Push out frames, oldest first, of ``key`` or else of the key with the most waiting."""
        pushed_out = 0
        by_key = self._by_key
        while by_key and self._bytes + size > self.max_bytes:
            victim_key = key if key in by_key else max(by_key, key=lambda k: len(by_key[k]))
            victims = by_key[victim_key]
            self._gone(victims.popleft())
            if not victims:
                del by_key[victim_key]
            pushed_out += 1
            self.dropped_by_key[victim_key] = self.dropped_by_key.get(victim_key, 0) + 1
        if pushed_out:
            self.dropped += pushed_out
            if len(self._entries) > 2 * self._live + 64:  # forget the pushed-out ones
                self._entries = collections.deque(e for e in self._entries if e.data is not None)
            self.loss.dropped(pushed_out)

    def _gone(self, entry: _Entry) -> None:  # written or pushed out
        if entry.data is not None:
            self._bytes -= len(entry.data)
            entry.data = None
            self._live -= 1

    def write_to(self, write: Write) -> bool:
        """Write what ``write`` takes now, many frames a call; True once nothing waits.

        Raises:
            OSError: the peer is gone (not BlockingIOError: a full buffer means "later").

        Example::

            outbox.write_to(sock.send)   # True: all written
        """
        with self._lock:
            while self._live:
                parts: List[bytes] = []
                size = 0
                for entry in self._entries:
                    if size >= _MAX_CHUNK_BYTES:
                        break
                    if entry.data is not None:
                        parts.append(entry.data)
                        size += len(entry.data)
                try:
                    sent = write(parts[0] if len(parts) == 1 else b"".join(parts))
                except BlockingIOError:
                    return False
                if sent:
                    self.last_sent_at = time.monotonic()
                self._consume(sent)
                if sent < size:
                    return False
            return True

    def _consume(self, sent: int) -> None:
        """Forget the first ``sent`` bytes of what waits (a frame written in part stays)."""
        entries = self._entries
        while entries:
            entry = entries[0]
            data = entry.data
            if data is not None:
                if sent < len(data):
                    if sent:  # the rest goes first next time; its key no longer pushes it out
                        entry.data = data[sent:]
                        self._bytes -= sent
                        self._unkey(entry)
                    return
                sent -= len(data)
                self._unkey(entry)
                self._gone(entry)
            entries.popleft()

    def _unkey(self, entry: _Entry) -> None:
        """``entry``, the oldest waiting of its key, leaves its key's line."""
        key = entry.key
        if key is not None:
            entry.key = None
            waiting = self._by_key.get(key)
            if waiting and waiting[0] is entry:
                waiting.popleft()
                if not waiting:
                    del self._by_key[key]

    def take(self, timeout_s: Optional[float] = None) -> Optional[bytes]:
        """For a writer thread: the oldest frame, waiting up to ``timeout_s`` (else None).

        Example::

            line = outbox.take(0.25)   # the serial link's writer thread
        """
        with self._lock:
            if not self._live and not self.closed:
                self._ready.wait(timeout_s)
            while self._entries:
                entry = self._entries.popleft()
                if entry.data is not None:
                    data = entry.data
                    self._unkey(entry)
                    self._gone(entry)
                    return data
            return None

    def close(self, discard: bool = False) -> int:
        """Take no more frames; with ``discard``, forget those waiting. How many were forgotten.

        Example::

            outbox.close(discard=True)   # 3
        """
        with self._lock:
            self.closed = True
            forgotten = self._live if discard else 0
            if discard:
                self._entries.clear()
                self._by_key.clear()
                self._live = self._bytes = 0
            self._ready.notify_all()
            return forgotten

    @property
    def queued_bytes(self) -> int:
        """Bytes of frames waiting to be written."""
        return self._bytes

    def __len__(self) -> int:
        """How many frames wait to be written."""
        return self._live


# -- the link: one connection to one peer

_WRITE_NOW_BYTES = 64 * 1024  # the node's thread writes a backlog this big before it goes idle
_BURST_S = 0.0002  # a frame this soon after the last send joins a batch for the I/O thread
_LATE_S = 0.001  # a look at a deadline comes just after it, so the limit has passed
_READ = selectors.EVENT_READ
_WRITE = selectors.EVENT_WRITE
_MAX_KEYS_NOTED = 1000  # DEBUG: how many received keys a link remembers for the hints
_PROGRESS_BYTES = 16 * 1024  # this much of a big frame still arriving is a sign of life
_SHOWN_ROLE_CHARS = 60
_BEAT = encode_beat()  # the one frame an idle link receives, once a beat interval


def shown_role(role: str) -> str:
    """A peer's role as log lines show it: quoted, cut short (a hostile hello may send megabytes).

    Example::

        shown_role("urov")        # "'urov'"
        shown_role("x" * 5000)    # "'xxx…xxx'… (5,000 characters)"
    """
    if len(role) <= _SHOWN_ROLE_CHARS:
        return repr(role)
    return f"{role[:_SHOWN_ROLE_CHARS]!r}… ({len(role):,} characters)"


class LinkState(enum.Enum):
    """Where a link is in its life: one value (the moves: docs/design.md, "A link's states").

    HELLO (the handshake: no page either way; a node with no system and no
    secret starts OPEN) → OPEN (pages, beats) → CLOSING (``close()``: writing
    what waits, then a bye) → DRAINING (half-closed, reading the last bytes)
    → CLOSED (transport closed, the `CommsLoop` told); ENDING when aborted or
    its end was found on the node's thread, finished on the I/O thread.

    Example::

        link.state is LinkState.OPEN
    """

    HELLO = "hello"
    OPEN = "open"
    CLOSING = "closing"
    DRAINING = "draining"
    ENDING = "ending"
    CLOSED = "closed"


_HELLO, _OPEN, _CLOSING = LinkState.HELLO, LinkState.OPEN, LinkState.CLOSING
_LIVE = (_HELLO, _OPEN)  # looked at on a clock (silence, beats, handshake)
_ENDED = (LinkState.ENDING, LinkState.CLOSED)  # no more reading or writing


class Link:
    """One live connection to one peer, served by the node's `IOLoop` (no thread of its own).

    The loop reads the transport, cuts frames and hands pages to the
    `CommsLoop`, and writes the outbox when the transport has room. The link
    beats when quiet, ends when the peer goes, falls silent (wire format 3.3)
    or sends a bad length, and reads nothing while the node's queue is over
    its high-water mark (``_held``; docs/design.md, "One I/O thread per node").

    Example::

        link = Link(comms_loop, transport)
        link.start()
        link.send(encode_page(page), key=page.key)
        link.close()              # flush, then end the connection

    Attributes:
        pages_sent: pages handed to the transport or queued for it.
        pages_received: pages that arrived.
        keys_received: in DEBUG mode, the keys of the pages that arrived (up to
            1,000, for `CommsLoop.check_link`); None otherwise.
        went_silent: the link was closed because the peer fell silent.
        refusal: why the peer was refused (`Refused`), or None.
        peer_said_bye: the peer sent a bye: the end that follows is orderly.
        loss: the `LossReport` of pages dropped because the peer fell behind.
    """

    flush_timeout_s: float = 1.0
    drain_s: float = 0.25  # after a graceful half-close, how long to read what still comes

    def __init__(self, owner: CommsLoop, transport: Transport) -> None:
        io = owner.io_loop
        if io is None:
            raise CommsError(
                f"Cannot open a link for comms component {owner.name!r}: it is not running "
                "(it was never started, or it has stopped)."
            )
        self.owner = owner
        self.io: IOLoop = io
        self.transport = transport
        self.peer_role: Optional[str] = None
        self.peer_beat_s: Optional[float] = None
        self.hello_at: Optional[float] = None  # when the handshake ended
        self.refusal: Optional[Refused] = None
        self.keys_received: Optional[Set[DataKey]] = None
        self.went_silent = self.peer_said_bye = False
        self._peer_takes_bye = False  # its hello said it understands a bye frame
        self.bad_frames = self.pages_sent = self.pages_received = 0
        self.opened_at = self.last_heard = self._progress_at = time.monotonic()
        self._heard_frame = False  # a well-formed frame has arrived (for the hello timeout)
        self._progress = 0  # bytes of a frame still arriving, since the peer was last heard
        self._sent_when_heard = 0
        self._unread_seen = 0  # while paused: bytes the OS held for us at the last look
        self._held: List[Page] = []  # read while the node was behind: read no more until stored
        self._timer: Optional[IOTimer] = None
        self._tick_s = owner.beat_s / 4  # beats are looked at on this grid (_next_look_s)
        self._answer_due = False  # the peer was heard since the last send: answer at once
        self._closed = threading.Event()
        self._decoder = FrameDecoder()
        self.loss = LossReport(
            owner.log,
            f"pages for {transport.peer}",
            "the peer is not taking them as fast as they are stored "
            f"({owner.max_backlog_bytes // 1024:,} KiB wait to be sent; the newest page "
            "under each key is kept)",
        )
        self.outbox = Outbox(owner.max_backlog_bytes, self.loss)
        self.handshake = Handshake(owner.parent.role, owner.side, owner.system, owner.secret)
        self.state = _HELLO if self.handshake.needed else _OPEN
        self.outbox.put(self.handshake.hello_frame(owner.beat_s))

    @property
    def label(self) -> str:
        """The peer for log lines: ``"'receiver' at 127.0.0.1:9000"``."""
        return (
            f"{self.peer_name} at {self.transport.peer}" if self.peer_role else self.transport.peer
        )

    @property
    def peer_name(self) -> str:
        """The peer's role for log lines (quoted, cut short), or ``"unknown"`` before its hello.

        Example::

            link.peer_name   # "'urov'"
        """
        return shown_role(self.peer_role) if self.peer_role else "unknown"

    def fileno(self) -> int:
        """The transport's file descriptor (what the I/O loop watches)."""
        return self.transport.fileno()

    def start(self) -> None:
        """Hand the link to the node's I/O loop, which sends the hello and starts reading."""
        self.io.call_soon(self._attach)

    def send(self, frame: bytes, key: Optional[DataKey] = None) -> bool:
        """Send or queue a page's ``frame`` (node thread); False if the link is not open.

        A frame right behind another waits to leave with it in one write; a
        frame after a pause goes at once, and so does a reply. When the
        outbox is full, older frames make room (see `Outbox`).

        Example::

            link.send(encode_page(page), key=page.key)
        """
        if self.state is not _OPEN:
            return False
        write = None
        if self._answer_due or time.monotonic() - self.outbox.last_sent_at >= _BURST_S:
            self._answer_due = False
            write = self.transport.send
        return self._queued(self.outbox.put(frame, key, write), 1)

    def send_burst(self, frames: List[bytes], key: DataKey) -> None:
        """`send` for the frames of a run of pages under ``key`` (node thread), queued together.

        Example::

            link.send_burst([encode_page(page) for page in pages], "depth")
        """
        if self.state is _OPEN:
            self._queued(self.outbox.put_all(frames, key), len(frames))

    def _queued(self, outcome: str, pages: int) -> bool:
        if outcome == CLOSED:
            return False
        self.pages_sent += pages
        if outcome == FIRST:
            self._wake_writer()
        elif self.outbox.queued_bytes >= _WRITE_NOW_BYTES and not self.io.events(self) & _WRITE:
            self.write_waiting()  # a long burst: do not wait for the node to go idle
        return True

    def close(self) -> None:
        """Send what is queued and a goodbye, then end the connection (graceful)."""
        if self.state is _HELLO:  # no page was sent yet: nothing to flush
            self.abort("the link was closed during its handshake")
        elif self.state is _OPEN:
            self.state = _CLOSING
            if self._peer_takes_bye:  # older peers never get a frame they do not know
                self._put_control(encode_bye())
            self.outbox.close()
            self.io.call_soon(self._end_writing)

    def abort(self, reason: str = "the link was closed") -> None:
        """End the connection now, dropping what is queued; ``reason`` goes in the log line."""
        if self.state not in _ENDED:
            self.state = LinkState.ENDING
            self.outbox.close(discard=True)
            self.io.call_soon(lambda: self._finish(reason))

    def is_closed(self) -> bool:
        """True once the link has ended and the transport is closed."""
        return self._closed.is_set()

    def wait_closed(self, timeout_s: Optional[float]) -> bool:
        """Wait up to ``timeout_s`` for the link to close; True if it has."""
        return self._closed.wait(timeout_s)

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

    # -- writing
    def _put_control(self, frame: bytes) -> None:
        """Queue a frame that is not a page (bye, beat, proof), never pushed out."""
        if self.outbox.put(frame, None, self.transport.send) == FIRST:
            self._wake_writer()

    def _wake_writer(self) -> None:
        if self.io.in_loop_thread():
            self._want_write()
        else:
            self.io.write_soon(self)

    def write_waiting(self) -> None:
        """Not the loop's thread: write queued frames now, without blocking (the loop, the rest)."""
        if not len(self.outbox):
            return
        try:
            done = self.outbox.write_to(self.transport.send)
        except OSError:  # broken: the loop's thread finds out and ends the link
            done = False
        if not done:
            self.io.call_soon(self._want_write)

    def _want_write(self) -> None:
        if self.state not in _ENDED and len(self.outbox):
            self.io.watch(self, self.io.events(self) | _WRITE)

    def on_writable(self) -> None:
        """I/O thread: write what is queued; stop watching for room once it is all out."""
        if self.state in _ENDED:
            return
        try:
            done = self.outbox.write_to(self.transport.send)
        except OSError as error:
            self._finish(f"{type(error).__name__}: {error}")
            return
        events = self.io.events(self)
        if not done:
            if not events & _WRITE:
                self.io.watch(self, events | _WRITE)
            return
        if events & _WRITE:
            self.io.watch(self, events & ~_WRITE)
        self._check_recovered()
        if self.state is _CLOSING:
            self._end_writing()

    # -- life: deadlines, beats, the end (I/O thread)
    def _attach(self) -> None:
        if self.state not in _ENDED:  # (else aborted before the loop got to it)
            self.io.watch(self, _READ)
            self._timer = self.io.call_later(self.owner.hello_timeout_s + _LATE_S, self._tick)
            self.on_writable()  # the hello goes at once

    def _end_writing(self) -> None:
        """CLOSING, everything sent: half-close, then read what still comes for a moment."""
        if self.state is not _CLOSING or len(self.outbox):
            return
        self.state = LinkState.DRAINING
        self.transport.end_writing()
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self.io.call_later(self.drain_s, lambda: self._finish("the link was closed"))

    def _tick(self) -> None:
        """At the link's next deadline: is the peer still there, and do we owe it a beat?"""
        self._timer = None
        if self.state in _ENDED:
            return
        # A paused reader judges silence only while nothing waits unread in the OS.
        silence = self._silence() if not self._held or self._note_unread() == 0 else None
        if silence is not None:
            self._finish(silence)
            return
        if self.state not in _LIVE:
            return
        if (
            self.state is _OPEN
            and self.peer_beat_s is not None
            and not len(self.outbox)
            # due before the next look on the beat grid: it goes now, a little early
            and time.monotonic() + self._tick_s >= self.outbox.last_sent_at + self.owner.beat_s
        ):
            self._put_control(_BEAT)  # quiet for beat_s: a sign of life
        self._check_recovered()
        self._timer = self.io.call_later(self._next_look_s(), self._tick)

    def _look_again(self) -> None:
        """Put the next look at the link's first deadline (they moved)."""
        if self._timer is not None and self.state in _LIVE:  # (else it is the drain's timer)
            self._timer.cancel()
            self._timer = self.io.call_later(self._next_look_s(), self._tick)

    def _next_look_s(self) -> float:
        """Seconds until the first deadline: a beat owed, a silence or hello limit.

        A quarter beat while pages are held or dropped (their counts move
        without a frame), or when the deadline has passed. The look for a
        beat is on a grid of quarter beats, the same for every link with the
        same beat: it comes at the last grid point before the beat is due (the beat
        goes a little early, never late), so one wake-up of the I/O thread
        beats for every quiet link at once (a server with 300 idle clients
        wakes about 4 times a second, not 300).
        """
        if self._held or self.loss.dropping:
            return self._tick_s
        limit_s = self.owner.hello_timeout_s
        due = []
        if not self._heard_frame:
            due.append(self._progress_at + limit_s)
        if self.state is _HELLO:
            due.append(self.opened_at + limit_s)
        if self.peer_beat_s is not None:
            grid = self._tick_s
            due.append((self.outbox.last_sent_at + self.owner.beat_s) // grid * grid)
            due.append(self.last_heard + max(self.owner.dead_after_s, 3 * self.peer_beat_s))
        wait_s = min(due) + _LATE_S - time.monotonic() if due else 0.0
        return wait_s if wait_s > 0 else self._tick_s

    def _check_recovered(self) -> None:
        if self.loss.dropping and not len(self.outbox):  # the peer has caught up
            self.loss.recovered(quiet_s=self.owner.recovered_after_s)

    def on_io_stop(self) -> None:
        """The I/O loop is stopping: end the link now."""
        self._finish("the node stopped")

    def _end(self, reason: str) -> None:
        """End the link: at once on the I/O loop's thread, else soon, by that thread."""
        if self.io.in_loop_thread():
            self._finish(reason)
        else:  # the node's thread, reading while idle
            self.abort(reason)

    def _finish(self, reason: str) -> None:
        """Any state → CLOSED, on the I/O thread: close the transport, tell the `CommsLoop`."""
        if self.state is LinkState.CLOSED:
            return
        with self.io.read_role():  # nobody reads the socket while it closes
            if self.peer_said_bye:
                reason = "it said goodbye (its node is stopping)"
            elif self.state in (_CLOSING, LinkState.DRAINING) and not self.went_silent:
                reason = reason if reason.startswith("the peer") else "the link was closed"
            self.state = LinkState.CLOSED
            self.outbox.close(discard=True)
            if self._timer is not None:
                self._timer.cancel()
            self.io.forget(self)
            # Unread bytes make the OS reset the connection on close, and the
            # peer may then lose what it has not read yet.
            try:
                for _ in range(16):
                    if not self.transport.recv_into(self.io.buffer):
                        break
            except OSError:
                pass
            try:
                self.transport.close()
            except OSError:
                pass
        self.loss.ended("the link ended")  # drops not yet in the log are said now
        self._closed.set()
        self.owner.link_closed(self, reason)

    # -- reading (whoever holds the I/O loop's read role)
    def on_readable(self) -> None:
        """Read what arrived and cut it into frames; `_on_frames` does the rest.

        The I/O thread calls it, or the idle node's thread; ending and pausing
        are the I/O thread's. A bad length header loses the stream: the frames
        before it count, then the connection is reset.
        """
        try:
            if self.state in _ENDED or self._held:
                return
            try:
                count = self.transport.recv_into(self.io.buffer)
            except BlockingIOError:
                return
            except OSError as error:
                self._end(f"{type(error).__name__}: {error}")
                return
            decoder = self._decoder
            if not count:
                if decoder.pending_bytes():
                    self._bad_frame(
                        WireFormatError(
                            "the connection ended in the middle of a frame "
                            f"({decoder.pending_bytes()} bytes of it arrived)"
                        )
                    )
                self._end("the peer closed the connection")
                return
            self._answer_due = True
            view = self.io.view[:count]
            if count == len(_BEAT) and view == _BEAT and not decoder.pending_bytes():
                self._heard_frame = True  # an idle link's lone beat: nothing to decode
                self._heard(time.monotonic())
                return
            bodies: List[bytes] = []
            try:
                decoder.cut_frames(view.tobytes(), bodies)
            except WireFormatError as error:  # a bad length: the stream is lost...
                self._on_frames(bodies)  # ...but the frames before it count
                if self.state not in _ENDED:  # (else a frame got the peer refused: said so)
                    self._bad_frame(error, resetting=True)
                    self._end(f"reset after a bad frame ({error})")
                return
            if bodies:  # a sign of life is a whole frame (wire format 3.3)...
                self._heard(time.monotonic())
                self._on_frames(bodies)
                return
            self._progress += count  # ...or 16 KiB more of one; a trickle adds up too slowly
            if self._progress >= _PROGRESS_BYTES:
                self._progress_at = now = time.monotonic()
                self._heard(now)
        except Exception as error:  # a bug must not kill the node silently
            self.owner.log.exception("Link to %s failed", self.label)
            self._end(f"unexpected {type(error).__name__}: {error}")

    def _heard(self, now: float) -> None:
        """The peer showed a sign of life at ``now``: its silence is counted from there."""
        self.last_heard = now
        self._sent_when_heard = self.pages_sent
        self._progress = 0

    def _on_frames(self, bodies: List[bytes]) -> None:
        """Decode each frame's body, act on hellos, proofs and byes, and store the pages.

        A body that cannot be decoded is dropped and counted (`_bad_frame`);
        before the handshake ends it refuses the peer instead. Once the peer is
        refused, nothing more it sent is looked at, and no page is stored.
        The pages go to `CommsLoop.deliver`, or are held while the node is
        behind: held pages pause the reading until the node's queue has room
        again (`_stop_reading`, `_resume`), so the peer feels the back-pressure
        through the socket and the node's queue does not grow without end.
        """
        pages: List[Page] = []
        decode = self.owner.decode_message
        for body in bodies:
            try:
                message = decode(body)
            except WireFormatError as error:
                if self.state is _HELLO:  # before the handshake ends, a bad frame ends it
                    self._refuse(Refused("order", f"a bad frame before its hello: {error}"))
                    return
                self._bad_frame(error)
                continue
            except Exception as error:  # a bug in decoding: say so, and lose no other frame
                self.owner.log.exception("Decoding a frame from %s failed", self.label)
                self._bad_frame(WireFormatError(f"it could not be decoded ({error!r:.80})"))
                continue
            if message.__class__ is Page and self.state is not _HELLO:
                pages.append(message)
            else:
                self._on_message(message)
                if self.state in _ENDED:  # refused
                    return
        if not pages:
            return
        self._heard_frame = True  # a page is a well-formed frame too
        self.pages_received += len(pages)
        noted = self.keys_received
        if noted is not None and len(noted) < _MAX_KEYS_NOTED:
            noted.update([page.key for page in pages])
        if self.owner.parent.wait_for_room(0):
            self.owner.deliver(self, pages)
        else:  # on_readable reads nothing more while pages are held
            self._held = pages
            self.io.call_soon(self._stop_reading)  # the selector is the I/O thread's

    def _stop_reading(self) -> None:
        if self.state not in _ENDED:
            self.io.watch(self, self.io.events(self) & ~_READ)
            self._unread_seen = 0
            self.io.when_room(self._resume)

    def _resume(self) -> None:
        if self.state in _ENDED:
            return
        if self._note_unread() != 0:  # what waits is read next: news of the peer
            self.last_heard = time.monotonic()
        held, self._held = self._held, []
        if held:
            self.owner.deliver(self, held)
        self.io.watch(self, self.io.events(self) | _READ)

    def _note_unread(self) -> Optional[int]:
        """Bytes waiting unread in the OS (None if it cannot say); more than last time is life."""
        unread = unread_bytes(self.transport.fileno())
        if unread is not None:
            if unread > self._unread_seen:
                self.last_heard = time.monotonic()
            self._unread_seen = unread
        return unread

    def _silence(self) -> Optional[str]:
        """Why the link is lost if the peer has been quiet too long, else None."""
        now = time.monotonic()
        limit_s = self.owner.hello_timeout_s
        if self.state is _HELLO and now - self.opened_at > limit_s:
            return f"it did not finish the hello (and proof) within {limit_s:g} s of connecting"
        # Nothing well-formed yet, and no big first frame still coming in steadily:
        if not self._heard_frame and now - self._progress_at > limit_s:
            return (
                f"it sent no well-formed frame, not even a hello, within {limit_s:g} s "
                "of connecting"
            )
        if self.peer_beat_s is None:
            return None  # a peer that promised no beats may be quiet for ever
        quiet_s = now - self.last_heard
        if quiet_s <= max(self.owner.dead_after_s, 3 * self.peer_beat_s):
            return None
        self.went_silent = True
        return (
            f"nothing heard from it for {quiet_s:.1f} s, though it promised a sign of life "
            f"every {self.peer_beat_s:g} s (the network path is gone, or the peer froze); "
            f"{self.pages_sent - self._sent_when_heard} pages sent since it was last heard "
            "from may be lost"
        )

    # -- the handshake, and frames that are not pages
    def _on_message(self, message: Message) -> None:
        """A frame that is not a page (or a page before the handshake ended)."""
        self._heard_frame = True
        if self.state is _HELLO and not isinstance(message, (Hello, Proof, Beat, Bye)):
            what = "a page" if isinstance(message, Page) else "a frame"
            self._refuse(Refused("order", f"it sent {what} before the handshake ended"))
        elif isinstance(message, Proof):
            if self.state is not _HELLO:  # once open, a proof is a mistake, not a danger
                self._bad_frame(WireFormatError("a proof frame after the handshake ended"))
                return
            try:
                self.handshake.on_proof(message)
            except Refused as refusal:
                self._refuse(refusal)
                return
            self._handshake_done()
        elif isinstance(message, Hello):
            if self.peer_role is not None:  # said once per connection; more is a mistake
                if message.role != self.peer_role:
                    self._bad_frame(
                        WireFormatError(
                            f"a second hello, from role {shown_role(message.role)}; this "
                            f"connection is {shown_role(self.peer_role)}'s and stays so"
                        )
                    )
                return
            self.peer_role = message.role
            self.peer_beat_s = message.beat_s
            self._peer_takes_bye = message.bye
            try:
                proof = self.handshake.on_hello(message)
            except Refused as refusal:
                self._refuse(refusal)
                return
            if proof is not None:  # our answer to its challenge; its answer comes next
                self._put_control(proof)
            if self.handshake.done:
                self._handshake_done()
        elif isinstance(message, Bye):
            self.peer_said_bye = True

    def _handshake_done(self) -> None:
        """The peer is one of ours: pages may pass (HELLO → OPEN), say so once."""
        self.hello_at = time.monotonic()
        if self.state is _HELLO:
            self.state = _OPEN
        if self.handshake.needed:  # (else it was announced when it opened)
            self.owner.announce(self)
        self.io.call_soon(self._look_again)  # beats are owed from now on
        self.owner.on_hello(self)
        self.owner.watch_link(self)

    def _refuse(self, refusal: Refused) -> None:
        """The peer may not link here: say why (once per peer), count it, close, store nothing."""
        if self.state not in _ENDED:
            self.refusal = refusal
            self.owner.on_refused(self, refusal)
            self.abort(f"refused: {refusal.reason}")

    def _bad_frame(self, error: WireFormatError, resetting: bool = False) -> None:
        # Said by the component: sixty hostile connections must not write five lines each.
        self.bad_frames += 1
        count = self.bad_frames
        self.owner.say(
            "Connections reset after a bad frame" if resetting else "Bad frames",
            logging.WARNING,
            "Bad frame from %s: %s (%s; the node keeps running%s; see docs/wire-format.md)",
            self.label,
            error,
            "reset the connection" if resetting else "dropped the frame",
            f"; {count} bad frames from this peer so far" if count > 1 else "",
            news=self.owner.bad_frame_news,
        )
