"""`TaskQueue`: the thread-safe queue between loops and the node's thread.

Two deques: ``urgent`` for high-priority tasks (terminate) and ``normal`` for
the rest, each FIFO. ``deque.append``/``popleft`` are atomic in CPython, so
producers never take a lock.

**How an idle node waits.** When its queue is empty, the node's thread sleeps
in `TaskQueue.wait` (until a task comes or it stops), and producers wake it only while it
sleeps: an idle node uses no CPU, and a busy one pays nothing for waking.
What it sleeps on is the queue's *bell*, a ``queue.SimpleQueue`` (a blocking
get with a timeout), unless something else was installed with `use_waiter`:
an `IdleWaiter`, the one way to change how an idle node waits. SNR has three:
a `SimClock`'s turn (an idle node gives the clock back), the socket comms'
I/O loop and Zenoh's idle reader (an idle node reads its links itself, so a
page that arrives needs no hand-off from another thread).

The queue is bounded by a *high-water mark* (``high_water``, 10,000 tasks by
default). A task offered by another thread (a loop's ``store_data``) while the
normal lane is above it waits until the node has worked the lane down to the
*low-water mark* (half the high one): a loop that produces faster than the
node can handle is slowed to the node's pace (backpressure). If the node does
not catch up within ``max_wait_s`` (1 s) the waiting task is dropped, counted
and logged (at most once a second, with numbers), so a stuck node can never
fill the memory. Tasks the node's own handlers return never wait (the node
would wait on itself) and urgent tasks (terminate) never wait or drop.
Readers of sockets ask `wait_for_room(0)` and stop reading instead of waiting.
"""

from __future__ import annotations

import collections
import logging
import queue
import sys
import threading
import time
from types import FrameType
from typing import Deque, Dict, Optional, Protocol, Set, Tuple

from snr.core.checks.call_checks import check_schedule_args
from snr.core.logs import LossReport
from snr.prelude import AbstractTaskQueue, SomeTasks, Task
from snr.prelude.student_code import outside_runtime

__all__ = ["IdleWaiter", "TaskQueue"]


class IdleWaiter(Protocol):
    """What a node's thread sleeps on while its queue is empty, instead of the bell.

    The one extension point for how an idle node waits (see `TaskQueue.use_waiter`).
    The queue calls ``wait`` while it counts the node as sleeping, then
    ``woken`` once it no longer does, on the node's thread; producers call
    ``wake`` (any thread), only while the node sleeps.

    Example (a waiter that sleeps on an Event, as the bell does)::

        class EventWaiter:
            def __init__(self) -> None:
                self.event = threading.Event()

            def wait(self, timeout_s: Optional[float]) -> None:
                self.event.wait(timeout_s)
                self.event.clear()

            def woken(self) -> None:
                pass

            def wake(self) -> None:
                self.event.set()

        node.queue.use_waiter(EventWaiter())
    """

    def wait(self, timeout_s: Optional[float]) -> None:
        """Block until ``wake()``, work of the waiter's own, or ``timeout_s`` (None: no limit)."""

    def woken(self) -> None:
        """After ``wait`` (or instead of it): do the work it found, e.g. queue what it read."""

    def wake(self) -> None:
        """End a ``wait`` in progress, or the next one (any thread)."""


class TaskQueue(AbstractTaskQueue):
    """FIFO of tasks where high-priority tasks jump ahead; bounded, with backpressure.

    Args:
        high_water: tasks in the normal lane above which other threads wait.
        max_wait_s: how long such a thread waits before its task is dropped.
        log: where drops are reported (default: the ``snr`` logger).

    Example::

        queue = TaskQueue()
        queue.schedule([tasks.event("a"), tasks.terminate("done")])
        queue.get().type      # TaskType.terminate (it jumped ahead)
        queue.get().name      # 'a'

    Attributes:
        normal: the FIFO lane of ordinary tasks (the node pops from it).
        urgent: the lane of high-priority tasks, served first.
        owner_thread: the consuming thread's id (set by the node as it
            starts); tasks it schedules itself never wait.
        holds_back: ids of other threads that never wait here because they
            hold back on their own (a socket I/O thread stops reading); see
            `never_wait`.
        waits: how many times a producer had to wait for space.
        waits_by_thread: the same, for each thread id that had to wait (the
            watchdog names a loop that floods the queue with it).
        waited_at: for each thread id that had to wait, the caller's frame
            outside SNR and its line at the last wait (the watchdog shows it).
        sleeping: True while the node's thread sleeps in `wait` (any thread may look).
        waiter: the `IdleWaiter` the node sleeps on instead of the bell, or None.
    """

    def __init__(
        self,
        high_water: int = 10_000,
        max_wait_s: float = 1.0,
        log: Optional[logging.Logger] = None,
    ) -> None:
        if high_water < 2:
            raise ValueError(f"high_water must be at least 2, not {high_water}")
        self.normal: Deque[Task] = collections.deque()
        self.urgent: Deque[Task] = collections.deque()
        self.high_water = high_water
        self.low_water = high_water // 2
        self.max_wait_s = max_wait_s
        self.owner_thread: Optional[int] = None
        self.holds_back: Set[int] = set()
        self.waits = 0
        self.waits_by_thread: Dict[int, int] = {}
        self.waited_at: Dict[int, Tuple[FrameType, int]] = {}
        self.loss = LossReport(
            log or logging.getLogger("snr"),
            "tasks from other threads",
            f"the node's queue held over {high_water:,} tasks for {max_wait_s:g} s; the "
            "node cannot keep up (a slow handler, or a loop storing data too fast)",
        )
        self._bell: queue.SimpleQueue[None] = queue.SimpleQueue()
        self.waiter: Optional[IdleWaiter] = None
        self.sleeping = False
        self._rung = False
        self._closed = threading.Event()

    def put(self, task: Task) -> None:
        """Queue one task. Any thread; what `schedule` does with a single `Task`.

        From a thread other than the node's, this may wait while the queue is
        above its high-water mark, and drop the task if it stays there.

        Example::

            queue.put(tasks.event("go"))
        """
        if task.priority:
            self.urgent.append(task)
        elif len(self.normal) < self.high_water or self._make_room():
            self.normal.append(task)
        else:
            return
        if self.sleeping and not self._rung:  # ring once per sleep
            self._ring()

    def schedule(self, t: SomeTasks) -> None:
        """Queue a task, a list of tasks, or nothing (None). Any thread.

        From a thread other than the node's, this may wait while the queue is
        above its high-water mark, and drop the task if it stays there.
        """
        if t is None:
            return
        if isinstance(t, Task):
            self.put(t)
            return
        check_schedule_args(t)
        if len(self.normal) >= self.high_water and not self._make_room(len(t)):
            t = [task for task in t if task.priority]  # dropped: only urgent ones get in
        for task in t:
            (self.urgent if task.priority else self.normal).append(task)
        if self.sleeping and not self._rung:
            self._ring()

    def _ring(self) -> None:
        """Wake the sleeping node, once per sleep (on the bell, or on its waiter)."""
        self._rung = True
        waiter = self.waiter
        if waiter is None:
            self._bell.put(None)
        else:
            waiter.wake()

    def _make_room(self, n: int = 1) -> bool:
        """Wait for the lane to drain below the low-water mark; False to drop ``n`` tasks."""
        me = threading.get_ident()
        if me == self.owner_thread or self.owner_thread is None or me in self.holds_back:
            return True  # the node's own work, no node yet, or a thread that holds back
        if self._closed.is_set():
            return True  # shutting down: the queue is cleared anyway
        self._count_wait(me)
        if not self._drain(self.max_wait_s):
            self.loss.dropped(n)
            return False
        if self.loss.dropping:
            self.loss.recovered()
        return True

    def _drain(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` until the normal lane is down to the low-water mark.

        False on timeout; True once it is there, or when `close` ends the wait.
        """
        deadline = time.monotonic() + timeout_s
        while len(self.normal) > self.low_water:
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            # Poll: the node works the lane down without a word to producers,
            # so its hot path pays nothing. close() ends the wait at once.
            if self._closed.wait(min(left, 0.005)):
                return True
        return True

    def _count_wait(self, me: int) -> None:
        """Count a producer's wait and remember where it waits (slow path: the queue is full)."""
        self.waits += 1
        if len(self.waits_by_thread) >= 100:  # threads come and go; keep these bounded
            self.waits_by_thread.clear()
            self.waited_at.clear()
        self.waits_by_thread[me] = self.waits_by_thread.get(me, 0) + 1
        frame = outside_runtime(sys._getframe(2))  # schedule(); then out of SNR's code
        if frame is not None:
            self.waited_at[me] = (frame, frame.f_lineno)

    def never_wait(self, thread_id: int) -> None:
        """Let ``thread_id``'s tasks in at once, whatever the queue's length.

        For a thread that serves many producers and holds back by itself when
        the queue is full (a socket I/O thread stops reading): making it wait
        would stall every link it serves. Its tasks still count towards the
        high-water mark the others see.

        Example::

            queue.never_wait(threading.get_ident())   # called by the I/O thread
        """
        self.holds_back.add(thread_id)

    def wait_for_room(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` until the normal lane is below the high-water mark.

        For producers that can hold back without losing anything, such as a
        socket reader (unread bytes stay in the OS, and TCP slows the sender).
        True once there is room (or the node is stopping); False on timeout.

        Example::

            while not queue.wait_for_room(0.25):
                if link_closed:
                    return
        """
        return len(self.normal) < self.high_water or self._closed.is_set() or self._drain(timeout_s)

    def get(self, timeout_s: Optional[float] = None) -> Optional[Task]:
        """The next task; waits up to ``timeout_s`` (None: forever) if empty."""
        task = self.pop()
        if task is None:
            self.wait(timeout_s)
            task = self.pop()
        return task

    def pop(self) -> Optional[Task]:
        """The next task without waiting, or None."""
        lane = self.urgent or self.normal  # urgent tasks first
        return lane.popleft() if lane else None

    def use_waiter(self, waiter: IdleWaiter) -> bool:
        """Sleep on ``waiter`` from now on instead of the bell; True if it now does.

        One waiter at a time, the first to ask: False if another is installed
        (a node on a `SimClock` sleeps on its turn; a node with sockets and
        Zenoh sleeps on whichever comms started first). A comms refused here
        reads its links on a thread of its own and queues what it reads,
        which is always correct, only a hand-off slower. Call it from the
        node's thread, or before the node runs; a sleep on the bell in
        progress is ended, so no wake-up is lost.

        Example (what the socket comms' I/O loop does as it starts)::

            if node.queue.use_waiter(io_loop):
                ...   # idle waits now watch the links' sockets too
        """
        if self.waiter is not None:
            return self.waiter is waiter
        self.waiter = waiter
        self._bell.put(None)
        return True

    def stop_waiter(self, waiter: IdleWaiter) -> None:
        """Sleep on the bell again if ``waiter`` is the one installed (else nothing changes).

        A sleep on ``waiter`` in progress is ended, so no wake-up is lost.

        Example::

            node.queue.stop_waiter(io_loop)   # the comms are closing
        """
        if self.waiter is waiter:
            self.waiter = None
            waiter.wake()

    def wait(self, timeout_s: Optional[float], urgent_only: bool = False) -> None:
        """Sleep until a task arrives, ``wake()`` is called, or the timeout.

        ``urgent_only``: sleep even if normal tasks wait (a paused node runs
        none of them; each new task still wakes it once).
        """
        waiter = self.waiter
        self._rung = False
        self.sleeping = True
        try:
            # Check again now that producers will ring: one may have appended
            # just before it saw us sleeping.
            if self.urgent or (self.normal and not urgent_only):
                return
            if waiter is not None:
                waiter.wait(timeout_s)
                return
            try:
                self._bell.get(timeout=timeout_s)
            except queue.Empty:
                pass
        finally:
            self.sleeping = False
            if waiter is not None:
                # Reading what woke it queues tasks: done once no producer
                # rings for this sleep any more.
                waiter.woken()

    def close(self) -> None:
        """The consumer is stopping: wake it if it sleeps; producers never wait from now on."""
        self._closed.set()
        self._bell.put(None)
        waiter = self.waiter
        if waiter is not None:
            waiter.wake()

    def clear(self) -> int:
        """Drop every waiting task; returns how many were dropped."""
        dropped = len(self.normal) + len(self.urgent)
        self.normal.clear()
        self.urgent.clear()
        return dropped

    def __len__(self) -> int:
        return len(self.normal) + len(self.urgent)
