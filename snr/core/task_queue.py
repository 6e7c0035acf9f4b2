"""`TaskQueue`: the thread-safe queue between loops and the node's thread.

Two deques: ``urgent`` for high-priority tasks (terminate) and ``normal`` for
the rest, each FIFO. ``deque.append``/``popleft`` are atomic in CPython, so
producers never take a lock. When the node sleeps on an empty queue it blocks
on a "bell" (a C-implemented ``queue.SimpleQueue``), and producers ring it
only while the node sleeps: an idle node uses no CPU, and a busy one pays
nothing for waking. (A ``threading.Event`` does the same job with Python-level
locking that cost ~15 µs per wake-up, which showed in round trips between
nodes.)
"""

from __future__ import annotations

import collections
import queue
from typing import Deque, Optional

from snr.prelude import AbstractTaskQueue, HandlerError, SomeTasks, Task

__all__ = ["TaskQueue"]


class TaskQueue(AbstractTaskQueue):
    """FIFO of tasks where high-priority tasks jump ahead.

    Example::

        queue = TaskQueue()
        queue.schedule([tasks.event("a"), tasks.terminate("done")])
        queue.get().type      # TaskType.terminate (it jumped ahead)
        queue.get().name      # 'a'
    """

    def __init__(self) -> None:
        self.normal: Deque[Task] = collections.deque()
        self.urgent: Deque[Task] = collections.deque()
        self._bell: queue.SimpleQueue[None] = queue.SimpleQueue()
        self._sleeping = False
        self._rung = False

    def schedule(self, t: SomeTasks) -> None:
        """Queue a task, a list of tasks, or nothing (None). Any thread."""
        if t is None:
            return
        if isinstance(t, Task):
            (self.urgent if t.priority else self.normal).append(t)
        elif isinstance(t, list):
            for task in t:
                if not isinstance(task, Task):
                    raise HandlerError(
                        f"Cannot schedule {task!r} ({type(task).__name__}): only Task "
                        "objects can be queued. Build tasks with snr.tasks, e.g. "
                        "tasks.event('name') or self.store_data_task(key, data)."
                    )
                (self.urgent if task.priority else self.normal).append(task)
        else:
            raise HandlerError(
                f"Cannot schedule {t!r} ({type(t).__name__}): schedule() takes a Task, "
                "a list of Tasks or None. Build tasks with snr.tasks, e.g. "
                "tasks.event('name')."
            )
        if self._sleeping and not self._rung:  # ring once per sleep
            self._rung = True
            self._bell.put(None)

    def get(self, timeout_s: Optional[float] = None) -> Optional[Task]:
        """The next task; waits up to ``timeout_s`` (None: forever) if empty."""
        task = self.pop()
        if task is None:
            self.wait(timeout_s)
            task = self.pop()
        return task

    def pop(self) -> Optional[Task]:
        """The next task without waiting, or None."""
        if self.urgent:
            return self.urgent.popleft()
        if self.normal:
            return self.normal.popleft()
        return None

    def wait(self, timeout_s: Optional[float]) -> None:
        """Sleep until a task arrives, ``wake()`` is called, or the timeout."""
        self._rung = False
        self._sleeping = True
        try:
            # Check again now that producers will ring: one may have appended
            # just before it saw us sleeping.
            if self.normal or self.urgent:
                return
            try:
                self._bell.get(timeout=timeout_s)
            except queue.Empty:
                pass
        finally:
            self._sleeping = False

    def wake(self) -> None:
        """Wake a thread sleeping in :meth:`wait` (used to stop the node)."""
        self._bell.put(None)

    def clear(self) -> int:
        """Drop every waiting task; returns how many were dropped."""
        dropped = len(self.normal) + len(self.urgent)
        self.normal.clear()
        self.urgent.clear()
        return dropped

    def __len__(self) -> int:
        return len(self.normal) + len(self.urgent)
