"""`TaskQueue`: the thread-safe queue between loops and the node's thread.

Two deques: ``urgent`` for high-priority tasks (terminate) and ``normal`` for
the rest, each FIFO. ``deque.append``/``popleft`` are atomic in CPython, so
producers never take a lock; an ``Event`` wakes the node when it sleeps on an
empty queue, so an idle node uses no CPU.
"""

from __future__ import annotations

import collections
import threading
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
        self._wakeup = threading.Event()

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
        self._wakeup.set()

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
        self._wakeup.clear()
        # Check again after clearing: a producer may have appended in between.
        if self.normal or self.urgent:
            return
        self._wakeup.wait(timeout_s)

    def wake(self) -> None:
        """Wake a thread sleeping in :meth:`wait` (used to stop the node)."""
        self._wakeup.set()

    def clear(self) -> int:
        """Drop every waiting task; returns how many were dropped."""
        dropped = len(self.normal) + len(self.urgent)
        self.normal.clear()
        self.urgent.clear()
        return dropped

    def __len__(self) -> int:
        return len(self.normal) + len(self.urgent)
