"""Lesson 7: a task queue safe for many producers: your file (docs/lessons.md, "Lesson 7").

A node's thread takes its tasks, one at a time, from a queue that its loops,
each on a thread of its own, put tasks into: many producers, one consumer.
Write `MyTaskQueue`, the same idea as SNR's own queue in miniature, on one
`threading.Condition`:

* ``put(task)``: queue a task; a high-priority one (terminate) goes first;
  while ``capacity`` tasks are queued, wait for room, at most ``max_wait_s``,
  then give up and return False;
* ``take()``: the next task, or None; ``wait(timeout_s)``: sleep, using no
  CPU, until a task is queued, the queue is closed, or the timeout;
* ``close()``: wake every thread that waits; ``len(queue)``: how many are queued.

As it is, it keeps nothing and never waits. Run it (loops put tasks into your
queue, and one more feeds them into a node), and grade it::

    python task_queue.py --seconds 3
    python -m snr lesson grade 7
"""

from __future__ import annotations

import collections
import sys
import threading
import time
from typing import Deque, Optional

from snr import Task
from snr.extras.lessons.l07_task_queue.solution import main

__all__ = ["MyTaskQueue"]


class MyTaskQueue:
    """A bounded FIFO of tasks for one consumer and many producers; urgent tasks first.

    Example::

        queue = MyTaskQueue(capacity=100, max_wait_s=1.0)
        queue.put(tasks.event("a"))              # True: queued
        queue.put(tasks.terminate("done"))       # high priority: jumps ahead
        queue.take().type                        # TaskType.terminate
        queue.take().name                        # 'a'
        queue.take()                             # None: empty
        queue.wait(0.5)                          # sleeps 0.5 s: nothing comes
    """

    def __init__(self, capacity: int = 100, max_wait_s: float = 1.0) -> None:
        self.capacity = capacity
        self.max_wait_s = max_wait_s
        self.normal: Deque[Task] = collections.deque()
        self.urgent: Deque[Task] = collections.deque()
        self.closed = False
        # One lock for every field above. Hold it (`with self.changed:`) to read
        # or change them; self.changed.wait(s) lets go of it while it sleeps,
        # and self.changed.notify_all() wakes every thread sleeping there.
        self.changed = threading.Condition(threading.Lock())

    def put(self, task: Task) -> bool:
        # TODO (step 1): holding self.changed, append the task to self.normal.
        # TODO (step 2): a task with task.priority goes to self.urgent instead,
        #                and never waits.
        # TODO (step 3): then self.changed.notify_all(): the consumer may sleep in wait.
        # TODO (step 4): while len(self.normal) >= self.capacity (and not
        #                self.closed), wait on self.changed for what is left of
        #                max_wait_s; if it runs out, return False.
        return True

    def take(self) -> Optional[Task]:
        # TODO (step 1): holding self.changed, pop the oldest task (popleft) and
        #                return it; None if there is none.
        # TODO (step 2): self.urgent first.
        # TODO (step 4): notify_all after popping: a producer may wait for room.
        return None

    def wait(self, timeout_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        # TODO (step 3): holding self.changed, while both lanes are empty (and
        #                not self.closed): self.changed.wait(what is left until
        #                deadline); return when nothing is left.
        del deadline

    def close(self) -> None:
        # TODO (step 5): holding self.changed, set self.closed and notify_all.
        pass

    def __len__(self) -> int:
        # TODO (step 1): how many tasks are queued, in both lanes.
        return 0


if __name__ == "__main__":
    main(sys.argv, MyTaskQueue)
