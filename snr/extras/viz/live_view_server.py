"""The server side of the Foxglove WebSocket protocol, on the ``websockets`` package.

`FoxgloveBridge` (``live_view.py``) hands it pages; viewers (Foxglove,
Lichtblick) connect over WebSocket and subscribe to the keys they show. The
protocol (github.com/foxglove/ws-protocol, ``docs/spec.md``) as used here:

* The viewer offers the subprotocol ``foxglove.sdk.v1`` (current Foxglove,
  Lichtblick since its PR #819) or ``foxglove.websocket.v1`` (older viewers):
  both name the same messages, and both are accepted. A client offering
  neither is refused (HTTP 400).
* The server sends ``serverInfo`` and then ``advertise``: one channel per key,
  topic ``/<key>``, encoding ``json``, schema ``snr.Page`` (a JSON Schema
  inferred from the key's first page, see ``page_schema.py``). A key is
  advertised when its first page arrives.
* The viewer sends ``subscribe`` with its own subscription ids; each page is
  then sent as a binary ``messageData`` frame: opcode ``0x01``, the
  subscription id (u32, little endian), the page's time in nanoseconds (u64,
  little endian), then the page exactly as the codec writes it.

**Bounds.** The node never waits for a viewer. A page goes from the node's
thread to this server's thread through a dict holding the newest page per key
(a page replaced before it was taken is counted as dropped). Each viewer has
its own such dict of pages not yet sent, one per channel, and one frame in
flight: a viewer that reads slowly, or not at all, gets the newest page of
each key when it reads again, and every page it missed is counted. So memory
stays bounded by (keys x largest page) per viewer, and one slow viewer does
not slow another.

Example::

    server = LiveViewServer("urov", listening_socket, log)
    server.start()
    server.publish(Page("depth_m", 2.5, "urov", time.time()))   # from the node's thread
    server.stop(1.0)
"""

from __future__ import annotations

import asyncio
import json
import logging
import socket
import struct
import threading
import time
from typing import TYPE_CHECKING, Any, Dict, FrozenSet, List, Optional, Set, Tuple

from snr.core.logs import LossReport, RepeatFilter
from snr.extras.viz.page_schema import PAGE_SCHEMA_NAME, page_schema
from snr.prelude import Page, WireFormatError
from snr.std_mods.codec import load_object, page_json

if TYPE_CHECKING:
    # websockets (the view extra) is imported when the server starts, not with
    # this module: the docs and `import snr.std_mods.io` must work without it.
    from websockets.asyncio.server import ServerConnection

__all__ = ["MESSAGE_DATA", "SUBPROTOCOLS", "LiveViewServer", "LiveViewStats"]

SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")
"""The WebSocket subprotocols accepted, the first preferred when a viewer offers both."""

MESSAGE_DATA = 0x01
"""Opcode of a binary ``messageData`` frame (server to viewer)."""

_FRAME_HEAD = struct.Struct("<BIQ")  # opcode, subscription id, log time (ns)
_MAX_TIME_NS = 2**64 - 1
_MAX_VIEWER_MESSAGE = 1 << 20  # viewers send small JSON requests
_CLOSE_S = 0.5  # how long a closing handshake may take before the socket is cut
Pending = Tuple[int, bytes]  # (log time in ns, encoded page)


class LiveViewStats:
    """Counts kept for the live view, over the node's whole run (reloads too).

    Example::

        stats.pages_sent, stats.pages_dropped   # (1520, 37)
    """

    def __init__(self) -> None:
        self.pages_sent = 0
        """Pages sent to viewers (a page sent to two viewers counts twice)."""
        self.dropped_before_sending = 0
        """Pages replaced by a newer page of their key before the server took them."""
        self.dropped_for_viewers = 0
        """Pages replaced by a newer page of their key before a viewer could take them."""
        self.pages_not_encoded = 0
        """Pages whose data JSON cannot hold (logged, not sent)."""

    @property
    def pages_dropped(self) -> int:
        """Every page dropped, wherever: always the older page of a key."""
        return self.dropped_before_sending + self.dropped_for_viewers


class _Channel:
    """One key as the viewers see it."""

    def __init__(self, channel_id: int, key: str, data: Any) -> None:
        self.id = channel_id
        self.key = key
        self.advertisement = {
            "id": channel_id,
            "topic": "/" + key,
            "encoding": "json",
            "schemaName": PAGE_SCHEMA_NAME,
            "schema": json.dumps(page_schema(data)),
            "schemaEncoding": "jsonschema",
        }
        self.latest: Optional[Pending] = None  # for a viewer that subscribes later


class _Viewer:
    """One connected viewer: its subscriptions and its pages not yet sent."""

    def __init__(self, connection: ServerConnection) -> None:
        self.connection = connection
        self.subscription_of: Dict[int, int] = {}  # channel id -> the viewer's subscription id
        self.pending: Dict[int, Pending] = {}  # channel id -> newest page not yet sent
        self.control: List[str] = []  # advertisements to send before any page
        self.wake = asyncio.Event()

    def offer(self, channel_id: int, item: Pending) -> bool:
        """Queue a page if subscribed; True when it replaced an unsent page (a drop)."""
        if channel_id not in self.subscription_of:
            return False
        replaced = channel_id in self.pending
        self.pending[channel_id] = item  # a replaced key keeps its place in line
        self.wake.set()
        return replaced

    def say(self, message: Dict[str, Any]) -> None:
        self.control.append(json.dumps(message, separators=(",", ":")))
        self.wake.set()

    async def write(self, stats: LiveViewStats) -> None:
        """Send what is pending, oldest key first; ``send`` waits while the socket is full."""
        connection = self.connection
        while True:
            await self.wake.wait()
            self.wake.clear()
            while self.control or self.pending:
                if self.control:
                    await connection.send(self.control.pop(0))
                    continue
                channel_id = next(iter(self.pending))
                log_time_ns, payload = self.pending.pop(channel_id)
                subscription = self.subscription_of.get(channel_id)
                if subscription is None:  # unsubscribed meanwhile
                    continue
                head = _FRAME_HEAD.pack(MESSAGE_DATA, subscription, log_time_ns)
                await connection.send(head + payload)
                stats.pages_sent += 1


class LiveViewServer:
    """Serves pages to Foxglove-protocol viewers from its own thread.

    Args:
        name: the server's name, shown by viewers (the node's role).
        listener: a bound, listening TCP socket (binding is the caller's, so
            a port in use is reported where the node starts).
        log: where to say what happens (viewers, drops, pages not encoded).
        stats: counters to add to (kept on the factory across reloads).

    Example::

        server = LiveViewServer("urov", listener, log)
        server.start()
        server.publish(page)    # from the node's thread: never waits
        server.stop(1.0)
    """

    def __init__(
        self,
        name: str,
        listener: socket.socket,
        log: logging.Logger,
        stats: Optional[LiveViewStats] = None,
    ) -> None:
        self.name = name
        self.listener = listener
        self.log = log
        self.stats = stats if stats is not None else LiveViewStats()
        self.loss = LossReport(
            log,
            "pages for the live view",
            "the node stores pages faster than the view sends them (a slow viewer, or a "
            "busy machine); the newest page of each key is kept",
        )
        self._repeats = RepeatFilter(log, first=1)
        self.watched: FrozenSet[str] = frozenset()
        """Keys some viewer subscribes to (replaced as a whole: safe to read anywhere)."""
        # node thread -> server thread: the newest page per key
        self._inbox: Dict[str, Page] = {}
        self._published = 0  # pages put in the inbox (written by the node's thread only)
        self._taken = 0  # pages taken from it (written by the server's thread only)
        self._ringing = False  # a call to _take_inbox is on its way
        self._unwatched: Dict[str, Page] = {}  # the newest page of each unwatched key
        # server thread only
        self._channels: Dict[str, _Channel] = {}
        self._by_id: Dict[int, _Channel] = {}
        self._viewers: Set[_Viewer] = set()
        self._loop: Optional[asyncio.AbstractEventLoop] = None
        self._stop: Optional[asyncio.Event] = None
        self._ready = threading.Event()
        self._error: Optional[BaseException] = None
        self._thread = threading.Thread(target=self._run, name=f"snr-{name}-live-view", daemon=True)

    # -- any thread ------------------------------------------------------------
    def start(self, timeout_s: float = 5.0) -> None:
        """Start serving; returns once viewers can connect.

        Raises:
            RuntimeError: the server did not start (the cause is chained).
        """
        self._thread.start()
        if not self._ready.wait(timeout_s):
            raise RuntimeError(f"the live view server did not start within {timeout_s:g} s")
        if self._error is not None:
            raise RuntimeError(f"the live view server did not start: {self._error}") from (
                self._error
            )

    def publish(self, page: Page) -> None:
        """Hand over a stored page; never waits. The newest page of a key wins.

        Lock-free, so the node pays a few dict operations per page: only the
        node's thread adds to the inbox and counts, only the server's thread
        takes (``dict`` operations are atomic in CPython).
        """
        key = page.key
        if key not in self.watched and key in self._channels:
            self._unwatched[key] = page  # nobody looks: keep it for a later subscriber
            return
        self._inbox[key] = page
        self._published += 1
        if not self._ringing:
            self._ringing = True
            loop = self._loop
            if loop is not None:
                try:
                    loop.call_soon_threadsafe(self._take_inbox)
                except RuntimeError:  # the server has stopped: nothing to send to
                    pass

    def stop(self, timeout_s: float = 1.0) -> None:
        """Close every connection and the listener; wait (bounded) for the thread."""
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None:
            try:
                loop.call_soon_threadsafe(stop.set)
            except RuntimeError:  # already stopped
                pass
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)
        self.listener.close()
        self._repeats.flush()

    def is_alive(self) -> bool:
        """True while the server's thread runs."""
        return self._thread.is_alive()

    def join(self, timeout_s: Optional[float] = None) -> None:
        """Wait up to ``timeout_s`` for the server's thread to end."""
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)

    # -- the server's thread -----------------------------------------------------
    def _run(self) -> None:
        try:
            asyncio.run(self._serve())
        except BaseException as error:  # reported by start(), or logged
            if not self._ready.is_set():
                self._error = error
                self._ready.set()
            else:
                self.log.error("The live view server stopped: %s", error)

    async def _serve(self) -> None:
        from websockets.asyncio.server import serve
        from websockets.typing import Subprotocol

        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        library_log = self.log.getChild("websockets")
        if library_log.level == logging.NOTSET:  # its every connection is INFO: too chatty
            library_log.setLevel(logging.WARNING)
        server = await serve(
            self._serve_viewer,
            sock=self.listener,
            subprotocols=[Subprotocol(name) for name in SUBPROTOCOLS],
            compression=None,  # pages are small; compressing costs the robot's CPU
            max_size=_MAX_VIEWER_MESSAGE,
            close_timeout=_CLOSE_S,
            logger=library_log,
        )
        self._ready.set()
        await self._stop.wait()
        server.close()
        try:
            await asyncio.wait_for(server.wait_closed(), 2 * _CLOSE_S)
        except asyncio.TimeoutError:
            pass  # a viewer that never answers the close: its socket is cut on exit

    def _take_inbox(self) -> None:
        self._ringing = False  # first: a page added from now on rings again
        pages: Dict[str, Page] = {}
        for key in list(self._inbox):  # list(): the node's thread may add keys meanwhile
            pages[key] = self._inbox.pop(key)
        self._taken += len(pages)
        # Published but neither taken nor waiting: replaced by a newer page of its key.
        replaced = (
            self._published - self._taken - len(self._inbox) - self.stats.dropped_before_sending
        )
        dropped = self.stats.pages_dropped
        if replaced > 0:
            self.stats.dropped_before_sending += replaced
            self.loss.dropped(replaced)
        for key in list(self._unwatched):
            if key in self.watched:
                waiting = self._unwatched.pop(key, None)  # stored as a viewer subscribed
                if waiting is not None and key not in pages:
                    self._send(waiting)
        for page in pages.values():
            self._send(page)
        if self.loss.dropping and self.stats.pages_dropped == dropped + max(replaced, 0):
            self.loss.recovered(quiet_s=2.0)

    def _send(self, page: Page) -> None:
        """Encode a page once; offer it to every viewer subscribed to its key."""
        try:
            payload = page_json(page, to="to the live view")
            log_time_ns = min(max(int(page.created_at_s * 1e9), 0), _MAX_TIME_NS)
        except Exception as error:  # never stop serving over one page
            self.stats.pages_not_encoded += 1
            self._repeats.report(
                (page.key, type(error).__name__),
                f"Pages under {page.key!r} not shown in the live view",
                logging.ERROR,
                "Not shown in the live view: %s",
                error,
            )
            return
        channel = self._channels.get(page.key)
        if channel is None:
            channel = self._advertise(page)
        item = (log_time_ns, payload)
        channel.latest = item
        for viewer in self._viewers:
            if viewer.offer(channel.id, item):
                self.stats.dropped_for_viewers += 1
                self.loss.dropped()

    def _advertise(self, page: Page) -> _Channel:
        channel = _Channel(len(self._channels) + 1, page.key, page.data)
        self._channels[page.key] = channel
        self._by_id[channel.id] = channel
        for viewer in self._viewers:
            viewer.say({"op": "advertise", "channels": [channel.advertisement]})
        return channel

    async def _serve_viewer(self, connection: ServerConnection) -> None:
        from websockets.exceptions import ConnectionClosed

        viewer = _Viewer(connection)
        self._viewers.add(viewer)
        host, port = connection.remote_address[:2]
        where = f"{host}:{port}"
        self.log.info("A viewer connected from %s (%s)", where, connection.subprotocol)
        viewer.say(
            {
                "op": "serverInfo",
                "name": self.name,
                "capabilities": [],
                "metadata": {"library": "snr"},
                "sessionId": str(time.time_ns()),
            }
        )
        if self._channels:
            channels = [channel.advertisement for channel in self._channels.values()]
            viewer.say({"op": "advertise", "channels": channels})
        writer = asyncio.ensure_future(viewer.write(self.stats))
        try:
            async for message in connection:
                self._on_request(viewer, message)
        except ConnectionClosed:
            pass
        finally:
            self._viewers.discard(viewer)
            self._update_watched()
            writer.cancel()
            try:
                await writer
            except (asyncio.CancelledError, ConnectionClosed):
                pass
            self.log.info("The viewer at %s left", where)

    def _on_request(self, viewer: _Viewer, message: Any) -> None:
        """Handle ``subscribe`` and ``unsubscribe``; anything else is logged once and ignored."""
        try:
            if isinstance(message, (bytes, bytearray)):
                raise WireFormatError("a binary message (this server takes no client data)")
            request = load_object(message)
            op = request.get("op")
            if op == "subscribe":
                wanted = [
                    (int(entry["id"]), int(entry["channelId"]))
                    for entry in request["subscriptions"]
                ]
                for subscription, channel_id in wanted:
                    if channel_id not in self._by_id:
                        raise ValueError(f"there is no channel {channel_id}")
                    viewer.subscription_of[channel_id] = subscription
                self._update_watched()  # before looking for pages of keys nobody watched
                for _, channel_id in wanted:
                    self._show_current(viewer, self._by_id[channel_id])
            elif op == "unsubscribe":
                dropped = set(request["subscriptionIds"])
                viewer.subscription_of = {
                    channel: sub
                    for channel, sub in viewer.subscription_of.items()
                    if sub not in dropped
                }
            else:
                raise WireFormatError(f"the request {op!r} is not supported")
        except (WireFormatError, KeyError, TypeError, ValueError) as error:
            self._repeats.report(
                ("request", type(error).__name__),
                "Viewer requests ignored",
                logging.WARNING,
                "Ignored a viewer's request (%s): %.200r",
                error,
                message,
            )
        self._update_watched()

    def _show_current(self, viewer: _Viewer, channel: _Channel) -> None:
        """Send a new subscriber the key's newest page at once (a slow key may not change)."""
        waiting = self._unwatched.pop(channel.key, None)
        if waiting is not None:  # stored while nobody watched: newer than `latest`
            self._send(waiting)
        elif channel.latest is not None:
            viewer.offer(channel.id, channel.latest)

    def _update_watched(self) -> None:
        self.watched = frozenset(
            self._by_id[channel_id].key
            for viewer in self._viewers
            for channel_id in viewer.subscription_of
        )
