"""Lesson 7: a task queue safe for many producers (docs/lessons.md), the reference solution.

A node's thread works through its queue of tasks, one at a time; its loops,
each on a thread of its own, put tasks in (thesis 4.3.1, 8.3.2): many
producers, one consumer. SNR's own queue is `snr.core.task_queue.TaskQueue`. `MyTaskQueue`
is the same idea in miniature, written on one `threading.Condition`:

* ``put(task)``: a high-priority task (terminate) jumps ahead of the others;
  while the queue holds ``capacity`` tasks a producer waits for room, at most
  ``max_wait_s``, then gives up (``False``): a loop faster than the node is
  slowed to the node's pace, and a stuck node cannot fill the memory;
* ``take()``: the next task, or None; ``wait(timeout_s)``: the consumer sleeps,
  using no CPU, until a task comes, the queue is closed, or the timeout;
* ``close()``: the consumer is stopping; every thread waiting is woken.

Run it: a node whose loops put tasks into your queue, and one more loop that
feeds them from your queue into the node, for a few seconds; it prints how
many went through, and whether any was lost or came out of order::

    python task_queue.py --seconds 3

To write it yourself, ``python -m snr lesson start 7`` writes the starter
file into your folder, and ``python -m snr lesson grade 7`` grades it.
"""

from __future__ import annotations

import argparse
import collections
import sys
import threading
import time
from typing import Any, Callable, Deque, List, Optional

from snr import Task

__all__ = ["MyTaskQueue", "main"]


class MyTaskQueue:
    """A bounded FIFO of tasks for one consumer and many producers; urgent tasks first.

    Args:
        capacity: how many ordinary tasks it holds; more wait for room.
        max_wait_s: how long a producer waits for room before it gives up.

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
        # One lock guards every field above; the condition's waiters (the
        # consumer in wait, producers in put) sleep on it, and are woken by
        # notify_all whenever a task comes or goes, or the queue is closed.
        self.changed = threading.Condition(threading.Lock())

    def put(self, task: Task) -> bool:
        """Queue ``task`` (any thread); False if it was dropped: no room within ``max_wait_s``."""
        with self.changed:
            if task.priority:
                self.urgent.append(task)  # urgent tasks never wait: terminate must get in
            else:
                deadline = time.monotonic() + self.max_wait_s
                while len(self.normal) >= self.capacity and not self.closed:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        return False  # the consumer is stuck: drop, never fill the memory
                    self.changed.wait(left)  # lets go of the lock while it sleeps
                self.normal.append(task)
            self.changed.notify_all()  # the consumer may be sleeping in wait
        return True

    def take(self) -> Optional[Task]:
        """The next task, urgent ones first, without waiting; None if there is none."""
        with self.changed:
            lane = self.urgent or self.normal
            if not lane:
                return None
            task = lane.popleft()
            self.changed.notify_all()  # a producer may be waiting for room
            return task

    def wait(self, timeout_s: float) -> None:
        """Sleep until a task is queued, the queue is closed, or ``timeout_s`` is over."""
        deadline = time.monotonic() + timeout_s
        with self.changed:
            # Checked under the lock: no producer can put a task (and notify)
            # between the check and the sleep, so no wake-up is lost.
            while not self.urgent and not self.normal and not self.closed:
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                self.changed.wait(left)

    def close(self) -> None:
        """The consumer is stopping: wake every waiting thread; from now on no one waits."""
        with self.changed:
            self.closed = True
            self.changed.notify_all()

    def __len__(self) -> int:
        with self.changed:
            return len(self.normal) + len(self.urgent)


def main(argv: List[str], make: Optional[Callable[..., Any]] = None) -> None:
    """``python task_queue.py [--seconds S] [--producers N]``: tasks through your queue, in a node.

    ``make``: what makes the queue (this file's `MyTaskQueue` by default).
    """
    from snr.extras.lessons.l07_task_queue.demo import run_demo

    parser = argparse.ArgumentParser(prog=argv[0], description="Lesson 7: a task queue.")
    parser.add_argument("--seconds", type=float, default=3.0, help="how long it runs")
    parser.add_argument("--producers", type=int, default=4, help="how many loops put tasks")
    options = parser.parse_args(argv[1:])
    if options.seconds <= 0:
        parser.error(f"--seconds {options.seconds:g}: give more than 0")
    if options.producers < 1:
        parser.error(f"--producers {options.producers}: give 1 or more")
    run_demo(make or MyTaskQueue, options.seconds, options.producers)


if __name__ == "__main__":
    main(sys.argv)
