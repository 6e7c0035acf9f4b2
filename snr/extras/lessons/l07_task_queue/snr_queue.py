"""SNR's own `TaskQueue` behind lesson 7's interface, so that it takes the same grade.

The node uses `snr.core.task_queue.TaskQueue` directly (there is no ``Config`` option for
it: docs/assignments.md says why); this thin adapter gives it the five names
lesson 7's queue has, and nothing more:

* ``put(task)``: `TaskQueue.put`, which, once the normal lane holds
  ``capacity`` tasks (its ``high_water``), waits until the consumer has
  worked it down to half (the low-water mark), at most ``max_wait_s``; False
  when it dropped the task (its loss count went up);
* ``take()``: `TaskQueue.pop`; ``wait(timeout_s)``, ``close()``, ``len()``:
  the same methods.

SNR's queue makes a producer wait only when it is not the consumer's own
thread (the node's handlers never wait on themselves): here every caller of
``put`` is a producer, so the consumer's thread id is set to 0, no thread's.

Example::

    grade_queue(SnrTaskQueue, Path("snr"))    # SNR's own queue: every check passes
"""

from __future__ import annotations

import logging
from typing import Optional

from snr import Task
from snr.core.task_queue import TaskQueue

__all__ = ["SnrTaskQueue"]

_QUIET = logging.Logger("lesson 7's grade")
"""Where SNR's queue reports the tasks it drops: nowhere, a grade says it in its checks."""
_QUIET.addHandler(logging.NullHandler())


class SnrTaskQueue:
    """`snr.core.task_queue.TaskQueue`, with lesson 7's names.

    Example::

        queue = SnrTaskQueue(capacity=8, max_wait_s=0.3)
        queue.put(tasks.event("a"))    # True
        queue.take().name              # 'a'
    """

    def __init__(self, capacity: int = 100, max_wait_s: float = 1.0) -> None:
        self.queue = TaskQueue(high_water=capacity, max_wait_s=max_wait_s, log=_QUIET)
        self.queue.owner_thread = 0  # no thread's id: every put here is a producer's

    def put(self, task: Task) -> bool:
        dropped = self.queue.loss.total
        self.queue.put(task)
        return self.queue.loss.total == dropped

    def take(self) -> Optional[Task]:
        return self.queue.pop()

    def wait(self, timeout_s: float) -> None:
        self.queue.wait(timeout_s)

    def close(self) -> None:
        self.queue.close()

    def __len__(self) -> int:
        return len(self.queue)
