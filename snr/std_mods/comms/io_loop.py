"""The socket transport: `SocketTransport` over TCP, and the `IOLoop` that serves every link.

A link talks over a `Transport`: a non-blocking byte stream (a TCP socket, a
pipe end). Every link of a node is served by the node's one `IOLoop`: a
``selectors`` loop on one thread, ``snr-<role>-io``, that reads, writes and
runs the links' timers, so hundreds of idle clients cost no more threads
than one. On Linux the node's own thread reads the links while it is idle
(the loop is its `snr.core.task_queue.IdleWaiter`); the *read role*, a lock,
says which thread reads. Why and how: docs/design.md, "One I/O thread per node".

Example::

    io = IOLoop.acquire(node)        # the first user starts "snr-<role>-io"
    io.call_soon(lambda: io.watch(link, selectors.EVENT_READ))
    io.release()                     # the last user stops and joins it
"""

from __future__ import annotations

import collections
import contextlib
import heapq
import itertools
import logging
import select
import selectors
import socket
import struct
import threading
import time
from typing import Any, Callable, Iterator, Optional, Protocol

from snr.core.node import Node
from snr.prelude import AbstractNode

try:  # Linux and macOS say how many bytes wait unread; Windows has no fcntl
    import fcntl
    import termios

    _FIONREAD: Optional[int] = termios.FIONREAD
except ImportError:
    _FIONREAD = None

__all__ = ["IOLoop", "IOTimer", "Served", "SocketTransport", "Transport", "unread_bytes"]

RECV_BYTES = 256 * 1024  # the loop's one receive buffer, shared by its links
ROOM_CHECK_S = 0.015  # while links wait for room in the node's queue, how often it is checked
BUSY_READS_S = 0.05  # once the node's thread has worked this long, the I/O thread reads too
IDLE_CHECK_S = 0.25  # while the node's thread sleeps, how often the I/O thread looks at it
IDLE_STOP_S = 1.0  # after this long with no work for the node, the I/O thread stops looking
JOIN_TIMEOUT_S = 1.0  # how long the last release waits for the thread to end
WRITE_DELAY_S = 0.001  # frames another thread queued wait this long for it, then the loop writes

_READ = selectors.EVENT_READ
_WRITE = selectors.EVENT_WRITE
_READS = "reads"  # the selector key of the read set (the wake-up socket's is None)


class Served(Protocol):
    """What the I/O loop calls on what it serves: a `snr.std_mods.comms.comms_loop.Link`.

    Example::

        io.watch(link, selectors.EVENT_READ)   # link.on_readable() when bytes come
    """

    def fileno(self) -> int:
        """The socket (or pipe) to watch."""

    def on_readable(self) -> None:
        """Read what came (the loop's thread, or the idle node's)."""

    def on_writable(self) -> None:
        """Write what waits, now that the socket has room (the loop's thread)."""

    def write_waiting(self) -> None:
        """Write what waits, from another thread than the loop's (`IOLoop.write_soon`)."""

    def on_io_stop(self) -> None:
        """Its reading or writing raised: end it (the loop's thread)."""


class IOTimer:
    """A callback `IOLoop.call_later` runs once; ``cancel()`` takes it back.

    Example::

        timer = io.call_later(0.25, check)
        timer.cancel()
    """

    __slots__ = ("callback", "cancelled", "when")

    def __init__(self, when: float, callback: Callable[[], None]) -> None:
        self.when = when
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        """Do not run the callback (if it has not run yet)."""
        self.cancelled = True


_registry_lock = threading.Lock()
_registry: dict[AbstractNode, IOLoop] = {}  # each node's loop, while it has users


class IOLoop:
    """One selector thread serving the sockets of every comms link of one node.

    Only the loop's thread touches the selector; other threads ask it with
    `call_soon`. The links are read by the holder of the *read role*: the
    node's thread while it is idle (`wait`, `woken`), else the loop's thread.
    A comms component gets its node's loop with `acquire` and gives it back
    with `release`.

    Example::

        io = IOLoop.acquire(node)
        io.call_soon(lambda: io.watch(link, selectors.EVENT_READ))
        io.release()

    Attributes:
        node: the node whose links it serves.
        buffer: the receive buffer links read into, and ``view``, a memoryview of it.
    """

    node_reads: bool = hasattr(select, "epoll")
    """Let the node's thread read the links while it is idle (needs epoll: Linux)."""

    def __init__(self, node: AbstractNode) -> None:
        self.node = node
        self.log = logging.getLogger(f"snr.{node.role}.io")
        self.buffer = bytearray(RECV_BYTES)
        self.view = memoryview(self.buffer)
        self._users = 0
        self._selector = selectors.DefaultSelector()
        self._handlers: dict[Served, int] = {}  # every watched link: its events
        self._calls: collections.deque[Callable[[], object]] = collections.deque()
        self._timers: list[tuple[float, int, IOTimer]] = []
        self._order = itertools.count()  # ties in the timer heap never compare IOTimers
        self._waiting_for_room: list[Callable[[], None]] = []
        self._to_write: dict[Served, None] = {}  # write_soon's links, each once
        self._stopping = self._woken = False
        self._wake_r, self._wake_w = _wake_pair()
        self._selector.register(self._wake_r, _READ, None)
        self._thread = threading.Thread(target=self._run, name=f"snr-{node.role}-io", daemon=True)
        self._queue = node.queue if isinstance(node, Node) else None  # a mock node has none
        # With node reads, links to read are in two epoll sets: `_reads`, which
        # the selector watches while the I/O thread reads, and `_node_poll`.
        self._reads: Any = None
        self._readers: dict[int, Served] = {}  # fd -> link, for `_reads`
        self._role = threading.RLock()  # the read role: whoever holds it reads
        self._role_wanted = False  # the loop's thread waits for the role: leave it
        self._waiter_installed = False  # the node waits on this loop when idle
        self._node_ready: Optional[list[tuple[int, int]]] = None  # wait() took the role
        self._busy_since = self._work_at = 0.0  # when the node last left wait() (with work)
        self._looking = False  # _check_busy is due (else woken() starts it)
        self._looks_lock = threading.Lock()  # _looking and _work_at, between the two threads
        if self.node_reads:
            self._reads, self._node_poll, self._wake_only = [select.epoll() for _ in range(3)]
            self._set_io_reads(True)  # until the node's thread first waits
            self._node_wake_r, self._node_wake_w = _wake_pair()
            for poll in (self._node_poll, self._wake_only):  # the latter while the role is wanted
                poll.register(self._node_wake_r.fileno(), select.EPOLLIN)

    # -- sharing one loop per node ------------------------------------------
    @classmethod
    def acquire(cls, node: AbstractNode) -> IOLoop:
        """The node's I/O loop, started for its first user.

        Example::

            io = IOLoop.acquire(self.parent)   # in a comms component's start
        """
        with _registry_lock:
            loop = _registry.get(node)
            if loop is None:
                loop = _registry[node] = cls(node)
                loop._thread.start()
                if loop._reads is not None and loop._queue is not None:
                    loop._waiter_installed = loop._queue.use_waiter(loop)
            loop._users += 1
            return loop

    def release(self) -> None:
        """Give the loop back; the last user stops it and joins its thread (bounded).

        Example::

            io.release()   # in the component's terminate()
        """
        with _registry_lock:
            self._users -= 1
            if self._users > 0:
                return
            if _registry.get(self.node) is self:
                del _registry[self.node]
        self.stop()

    def stop(self, timeout_s: float = JOIN_TIMEOUT_S) -> None:
        """End the thread (it closes what is still watched) and wait up to ``timeout_s``."""
        if self._waiter_installed and self._queue is not None:
            self._waiter_installed = False
            self._queue.stop_waiter(self)  # the node waits on its bell again
        self._stopping = True
        self._wake()
        thread = self._thread
        if thread.is_alive() and thread is not threading.current_thread():
            thread.join(timeout_s)
            if thread.is_alive():
                self.log.warning(
                    "The comms I/O thread of node %r did not stop within %.1f s.",
                    self.node.role,
                    timeout_s,
                )
        if self._reads is not None and not thread.is_alive():
            for closable in (self._node_poll, self._wake_only, self._reads):
                closable.close()
            self._node_wake_r.close()
            self._node_wake_w.close()

    def in_loop_thread(self) -> bool:
        """True when called on the loop's own thread."""
        return threading.current_thread() is self._thread

    # -- any thread ---------------------------------------------------------
    def call_soon(self, callback: Callable[[], object]) -> None:
        """Run ``callback`` on the loop's thread, in the order of the calls (any thread).

        Example::

            io.call_soon(link.on_writable)
        """
        self._calls.append(callback)
        if not self._woken:
            self._wake()

    def write_soon(self, link: Served) -> None:
        """``link`` has frames queued by another thread than the loop's.

        The node's thread writes them when it next goes idle (`wait`); the
        loop's thread writes what still waits `WRITE_DELAY_S` later.

        Example::

            io.write_soon(link)   # link.write_waiting() or link.on_writable() will follow
        """
        self._to_write[link] = None
        self.call_soon(lambda: self.call_later(WRITE_DELAY_S, link.on_writable))

    def write_waiting(self) -> None:
        """Not the loop's thread: let every link given to `write_soon` write what waits."""
        while self._to_write:
            try:
                link = self._to_write.popitem()[0]
            except KeyError:  # emptied meanwhile
                return
            try:
                link.write_waiting()
            except Exception:  # a bug in one link must not stop the node
                self.log.exception("A comms link's write failed; the I/O thread retries it")

    def _wake(self) -> None:
        self._woken = True
        try:
            self._wake_w.send(b"\0")
        except OSError:  # full (it is already awake) or closed (it has stopped)
            pass

    # -- loop thread only ---------------------------------------------------
    def watch(self, handler: Served, events: int) -> None:
        """Serve ``handler`` for ``events`` (0: keep it, but select nothing for now)."""
        old = self._handlers.get(handler)
        if old == events:
            return
        self._handlers[handler] = events
        old = old or 0
        if self._reads is not None:
            if (old ^ events) & _READ:  # reads go to the read set, not the selector
                fd = handler.fileno()
                if events & _READ:
                    self._readers[fd] = handler
                    self._reads.register(fd, select.EPOLLIN)
                    self._node_poll.register(fd, select.EPOLLIN)
                else:
                    self._reads.unregister(fd)
                    self._node_poll.unregister(fd)
                    del self._readers[fd]
            old, events = old & _WRITE, events & _WRITE
        if old and events:
            self._selector.modify(handler, events, handler)
        elif old:
            self._selector.unregister(handler)
        elif events:
            self._selector.register(handler, events, handler)

    def events(self, handler: Served) -> int:
        """The events ``handler`` is watched for (0 if none or not watched)."""
        return self._handlers.get(handler, 0)

    def forget(self, handler: Served) -> None:
        """Stop serving ``handler`` (before its socket is closed)."""
        self.watch(handler, 0)
        del self._handlers[handler]

    @contextlib.contextmanager
    def read_role(self) -> Iterator[None]:
        """Hold the read role (loop thread), e.g. to close a link's socket.

        If the node's thread holds it (idle in `wait`), it is woken to give it back.

        Example::

            with io.read_role():
                transport.close()
        """
        wanted = not self._role.acquire(blocking=False)
        if wanted:
            self._role_wanted = True  # the node's thread leaves it to us until we are done
            self.wake()
            self._role.acquire()
        try:
            yield
        finally:
            self._role.release()
            if wanted:  # the node's thread waits without watching the links
                self._role_wanted = False
                self.wake()

    def call_later(self, delay_s: float, callback: Callable[[], None]) -> IOTimer:
        """Run ``callback`` on the loop's thread after ``delay_s`` seconds."""
        timer = IOTimer(time.monotonic() + delay_s, callback)
        heapq.heappush(self._timers, (timer.when, next(self._order), timer))
        return timer

    def when_room(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` once the node's queue is below its high-water mark (a look a 15 ms)."""
        if not self._waiting_for_room:  # else a look is due
            self.call_later(ROOM_CHECK_S, self._check_room)
        self._waiting_for_room.append(callback)

    def _check_room(self) -> None:
        if not self.node.wait_for_room(0):
            self.call_later(ROOM_CHECK_S, self._check_room)
            return
        waiting, self._waiting_for_room = self._waiting_for_room, []
        for callback in waiting:
            self._safely(callback)

    def _safely(self, callback: Callable[[], object]) -> None:
        try:
            callback()
        except Exception:  # a bug in one link must not stop every link of the node
            self.log.exception("A comms I/O callback failed; the other links carry on")

    # -- the node's thread, while idle (the node's IdleWaiter) ---------------
    def wait(self, timeout_s: Optional[float]) -> None:
        """Node thread, its queue empty: write what waits, take the read role, wait."""
        if self._to_write:  # what the handlers just queued goes before the node sleeps
            self.write_waiting()
        timeout = -1.0 if timeout_s is None else timeout_s
        if self._role_wanted:  # the loop's thread is closing a link: wait without reading
            _poll(self._wake_only, timeout)
            _drain(self._node_wake_r)
            return
        with self._role:  # not held on to `woken`: a Ctrl-C between would keep it
            self._node_ready = _poll(self._node_poll, timeout)

    def woken(self) -> None:
        """Node thread, no longer marked sleeping: read what arrived, holding the read role."""
        ready, self._node_ready = self._node_ready, None
        if ready:
            with self._role:
                try:
                    wake_fd = self._node_wake_r.fileno()
                    links = [event for event in ready if event[0] != wake_fd]
                    if len(links) < len(ready):
                        _drain(self._node_wake_r)
                    self._read_ready(links)
                except (OSError, ValueError):  # closed: the loop has stopped
                    pass
        self._busy_since = now = time.monotonic()
        if self._queue is not None and len(self._queue):  # work
            with self._looks_lock:  # _check_busy decides under it that the looks stop
                self._work_at = now
                start, self._looking = not self._looking, True
            if start:  # a long idle spell had stopped the looks
                self.call_soon(self._check_busy)

    def wake(self) -> None:
        """End the node thread's idle wait (any thread; the queue rings it once per sleep)."""
        try:
            self._node_wake_w.send(b"\0")
        except OSError:  # full (a wake-up is already waiting) or closed
            pass

    def _check_busy(self) -> None:
        """Loop thread: once the node's thread has worked `BUSY_READS_S`, read the links here.

        Runs every `BUSY_READS_S` while the node works, every `IDLE_CHECK_S`
        while it sleeps, and stops after `IDLE_STOP_S` without work (`woken`
        starts it again).
        """
        queue = self._queue
        if queue is None or not self._waiter_installed:  # the I/O thread reads all along
            self._looking = False
            return
        idle = queue.sleeping
        if idle:
            with self._looks_lock:  # (woken starts the looks again under it: none is lost)
                if time.monotonic() - self._work_at >= IDLE_STOP_S:
                    self._looking = False
                    return
        elif time.monotonic() - self._busy_since >= BUSY_READS_S:
            self._set_io_reads(True)
        self.call_later(IDLE_CHECK_S if idle else BUSY_READS_S, self._check_busy)

    def _set_io_reads(self, on: bool) -> None:
        """Loop thread: the I/O thread reads the links (its selector watches `_reads`), or not."""
        watched = self._reads in self._selector.get_map()
        if on and not watched:
            self._selector.register(self._reads, _READ, _READS)
        elif watched and not on:
            self._selector.unregister(self._reads)

    def _read_ready(self, ready: list[tuple[int, int]]) -> None:
        """Read every link with bytes (or an end) waiting; the caller holds the read role."""
        for fd, _ in ready:
            handler = self._readers.get(fd)
            if handler is not None:  # else forgotten meanwhile
                try:
                    handler.on_readable()
                except Exception:  # a bug in one link must not stop every link
                    self.log.exception("A comms link's read failed; the other links carry on")
                    self.call_soon(handler.on_io_stop)

    def _run(self) -> None:
        # This thread serves every link and stops reading a link by itself
        # while the node is behind: the tasks it schedules must never wait.
        if self._queue is not None:
            self._queue.never_wait(threading.get_ident())
        if self._reads is not None:
            self._looking = True
            self.call_later(BUSY_READS_S, self._check_busy)
        select, monotonic = self._selector.select, time.monotonic
        calls, timers, handlers = self._calls, self._timers, self._handlers
        try:
            while not self._stopping:
                timeout: Optional[float] = None
                if calls:
                    timeout = 0
                elif timers:
                    timeout = max(0.0, timers[0][0] - monotonic())
                for key, mask in select(timeout):
                    handler = key.data
                    if handler is None:
                        # Drain, then clear the flag, then run the calls: a call_soon
                        # that saw the flag set appended before it was cleared; one
                        # that sees it cleared rings again. (Clearing first lost wake-ups.)
                        _drain(self._wake_r)
                        self._woken = False
                    elif handler is _READS:  # the read set, while the node's thread is busy
                        if self._role.acquire(blocking=False):
                            try:
                                self._read_ready(self._reads.poll(0))
                            finally:
                                self._role.release()
                        else:  # the node's thread holds it: idle, it reads its links
                            self._set_io_reads(False)
                    else:  # not through _safely: this is every read's path
                        try:
                            if mask & _READ:
                                handler.on_readable()
                            if mask & _WRITE and handlers.get(handler, 0) & _WRITE:
                                handler.on_writable()
                        except Exception:  # a bug in one link must not stop every link
                            self.log.exception(
                                "A comms link's I/O failed; the other links carry on"
                            )
                            calls.append(handler.on_io_stop)  # or it would be ready again at once
                while calls:
                    self._safely(calls.popleft())
                if timers and timers[0][0] <= monotonic():
                    now = monotonic()
                    while timers and timers[0][0] <= now:
                        timer = heapq.heappop(timers)[2]
                        if not timer.cancelled:
                            self._safely(timer.callback)
        except Exception:  # the selector itself failed: close every link, say so
            self.log.exception("The comms I/O loop of node %r failed", self.node.role)
        finally:
            self._stopping = True
            for handler in list(handlers):
                self._safely(handler.on_io_stop)
            while calls:  # what was asked before the stop, e.g. a link's close
                self._safely(calls.popleft())
            self._selector.close()
            self._wake_r.close()
            self._wake_w.close()


def _wake_pair() -> tuple[socket.socket, socket.socket]:
    """Two connected non-blocking sockets: a byte written to one wakes a wait on the other."""
    ends = socket.socketpair()
    for end in ends:
        end.setblocking(False)
    return ends


def _poll(epoll: Any, timeout_s: float) -> list[tuple[int, int]]:
    """``epoll.poll(timeout_s)``; nothing if it is closed (the loop has stopped)."""
    try:
        return epoll.poll(timeout_s)  # type: ignore[no-any-return]
    except (OSError, ValueError):
        return []


def _drain(sock: socket.socket) -> None:
    """Read every wake-up byte waiting on a non-blocking socket."""
    try:
        while sock.recv(4096):
            pass
    except OSError:  # BlockingIOError: drained
        pass


class Transport(Protocol):
    """A non-blocking byte stream to one peer that the node's `IOLoop` watches (a socket, a pipe).

    The loop calls ``recv_into`` when ``fileno()`` is readable (the node's
    thread does while it is idle) and ``send`` when it is writable; the
    node's thread may call ``send`` too.

    Example: `SocketTransport` below.
    """

    peer: str
    """Where the peer is, for log messages, e.g. ``"127.0.0.1:9000"``."""

    def fileno(self) -> int:
        """The file descriptor the I/O loop watches."""

    def send(self, data: bytes) -> int:
        """Write what fits; how many bytes went (BlockingIOError: none; another OSError: gone)."""

    def recv_into(self, buffer: bytearray) -> int:
        """Read what arrived; 0 at end of stream (BlockingIOError: nothing yet; OSError: broken)."""

    def end_writing(self) -> None:
        """Tell the peer nothing more will be sent (after a graceful flush)."""

    def close(self) -> None:
        """Release the socket or pipe."""


def unread_bytes(fd: int) -> Optional[int]:
    """How many received bytes wait unread in the OS for ``fd``; None where it cannot say.

    A socket or pipe that is not read keeps what arrives; a link whose node is
    behind uses this to tell a peer that still talks from one that fell silent.

    Example::

        unread_bytes(sock.fileno())   # 0 when nothing waits
    """
    if _FIONREAD is None:
        return None
    try:
        return int(struct.unpack("i", fcntl.ioctl(fd, _FIONREAD, b"\0\0\0\0"))[0])
    except OSError:
        return None


class SocketTransport:
    """A connected TCP socket as a link ``Transport`` (non-blocking, ``TCP_NODELAY`` on).

    Example::

        SocketTransport(socket.create_connection(("localhost", 9000)), "localhost:9000", 5.0)
    """

    def __init__(self, sock: socket.socket, peer: str, dead_after_s: float) -> None:
        # No Nagle; a peer that vanished (cable pulled) is noticed in ~10 s, and
        # unacknowledged data given up after dead_after_s, not 15 minutes (Linux).
        options = [
            (socket.IPPROTO_TCP, "TCP_NODELAY", 1),
            (socket.SOL_SOCKET, "SO_KEEPALIVE", 1),
            (socket.IPPROTO_TCP, "TCP_KEEPIDLE", 5),
            (socket.IPPROTO_TCP, "TCP_KEEPINTVL", 2),
            (socket.IPPROTO_TCP, "TCP_KEEPCNT", 3),
            (socket.IPPROTO_TCP, "TCP_USER_TIMEOUT", int(dead_after_s * 1000)),
        ]
        for level, option, value in options:
            if hasattr(socket, option):
                try:
                    sock.setsockopt(level, getattr(socket, option), value)
                except OSError:
                    pass
        sock.setblocking(False)
        self.sock = sock
        self.peer = peer

    def fileno(self) -> int:
        """The socket's file descriptor."""
        return self.sock.fileno()

    def send(self, data: bytes) -> int:
        """Write what fits now (BlockingIOError if nothing does)."""
        return self.sock.send(data)

    def recv_into(self, buffer: bytearray) -> int:
        """Read what has arrived; 0 when the peer closed (BlockingIOError if nothing has)."""
        return self.sock.recv_into(buffer)

    def end_writing(self) -> None:
        """Half-close: the peer reads to the end, then sees end of stream."""
        try:
            self.sock.shutdown(socket.SHUT_WR)
        except OSError:
            pass

    def close(self) -> None:
        """Release the socket."""
        self.sock.close()
