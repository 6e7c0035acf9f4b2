"""`IOLoop`: one thread per node serves every comms socket, however many peers connect.

A comms link used to cost two threads (a reader and a writer), so a server
with hundreds of idle clients cost hundreds of threads, and once enough
connections exhausted the process's threads the server could accept no more.
Now every link of a node (each accepted or made TCP connection, each pipe)
is a handler registered with the node's single `IOLoop`: a
``selectors.DefaultSelector`` loop on one thread named ``snr-<role>-io``
that reads when a socket has bytes, writes when one has room, and runs the
links' timers (beats, silence checks, paused readers). The node's thread
count stays the same whatever the number of peers.

The loop is shared: every comms component of a node gets the same one with
`IOLoop.acquire` (the first starts its thread) and gives it back with
`IOLoop.release` (the last stops and joins it, within a bound), so it never
outlives its node.

Example::

    io = IOLoop.acquire(node)        # starts the thread "snr-<role>-io"
    io.call_soon(lambda: io.watch(handler, selectors.EVENT_READ))
    ...
    io.release()                     # the last user stops and joins it
"""

from __future__ import annotations

import collections
import heapq
import itertools
import logging
import selectors
import socket
import threading
import time
from typing import Callable, Deque, Dict, List, Optional, Protocol, Tuple

from snr.prelude import AbstractNode

__all__ = ["IOHandler", "IOLoop", "IOTimer"]

RECV_BYTES = 256 * 1024
"""Size of the loop's one receive buffer, shared by all its links (only its thread reads)."""

ROOM_CHECK_S = 0.015
"""While a link has stopped reading because the node is behind, how often room is checked."""

JOIN_TIMEOUT_S = 1.0
"""How long the last `IOLoop.release` waits for the thread to end."""

_READ = selectors.EVENT_READ
_WRITE = selectors.EVENT_WRITE


class IOHandler(Protocol):
    """What the loop serves: a link over something with a ``fileno()``.

    The loop calls these on its own thread; they must not block.

    Example: ``Link`` in ``link.py``.
    """

    def fileno(self) -> int:
        """The file descriptor to watch (a socket's)."""

    def on_readable(self) -> None:
        """Bytes (or end of stream) can be read without blocking."""

    def on_writable(self) -> None:
        """Some bytes can be written without blocking."""

    def on_io_stop(self) -> None:
        """The loop is stopping: close now (a last resort; owners close links first)."""


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

    Only the loop's thread touches the selector and the handlers' sockets for
    reading; other threads ask it for things with `call_soon` (thread-safe:
    it appends to a queue and wakes the selector through a socket pair).

    Get it with `acquire` and give it back with `release`, never by
    constructing it yourself in a component.

    Example::

        io = IOLoop.acquire(node)
        io.call_soon(lambda: io.watch(link, selectors.EVENT_READ))
        io.release()

    Attributes:
        node: the node whose links it serves.
        buffer: the receive buffer handlers read into (loop thread only).
        view: a ``memoryview`` of ``buffer``.
    """

    def __init__(self, node: AbstractNode) -> None:
        self.node = node
        self.log = logging.getLogger(f"snr.{node.role}.io")
        self.buffer = bytearray(RECV_BYTES)
        self.view = memoryview(self.buffer)
        self._users = 0
        self._selector = selectors.DefaultSelector()
        self._handlers: Dict[IOHandler, int] = {}  # every watched handler: its events
        self._calls: Deque[Callable[[], None]] = collections.deque()
        self._timers: List[Tuple[float, int, IOTimer]] = []
        self._order = itertools.count()  # ties in the timer heap never compare IOTimers
        self._waiting_for_room: List[Callable[[], None]] = []
        self._room_timer: Optional[IOTimer] = None
        self._stopping = False
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._woken = False
        self._selector.register(self._wake_r, _READ, None)
        self._thread = threading.Thread(target=self._run, name=f"snr-{node.role}-io", daemon=True)

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

    def is_alive(self) -> bool:
        """True while the loop's thread runs."""
        return self._thread.is_alive()

    def in_loop_thread(self) -> bool:
        """True when called on the loop's own thread."""
        return threading.current_thread() is self._thread

    # -- any thread ---------------------------------------------------------
    def call_soon(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` on the loop's thread, in the order of the calls (any thread).

        Example::

            io.call_soon(link.on_writable)
        """
        self._calls.append(callback)
        if not self._woken:
            self._wake()

    def _wake(self) -> None:
        self._woken = True
        try:
            self._wake_w.send(b"\0")
        except OSError:  # full (it is already awake) or closed (it has stopped)
            pass

    # -- loop thread only ---------------------------------------------------
    def watch(self, handler: IOHandler, events: int) -> None:
        """Serve ``handler`` for ``events`` (0: keep it, but select nothing for now)."""
        old = self._handlers.get(handler)
        if old == events:
            return
        self._handlers[handler] = events
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
        if self._handlers.pop(handler, 0):
            self._selector.unregister(handler)

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

    def _safely(self, callback: Callable[[], None]) -> None:
        try:
            callback()
        except Exception:  # a bug in one link must not stop every link of the node
            self.log.exception("A comms I/O callback failed; the other links carry on")

    def _run(self) -> None:
        # This thread serves every link and stops reading a link by itself
        # while the node is behind: the tasks it schedules must never wait.
        self.node._snr_never_wait()
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
        try:
            while self._wake_r.recv(4096):
                pass
        except OSError:  # BlockingIOError: drained
            pass
        self._woken = False
