"""`CommsLoop`: the comms component a node gets, forwarding pages by key over its links.

A `CommsLoop` (thesis 6.4.1) forwards every page stored under its keys to
each open `Link` (``link.py``: one live connection to one peer), and stores
every page a link receives, with the page's original origin and time.
`SocketsServerLoop`, `SocketsClientLoop` and `PipeLoop` are comms loops; they
differ only in how they open their links.

How a page travels::

    node thread                          peer's I/O thread         peer's node thread
    store_page → CommsLoop.forward_page  →  frame bytes  →  decode → schedule(store_page)
                 (encodes the very page       (written at once, or     → datastore
                  that was stored)             by the I/O thread)      → process_data

Example (what `SocketsPair` and `PipeLoopFactory` build for you)::

    class MyLoop(CommsLoop):
        def begin(self) -> None:
            self.open_link(my_transport)

        def loop(self) -> None:
            self.wait_s(0.5)
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple, Union

from snr.core import ThreadLoop, tasks
from snr.core.logs import RateLimitedLog
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
    TaskId,
    TaskType,
)
from snr.std_mods.comms.handshake import Refused
from snr.std_mods.comms.io_loop import IOLoop
from snr.std_mods.comms.link import Link, LinkState, Transport
from snr.std_mods.comms.wire import Message, decode_body, encode_page

_OPEN = LinkState.OPEN
_STORE_PAGE = TaskType.store_page

__all__ = [
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "DEFAULT_DEAD_AFTER_S",
    "DEFAULT_MAX_BACKLOG_BYTES",
    "CommsLoop",
    "Keys",
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
_NEWS_TICK_S = 0.5  # while news may be counted, how often its counts are looked at
_NEWS_WINDOW_S = 10.0  # the longest window of the news logs (RateLimitedLog)
_MAX_REFUSED_NOTED = 10_000  # refused peers remembered (so each is logged once)
"""Seconds of silence after which a peer that promised beats counts as lost."""

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
        closed_totals: the counters of the links that have closed, added up
            (``links``, ``pages_sent``, ``pages_received``, ``dropped``,
            ``bad_frames``), so that what a dead link dropped is not forgotten.
        dead_after_s: a peer that promised beats and is silent this long is lost.
        beat_s: how often a quiet link sends a beat (a quarter of ``dead_after_s``,
            at most 1 s); promised to the peer in the hello.
    """

    hello_timeout_s: float = 5.0
    """A connection that sends no well-formed frame (not even a hello) for this long is closed."""

    recovered_after_s: float = 1.0
    """After drops, a link logs "Recovered" once nothing was dropped for this long."""

    checks_keys_per_link = True
    """In DEBUG mode its keys are checked once a link is up (link_hints.py), not at start."""

    side: str = "pipe"
    """Which end of its links it is: ``"server"``, ``"client"`` or ``"pipe"`` (in the proofs)."""

    peer_noun: str = "peer"
    """What its log lines call the other end, e.g. ``"client"``."""

    system: Optional[str] = None
    """The system its hellos name; peers of another (or none) are refused. None: no check."""

    secret: Optional[bytes] = None
    """The secret its links prove they know and ask peers to prove; None: no authentication."""

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
        self._news_lock = threading.Lock()
        self._news_at = 0.0  # when news was last counted
        self._news_ticking = False  # the I/O thread ticks the news (see _news_came)
        self.closed_totals: Dict[str, int] = dict.fromkeys(
            ("links", "pages_sent", "pages_received", "dropped", "bad_frames", "refused"), 0
        )
        # (peer's host, its role, why) -> how many times it was refused: said once each
        self.refused_peers: Dict[Tuple[str, str, str], int] = {}
        self.refusal_news = RateLimitedLog(self.log, burst=5, window_s=5.0)
        self.io_loop: Optional[IOLoop] = None  # the node's, while this component runs
        self._links_lock = threading.Lock()
        self._opened: List[Link] = []  # every link that may not have ended yet
        self._forwarded = frozenset(self.keys)
        # Pages a link delivered under a forwarded key, until forward_page sees
        # them: {id(page): (page, link)} so they are not sent back to that link.
        self._arrived: Dict[int, Tuple[Page, Link]] = {}
        self._unsent_reported = False
        self._unsendable_reported: Set[Tuple[DataKey, type]] = set()
        self.task_handlers = {(TaskType.store_page, key): self.forward_page for key in self.keys}
        self.burst_handlers = {(TaskType.store_page, key): self.forward_burst for key in self.keys}
        if parent.profiler is not None:  # the profile also tells what was sent and dropped
            parent.profiler.add_report(name, self.stats_text)

    # -- node thread: sending -------------------------------------------------
    def forward_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Send the page just stored to every open link it did not come from."""
        page = task.page()
        if page is None:
            return None  # the node core has already reported the bad task
        source = None
        if self._arrived:  # pages from a link, under a key this node forwards
            arrived = self._arrived.pop(id(page), None)
            if arrived is not None and arrived[0] is page:
                source = arrived[1]
        origin = page.origin
        links = self.links
        targets: Sequence[Link]
        if len(links) == 1:  # the usual case, a pair: no list to build
            link = links[0]
            sendable = link is not source and link.state is _OPEN and link.peer_role != origin
            targets = links if sendable else ()
        else:
            targets = [
                link
                for link in links
                if link is not source and link.state is _OPEN and link.peer_role != origin
            ]
        if not targets:
            if source is None and not any(link.state is _OPEN for link in self.links):
                self._report_unsent(page)
            return None
        try:
            frame = encode_page(page)
        except NotSerializableError as error:
            self._report_unsendable(page, error)
            return None
        page_key = page.key
        for link in targets:
            link.send(frame, True, page_key)  # a drop is counted and reported by the link
        return None

    def forward_burst(self, run: List[Task]) -> SomeTasks:
        """`forward_page` for a run of pages under one key: encoded, then queued in one go.

        The node calls it for ``store_page`` tasks that waited one behind the
        other (a handler that stored many pages, a replayed recording), all
        stored already. One link, open, and no page from a link to keep from
        echoing (the usual pair sending its own pages): the frames go to the
        link's outbox with one call. Anything else: page by page.

        Example (the node calls it; a test may too)::

            comms.forward_burst([tasks.store_page(page) for page in pages])
        """
        links = self.links
        if len(links) != 1 or self._arrived or links[0].state is not _OPEN:
            for task in run:
                self.forward_page(task, (TaskType.store_page, task.name))
            return None
        link = links[0]
        peer = link.peer_role
        frames: List[bytes] = []
        for task in run:
            page = task.page()
            if page is None or page.origin == peer:
                continue  # a bad task (the node core said so), or the peer's own page
            try:
                frames.append(encode_page(page))
            except NotSerializableError as error:
                self._report_unsendable(page, error)
        if frames:
            link.send_burst(frames, run[0].name)
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

    # -- I/O thread: receiving -------------------------------------------------
    def deliver(self, link: Link, pages: List[Page]) -> None:
        """Store pages a link received (called by the thread that read them).

        The link calls it only while the node's queue has room: while the
        queue is over its high-water mark the link stops reading instead (the
        bytes stay in the OS, TCP slows the sender, and nothing is lost on
        this side), so the I/O thread never waits here.
        """
        forwarded = self._forwarded
        if forwarded:
            for page in pages:
                if page.key in forwarded:
                    self._arrived[id(page)] = (page, link)
        if len(pages) == 1:  # the usual read when pages come one at a time
            self.parent.schedule(Task(_STORE_PAGE, pages[0].key, pages))
        elif not link.io.in_loop_thread():
            # The node's thread read these while its queue was empty: one task
            # for the lot, which the node core stores without a dispatch per
            # page. (At most one read's worth: the queue stays bounded.)
            self.schedule(tasks.store_pages(pages))
        else:  # the I/O thread: one task each, so the queue's high-water mark counts pages
            self.schedule([Task(_STORE_PAGE, page.key, [page]) for page in pages])

    # -- opening and closing links --------------------------------------------
    def start_thread(self) -> None:
        """Acquire the node's I/O loop, then start as every loop does (``begin()``, its thread)."""
        # Links need the node's I/O loop from begin() on; a restart after a
        # failed reload keeps the one it has.
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
            self._opened = [old for old in self._opened if not old.is_closed()] + [link]
        self._unsent_reported = False
        link.start()
        if link.state is _OPEN:  # no handshake: pages may pass at once (else: announce)
            self.announce(link)
        return link

    def announce(self, link: Link) -> None:
        """The link is open for pages: schedule ``COMMS_CONNECTED`` (once per link)."""
        if not link.announced:
            link.announced = True
            self.schedule(tasks.event(COMMS_CONNECTED, [self.name, link.transport.peer]))

    def on_refused(self, link: Link, refusal: Refused) -> None:
        """A peer was refused (I/O thread): log it once per peer, count it every time.

        A peer is its host, its role and why: a client that retries every
        second is one line, however long it tries; many peers at once are
        at most five lines in 5 s, then a count (`RateLimitedLog`).

        Example (what the log says)::

            Refused client 'topside' at 10.0.0.7:51234: it belongs to system 'team3', ...
        """
        host = link.transport.peer.rsplit(":", 1)[0]
        key = (host, link.peer_role or "", refusal.kind)
        with self._links_lock:
            seen = self.refused_peers.get(key, 0)
            if seen == 0 and len(self.refused_peers) >= _MAX_REFUSED_NOTED:
                self.refused_peers.clear()  # a flood of peers: remember the newest ones
            self.refused_peers[key] = seen + 1
        if seen:
            return
        if self.refusal_news.report(
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
        ):
            self._news_came()

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
        if link.refusal is not None:
            return  # said once per peer by on_refused; it was never open for pages
        if not self.is_terminated():
            self.on_link_lost(link, reason)
            if link.announced:  # only a link that was open for pages is news to handlers
                self.schedule(tasks.event(COMMS_DISCONNECTED, [self.name, link.transport.peer]))

    def say(self, what: str, level: int, msg: str, *args: Any) -> None:
        """Log news of links (connects, hellos, losses) in full, unless it comes in a flood.

        ``what`` names the kind of news, e.g. ``"Clients connected"``: each
        line is logged in full while no more than 20 of its kind came in the
        last 10 s; past that they are counted, and the count is logged once
        every 10 s (see `RateLimitedLog`; `tick_news` says the last count). A
        class of robots connecting is logged robot by robot; a program that
        connects a thousand times a second costs a line every 10 s.

        Example::

            self.say("Links lost", logging.WARNING, "Lost the link to %s", link.label)
        """
        if self.news.report(what, level, msg, *args):
            self._news_came()

    def say_bad_frame(self, what: str, level: int, msg: str, *args: Any) -> None:
        """`say` for bad frames: at most five lines in 5 s, then a count.

        Example::

            self.say_bad_frame("Bad frames", logging.WARNING, "Bad frame from %s", link.label)
        """
        if self.bad_frame_news.report(what, level, msg, *args):
            self._news_came()

    def tick_news(self) -> None:
        """Log the counts of news that came in a flood, once their window has passed.

        The node's I/O thread calls it every half second for a while after
        news was counted rather than logged (`say`), and never otherwise:
        quiet comms wake no thread for it.

        Example::

            comms.tick_news()
        """
        self.news.tick()
        self.bad_frame_news.tick()
        self.refusal_news.tick()

    def _news_came(self) -> None:
        """Any thread: news was counted, not logged; tick until its window has passed."""
        with self._news_lock:
            self._news_at = time.monotonic()
            io = self.io_loop
            if self._news_ticking or io is None:
                return
            self._news_ticking = True
        io.call_soon(self._tick_news_soon)

    def _tick_news_soon(self) -> None:
        io = self.io_loop
        if io is not None:
            io.call_later(_NEWS_TICK_S, self._tick_news_later)

    def _tick_news_later(self) -> None:
        """I/O thread: say what a flood left counted; again soon while news may be pending."""
        self.tick_news()
        io = self.io_loop
        with self._news_lock:
            if io is None or time.monotonic() - self._news_at > _NEWS_WINDOW_S + _NEWS_TICK_S:
                self._news_ticking = False  # every count has been said
                return
        io.call_later(_NEWS_TICK_S, self._tick_news_later)

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
        """Log that the peer went away (subclasses say what happens next).

        A warning, unless the peer said goodbye (``link.peer_said_bye``): a
        node that stops in order is news, not a fault.
        """
        if link.peer_said_bye:
            self.say("Links ended", logging.INFO, "The link to %s ended: %s.", link.label, reason)
        else:
            self.say("Links lost", logging.WARNING, "Lost the link to %s: %s.", link.label, reason)

    def decode_message(self, body: bytes) -> Message:
        """The message in one frame's body (`decode_body`); the pipe accepts 2021 pages too.

        Example::

            comms.decode_message(b'{"v":1,"kind":"beat"}')   # Beat()
        """
        return decode_body(body)

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

    # -- shutdown -------------------------------------------------------------
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
        with self._links_lock:
            opened = list(self._opened)
        for link in opened:  # aborted ones end on the I/O thread's next pass
            link.wait_closed(max(0.1, deadline - time.monotonic()))
        self._release_io_loop()
        self.news.flush()  # what a flood of connections or bad frames left uncounted aloud
        self.bad_frame_news.flush()
        self.refusal_news.flush()
