"""The socket transport: `SocketTransport` over TCP, and the `IOLoop` that serves every link.

A link talks over a `Transport`: a non-blocking byte stream (a TCP socket,
`SocketTransport`; a pipe end, ``pipe.py``). Every link of a node is a
handler of the node's one `IOLoop`: a ``selectors`` loop on one thread,
``snr-<role>-io``, that reads when a socket has bytes, writes when one has
room, and runs the links' timers (beats, silence, paused readers). So a
server with hundreds of idle clients costs no more threads than one with one.

While the node's own thread has nothing to do, *it* reads the links (Linux,
with ``epoll``): the loop is the node's `snr.core.task_queue.IdleWaiter`, so
a page that arrives is read, decoded and queued on the node's thread with no
hand-off (docs/performance.md). While the node's thread runs handlers, the
I/O thread reads, so a slow handler never stops a link from being read,
beating or noticing a dead peer. One lock, the *read role*, decides which of
the two reads (`IOLoop.wait`). Why and how: docs/design.md, "One I/O thread
per node".

The loop is shared: every comms component of a node gets it with
`IOLoop.acquire` (the first starts its thread) and gives it back with
`IOLoop.release` (the last stops and joins it, within a bound).

Example::

    io = IOLoop.acquire(node)        # starts the thread "snr-<role>-io"
    io.call_soon(lambda: io.watch(handler, selectors.EVENT_READ))
    ...
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
from typing import Any, Callable, Deque, Dict, Iterator, List, Optional, Protocol, Tuple

from snr.core.node import Node
from snr.core.task_queue import TaskQueue
from snr.prelude import AbstractNode

try:  # Linux and macOS say how many bytes wait unread; Windows has no fcntl
    import fcntl
    import termios

    _FIONREAD: Optional[int] = termios.FIONREAD
except ImportError:
    _FIONREAD = None

__all__ = ["IOHandler", "IOLoop", "IOTimer", "SocketTransport", "Transport", "unread_bytes"]

RECV_BYTES = 256 * 1024
"""Size of the loop's one receive buffer, shared by all its links (only its thread reads)."""

ROOM_CHECK_S = 0.015
"""While a link has stopped reading because the node is behind, how often room is checked."""

BUSY_READS_S = 0.05
"""After the node's thread has been busy this long, the I/O thread reads its links too."""

IDLE_CHECK_S = 0.25
"""While the node's thread sleeps, how often the I/O thread looks whether it is busy again."""

IDLE_STOP_S = 1.0
"""After this long with no work for the node's thread, the I/O thread stops looking.

An idle node then costs its I/O thread no wake-up at all; the node's thread
starts the looks again when it next leaves its wait with work (`IOLoop.woken`).
"""

JOIN_TIMEOUT_S = 1.0
"""How long the last `IOLoop.release` waits for the thread to end."""

WRITE_DELAY_S = 0.001
"""How long frames queued by another thread wait for it to write them before the loop does."""

_READ = selectors.EVENT_READ
_WRITE = selectors.EVENT_WRITE
_READS = "reads"  # the selector key of the links' read set (the wake-up socket's is None)
_HAS_EPOLL = hasattr(select, "epoll")


class IOHandler(Protocol):
    """What the loop serves: a link over something with a ``fileno()``.

    The loop calls these on its own thread; they must not block.

    Example: ``Link`` in ``comms_loop.py``.
    """

    def fileno(self) -> int:
        """The file descriptor to watch (a socket's)."""

    def on_readable(self) -> None:
        """Bytes (or end of stream) can be read without blocking."""

    def on_writable(self) -> None:
        """Some bytes can be written without blocking."""

    def on_io_stop(self) -> None:
        """The loop is stopping: close now (a last resort; owners close links first)."""

    def write_waiting(self) -> None:
        """Not the loop's thread: write what waits, without blocking (see `IOLoop.write_soon`)."""


class IOTimer:
    """A callback `IOLoop.call_later` will run once; ``cancel()`` takes it back.

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
# id(node) -> (node, its loop). The node is kept so an id cannot be reused
# by another node while the loop is registered.
_registry: Dict[int, Tuple[AbstractNode, IOLoop]] = {}


class IOLoop:
    """One selector thread serving the sockets of every comms link of one node.

    Only the loop's thread touches the selector; other threads ask it for
    things with `call_soon` (thread-safe: it appends to a queue and wakes the
    selector through a socket pair). The handlers' sockets are read by the
    thread that holds the *read role*: the node's thread while it is idle
    (`wait`, `woken`: it is the node's `snr.core.task_queue.IdleWaiter`), else the loop's thread.

    Get it with `acquire` and give it back with `release`, never by
    constructing it yourself in a component.

    Example::

        io = IOLoop.acquire(node)
        io.call_soon(lambda: io.watch(link, selectors.EVENT_READ))
        io.release()

    Attributes:
        node: the node whose links it serves.
        buffer: the receive buffer handlers read into (by the read role's holder).
        view: a ``memoryview`` of ``buffer``.
    """

    node_reads: bool = _HAS_EPOLL
    """Let the node's thread read the links while it is idle (needs epoll: Linux).

    Where it is False (or set so), the I/O thread reads every link and hands
    the pages over to the node's thread, which is correct everywhere, only
    slower.
    """

    def __init__(self, node: AbstractNode) -> None:
        self.node = node
        self.log = logging.getLogger(f"snr.{node.role}.io")
        self.buffer = bytearray(RECV_BYTES)
        self.view = memoryview(self.buffer)
        self._users = 0
        self._selector = selectors.DefaultSelector()
        self._handlers: Dict[IOHandler, int] = {}  # every watched handler: its events
        self._calls: Deque[Callable[[], object]] = collections.deque()
        self._timers: List[Tuple[float, int, IOTimer]] = []
        self._order = itertools.count()  # ties in the timer heap never compare IOTimers
        self._waiting_for_room: List[Callable[[], None]] = []
        # Handlers with frames another thread queued (write_soon): a dict, so
        # that a handler is listed once however many bursts it queues.
        self._to_write: Dict[IOHandler, None] = {}
        self._room_timer: Optional[IOTimer] = None
        self._stopping = False
        self._wake_r, self._wake_w = _wake_pair()
        self._woken = False
        self._selector.register(self._wake_r, _READ, None)
        self._thread = threading.Thread(target=self._run, name=f"snr-{node.role}-io", daemon=True)
        # With node reads: every link watched for reading is in `_reads` (an
        # epoll set) and in `_node_poll`, never in the selector. The selector
        # watches `_gate`, which holds `_reads` while the I/O thread reads the
        # links (the node's thread has been busy for BUSY_READS_S); the
        # node's thread takes `_reads` out of it before it waits, so the two
        # threads are never woken for the same bytes. Between two short busy
        # spells the gate stays shut: no epoll_ctl calls per task.
        self._reads: Any = None
        self._gate: Any = None
        self._node_poll: Any = None
        self._readers: Dict[int, IOHandler] = {}  # fd -> handler, for `_reads`
        self._role = threading.RLock()  # the read role: whoever holds it reads
        self._node_waiting = False  # the node's thread holds the role in wait()
        self._role_wanted = False  # the loop's thread waits for the role: leave it
        self._waiter_installed = False  # the node waits on this loop when idle
        self._node_ready: List[Tuple[int, int]] = []
        self._gate_lock = threading.Lock()  # opening and shutting the gate, and _node_idle
        self._gate_open = False  # `_reads` is in `_gate`: the I/O thread reads
        self._node_idle = False  # the node's thread is in wait(): never open the gate
        self._busy_since = 0.0  # when the node's thread last left wait()
        self._work_at = 0.0  # when it last left wait() with work to do
        self._looking = False  # _check_busy is due (else it waits for the node's work)
        self._queue = _queue_of(node)
        if self.node_reads:
            self._reads = select.epoll()
            self._gate = select.epoll()
            self._gate.register(self._reads.fileno(), select.EPOLLIN)
            self._gate_open = True  # until the node's thread first waits
            self._selector.register(self._gate.fileno(), _READ, _READS)
            self._node_wake_r, self._node_wake_w = _wake_pair()
            self._node_poll = select.epoll()
            self._node_poll.register(self._node_wake_r.fileno(), select.EPOLLIN)
            self._node_wake_only = select.epoll()  # while the loop's thread wants the role
            self._node_wake_only.register(self._node_wake_r.fileno(), select.EPOLLIN)

    # -- sharing one loop per node ------------------------------------------
    @classmethod
    def acquire(cls, node: AbstractNode) -> IOLoop:
        """The node's I/O loop, started if this is its first user.

        Example::

            io = IOLoop.acquire(self.parent)   # in a comms component's start
        """
        with _registry_lock:
            entry = _registry.get(id(node))
            if entry is not None and entry[0] is node:
                loop = entry[1]
            else:
                loop = cls(node)
                _registry[id(node)] = (node, loop)
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
            entry = _registry.get(id(self.node))
            if entry is not None and entry[1] is self:
                del _registry[id(self.node)]
        self.stop()

    def stop(self, timeout_s: float = JOIN_TIMEOUT_S) -> None:
        """End the thread (it closes what is still watched) and wait up to ``timeout_s``."""
        if self._waiter_installed and self._queue is not None:
            self._waiter_installed = False
            self._queue.stop_waiter(self)  # the node waits on its bell again
        self._stopping = True
        self._wake()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)
            if self._thread.is_alive():
                self.log.warning(
                    "The comms I/O thread of node %r did not stop within %.1f s.",
                    self.node.role,
                    timeout_s,
                )
                return
        if self._reads is not None and not self._thread.is_alive():
            for closable in (
                self._node_poll,
                self._node_wake_only,
                self._gate,
                self._reads,
                self._node_wake_r,
                self._node_wake_w,
            ):
                closable.close()

    def is_alive(self) -> bool:
        """True while the loop's thread runs."""
        return self._thread.is_alive()

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

    def write_soon(self, handler: IOHandler) -> None:
        """``handler`` has frames to write, queued by a thread that is not the loop's.

        The node's thread writes them itself when it next goes idle (`wait`),
        or sooner (a link writes a big backlog at once); the loop's thread
        writes what is still waiting `WRITE_DELAY_S` later. So a burst of
        pages stored by the node's handlers goes out in a few ``send`` calls,
        made by the thread that already holds the interpreter, instead of
        waking the I/O thread for each handful of pages.

        Example::

            io.write_soon(link)   # link.write_waiting() or link.on_writable() will follow
        """
        self._to_write[handler] = None
        self.call_soon(lambda: self.call_later(WRITE_DELAY_S, handler.on_writable))

    def write_waiting(self) -> None:
        """Not the loop's thread: let every handler given to `write_soon` write what waits."""
        to_write = self._to_write
        while to_write:
            try:
                handler = to_write.popitem()[0]
            except KeyError:  # emptied meanwhile
                return
            try:
                handler.write_waiting()
            except Exception:  # a bug in one link must not stop the node
                self.log.exception("A comms link's write failed; the I/O thread retries it")

    def _wake(self) -> None:
        self._woken = True
        try:
            self._wake_w.send(b"\0")
        except OSError:  # full (it is already awake) or closed (it has stopped)
            pass

    # -- loop thread only ---------------------------------------------------
    def watch(self, handler: IOHandler, events: int) -> None:
        """Serve ``handler`` for ``events`` (0: keep it, but select nothing for now)."""
        old = self._handlers.get(handler, 0)
        if old == events and handler in self._handlers:
            return
        self._handlers[handler] = events
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
                    self._readers.pop(fd, None)
            old, events = old & _WRITE, events & _WRITE
        if old:
            if events:
                self._selector.modify(handler, events, handler)
            else:
                self._selector.unregister(handler)
        elif events:
            self._selector.register(handler, events, handler)

    def events(self, handler: IOHandler) -> int:
        """The events ``handler`` is watched for (0 if none or not watched)."""
        return self._handlers.get(handler, 0)

    def forget(self, handler: IOHandler) -> None:
        """Stop serving ``handler`` (before its socket is closed)."""
        if self._handlers.get(handler):
            self.watch(handler, 0)
        self._handlers.pop(handler, None)

    @contextlib.contextmanager
    def read_role(self) -> Iterator[None]:
        """Hold the read role (loop thread), e.g. to close a link's socket.

        No other thread then reads any link. If the node's thread holds it
        in its idle wait, it is woken to give it back (a rare event: a link
        ends).

        Example::

            with io.read_role():
                transport.close()
        """
        if not self._role.acquire(blocking=False):
            self._role_wanted = True  # the node's thread leaves it to us until we are done
            self.wake()
            self._role.acquire()
        try:
            yield
        finally:
            self._role_wanted = False
            self._role.release()

    # -- the node's thread, while idle (the node's IdleWaiter) ---------------
    def wait(self, timeout_s: Optional[float]) -> None:
        """Node thread, its queue empty: wait for a task or for bytes on a link.

        The read set leaves the I/O thread's gate first (if it was in it), so
        that thread is not woken for bytes the node's thread reads; then the
        node's thread takes the read role (waiting, briefly, for a read the
        I/O thread has begun) and waits on the links and its own wake-up
        socket.
        """
        if self._to_write:  # what the handlers just queued goes before the node sleeps
            self.write_waiting()
        timeout = -1.0 if timeout_s is None else timeout_s
        if self._role_wanted:  # the loop's thread is closing a link: wait without reading
            self._node_ready = _poll(self._node_wake_only, timeout)
            _drain(self._node_wake_r)
            return
        with self._gate_lock:
            self._node_idle = True
            if self._gate_open:
                try:
                    self._gate.unregister(self._reads.fileno())
                except (OSError, ValueError):  # closed: the loop has stopped
                    return
                self._gate_open = False
        self._role.acquire()
        self._node_waiting = True
        self._node_ready = _poll(self._node_poll, timeout)

    def woken(self) -> None:
        """Node thread, no longer marked sleeping: read what arrived, give the role back.

        The gate stays shut: the node's thread will read again when it next
        waits, which is soon unless a handler takes long; after
        `BUSY_READS_S` of work the I/O thread opens it and reads meanwhile.
        """
        if not self._node_waiting:
            return
        try:
            wake_fd = self._node_wake_r.fileno()
            ready = self._node_ready
            if len(ready) != 1 or ready[0][0] == wake_fd:  # not just one link's bytes
                ready = [event for event in ready if event[0] != wake_fd]
                if len(ready) < len(self._node_ready):
                    _drain(self._node_wake_r)
            if ready:
                self._read_ready(ready, on_node=True)
        except (OSError, ValueError):  # closed: the loop has stopped
            pass
        finally:
            self._node_ready = []
            self._node_waiting = False
            look = False
            with self._gate_lock:
                self._busy_since = now = time.monotonic()
                self._node_idle = False
                if self._queue is not None and len(self._queue):
                    self._work_at = now
                    look = not self._looking
                    self._looking = True
            self._role.release()
            if look:  # the I/O thread had stopped looking (a long idle spell)
                self.call_soon(self._check_busy)

    def _check_busy(self) -> None:
        """Loop thread: once the node's thread has worked `BUSY_READS_S`, read its links too.

        Runs every `BUSY_READS_S` while the node's thread works, every
        `IDLE_CHECK_S` while it sleeps between pieces of work, and not at all
        once it has had no work for `IDLE_STOP_S`: an idle node costs its I/O
        thread no wake-up. `woken` starts the looks again; the lock makes
        sure the node's thread never leaves its wait with work while the
        looks stop unseen.
        """
        if not self._waiter_installed:  # the node waits on another's: the gate stays open
            self._looking = False
            return
        with self._gate_lock:
            idle = self._node_idle
            if idle and time.monotonic() - self._work_at >= IDLE_STOP_S:
                self._looking = False
                return
            self._looking = True
        self.call_later(IDLE_CHECK_S if idle else BUSY_READS_S, self._check_busy)
        with self._gate_lock:
            if self._node_idle or self._gate_open:
                return
            if time.monotonic() - self._busy_since < BUSY_READS_S:
                return
            try:
                self._gate.register(self._reads.fileno(), select.EPOLLIN)
            except (OSError, ValueError):  # closed: the loop is stopping
                return
            self._gate_open = True

    def _look_if_busy(self) -> None:
        """Loop thread, on a timer: start looking if the node's thread works unseen.

        It can get work without leaving a wait with it (a task queued a moment
        after it woke); then the looks start again within a timer's period.
        """
        with self._gate_lock:
            if self._looking or self._node_idle:
                return
            self._looking = True
        self.call_later(BUSY_READS_S, self._check_busy)

    def wake(self) -> None:
        """End the node thread's idle wait (any thread; the queue rings it once per sleep)."""
        try:
            self._node_wake_w.send(b"\0")
        except OSError:  # full (a wake-up is already waiting) or closed
            pass

    def _read_ready(self, ready: List[Tuple[int, int]], on_node: bool) -> None:
        """Read every link with bytes (or an end) waiting; the caller holds the read role."""
        readers = self._readers
        for fd, _ in ready:
            handler = readers.get(fd)
            if handler is None:  # forgotten meanwhile
                continue
            try:
                handler.on_readable()
            except Exception:  # a bug in one link must not stop every link
                self.log.exception("A comms link's read failed; the other links carry on")
                if on_node:
                    self.call_soon(handler.on_io_stop)
                else:
                    self._safely(handler.on_io_stop)

    def _serve_reads(self) -> None:
        """Loop thread: the read set has bytes, and the node's thread is busy."""
        if not self._role.acquire(blocking=False):
            return  # the node's thread took the role: it reads them
        try:
            self._read_ready(self._reads.poll(0), on_node=False)
        finally:
            self._role.release()

    def call_later(self, delay_s: float, callback: Callable[[], None]) -> IOTimer:
        """Run ``callback`` on the loop's thread after ``delay_s`` seconds."""
        timer = IOTimer(time.monotonic() + delay_s, callback)
        heapq.heappush(self._timers, (timer.when, next(self._order), timer))
        return timer

    def when_room(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` once the node's queue is below its high-water mark.

        Checked every `ROOM_CHECK_S` for all waiting links together, so a
        paused reader costs the loop nothing in between.
        """
        self._waiting_for_room.append(callback)
        if self._room_timer is None:
            self._room_timer = self.call_later(ROOM_CHECK_S, self._check_room)

    def _check_room(self) -> None:
        self._room_timer = None
        if not self._waiting_for_room:
            return
        if not self.node.wait_for_room(0):
            self._room_timer = self.call_later(ROOM_CHECK_S, self._check_room)
            return
        waiting, self._waiting_for_room = self._waiting_for_room, []
        for callback in waiting:
            self._safely(callback)

    def _safely(self, callback: Callable[[], object]) -> None:
        try:
            callback()
        except Exception:  # a bug in one link must not stop every link of the node
            self.log.exception("A comms I/O callback failed; the other links carry on")

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
                        self._drain_wake()
                        continue
                    if handler is _READS:
                        self._serve_reads()
                        continue
                    # Inline rather than through _safely: this is every read's path.
                    try:
                        if mask & _READ:
                            handler.on_readable()
                        if mask & _WRITE and handlers.get(handler, 0) & _WRITE:
                            handler.on_writable()
                    except Exception:  # a bug in one link must not stop every link
                        self.log.exception("A comms link's I/O failed; the other links carry on")
                        self._safely(handler.on_io_stop)  # or it would be ready again at once
                while calls:
                    self._safely(calls.popleft())
                if timers and timers[0][0] <= monotonic():
                    now = monotonic()
                    while timers and timers[0][0] <= now:
                        timer = heapq.heappop(timers)[2]
                        if not timer.cancelled:
                            self._safely(timer.callback)
                    if not self._looking and self._waiter_installed:
                        self._look_if_busy()
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

    def _drain_wake(self) -> None:
        # Drain first, then clear the flag, then (in _run) run the calls. A
        # call_soon that saw the flag still set appended before it was
        # cleared, so the calls run after this see it; one that sees it
        # cleared rings again, and that byte stays until the next select.
        # (Clearing first lost wake-ups: a byte rung between the clearing and
        # the draining was drained with the rest, leaving the flag set with
        # nothing to wake the selector, so later calls waited for a timer, or
        # for ever on a loop with no timers, such as a client between links.)
        _drain(self._wake_r)
        self._woken = False


def _queue_of(node: AbstractNode) -> Optional[TaskQueue]:
    """A `Node`'s task queue; None for another `AbstractNode` (a mock), which has none."""
    return node.queue if isinstance(node, Node) else None


def _wake_pair() -> Tuple[socket.socket, socket.socket]:
    """A connected pair of non-blocking sockets: a byte written to one wakes a wait on the other."""
    ends = socket.socketpair()
    for end in ends:
        end.setblocking(False)
    return ends


def _poll(epoll: Any, timeout_s: float) -> List[Tuple[int, int]]:
    """``epoll.poll(timeout_s)``; nothing if it is closed (the loop has stopped)."""
    try:
        ready: List[Tuple[int, int]] = epoll.poll(timeout_s)
    except (OSError, ValueError):
        return []
    return ready


def _drain(sock: socket.socket) -> None:
    """Read every wake-up byte waiting on a non-blocking socket."""
    try:
        while sock.recv(4096):
            pass
    except OSError:  # BlockingIOError: drained
        pass


# -- transports: what a link reads and writes ------------------------------


class Transport(Protocol):
    """A byte stream to one peer that the node's `IOLoop` can watch: a TCP socket or a pipe.

    Every method returns at once (the file descriptor is non-blocking): the
    loop calls ``recv_into`` when ``fileno()`` is readable and ``send`` when
    it is writable, and the node's thread may call ``send`` too (under the
    outbox's lock) to write a frame straight away.

    Example: `SocketTransport` below.
    """

    peer: str
    """Where the peer is, for log messages, e.g. ``"127.0.0.1:9000"``."""

    def fileno(self) -> int:
        """The file descriptor the I/O loop watches."""

    def send(self, data: bytes) -> int:
        """Write what fits without blocking; how many bytes went.

        Raises BlockingIOError if nothing fits, another OSError if the peer is gone.
        """

    def recv_into(self, buffer: bytearray) -> int:
        """Read what has arrived into ``buffer``; 0 at end of stream.

        Raises BlockingIOError if nothing has arrived, another OSError if the link broke.
        """

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
        answer = fcntl.ioctl(fd, _FIONREAD, b"\0\0\0\0")
    except OSError:
        return None
    return int(struct.unpack("i", answer)[0])


def _enable_keepalive(sock: socket.socket) -> None:
    """Notice a peer that vanished without a word (cable pulled) in ~10 s, not hours."""
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
    for option, value in (("TCP_KEEPIDLE", 5), ("TCP_KEEPINTVL", 2), ("TCP_KEEPCNT", 3)):
        if hasattr(socket, option):  # Linux; other systems keep their defaults
            try:
                sock.setsockopt(socket.IPPROTO_TCP, getattr(socket, option), value)
            except OSError:
                pass


def _limit_unacknowledged(sock: socket.socket, seconds: float) -> None:
    """Give up on data the peer has not acknowledged for ``seconds`` (Linux).

    Without it, a sender on a path that vanished (Wi-Fi out of range: no FIN,
    no RST) keeps retransmitting for about 15 minutes.
    """
    option = getattr(socket, "TCP_USER_TIMEOUT", None)
    if option is not None:
        try:
            sock.setsockopt(socket.IPPROTO_TCP, option, int(seconds * 1000))
        except OSError:
            pass


class SocketTransport:
    """A connected TCP socket as a link ``Transport`` (non-blocking, ``TCP_NODELAY`` on).

    The node's I/O loop watches it; nothing here ever blocks.

    Example::

        SocketTransport(socket.create_connection(("localhost", 9000)), "localhost:9000")
    """

    def __init__(
        self,
        sock: socket.socket,
        peer: str,
        dead_after_s: float,
    ) -> None:
        sock.setblocking(False)
        # Every frame is written in one call; without this, Nagle's algorithm
        # holds small frames back for up to ~40-200 ms.
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        _enable_keepalive(sock)
        _limit_unacknowledged(sock, dead_after_s)
        self.sock = sock
        self.peer = peer

    def fileno(self) -> int:
        """The socket's file descriptor."""
        return self.sock.fileno()

    def send(self, data: bytes) -> int:
        """Write what fits now; raises BlockingIOError if nothing does."""
        return self.sock.send(data)

    def recv_into(self, buffer: bytearray) -> int:
        """Read what has arrived; 0 when the peer closed; BlockingIOError if nothing has."""
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
