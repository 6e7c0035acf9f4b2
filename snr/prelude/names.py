"""The small vocabulary every SNR program shares: type aliases and enums.

Students mostly meet these names in annotations::

    from snr import DataKey, TaskId, SomeTasks, TaskType

    def on_depth(self, task: Task, key: TaskId) -> SomeTasks: ...

This module, the bottom layer, imports nothing of the package: an alias that
names `Task`, `Page` or `AbstractFactory` (`SomeTasks`...) stands beside that class.
"""

from __future__ import annotations

import enum
from typing import List, Tuple, Union

__all__ = ["ComponentName", "DataKey", "Mode", "Role", "StatsCell", "TaskId", "TaskName"]
__all__ += ["TaskPriority", "TaskType"]

DataKey = str
"""The name a page is stored under in a node's datastore, e.g. ``"depth_m"``."""

Role = str
"""The job a node does in a system, chosen on the command line, e.g. ``"urov"``."""

ComponentName = str
"""The unique name of an endpoint or loop inside one node, e.g. ``"depth_filter"``."""

TaskName = str
"""The second half of a task's identity, e.g. the data key of a stored page."""


class TaskType(enum.Enum):
    """What kind of work a task asks for.

    Example::

        tasks.event("button_pressed", ["A"]).type is TaskType.event

    Members:
        event: something happened; the name says what.
        store_page: put a page in the datastore (name = the page's key).
        process_data: a page is now in the datastore (sent after ``store_page``
            when ``page.process`` is true).
        reload: reload a component's source code (name = component or ``"all"``).
        terminate: stop the node (name = the reason). Runs before queued work.

    ``TaskType.store_data`` is another name for ``store_page``: thesis listing
    A.4 uses it, and a handler registered under it fires when data is stored.
    """

    event = "event"
    store_page = "store_page"
    store_data = "store_page"  # alias kept for thesis listing A.4
    process_data = "process_data"
    reload = "reload"
    terminate = "terminate"

    # Members are singletons, so identity hashing is correct, and it is twice
    # as fast as Enum's hash-by-name: every task dispatch hashes a TaskType.
    __hash__ = object.__hash__

    def __repr__(self) -> str:
        return f"TaskType.{self.name}"


class TaskPriority(enum.IntEnum):
    """How urgent a task is. High-priority tasks (terminate) jump the queue.

    Example::

        Task(TaskType.event, "stop_motors", priority=TaskPriority.high)
    """

    normal = 0
    high = 1


class Mode(enum.Enum):
    """How strict a node is about mistakes.

    Example::

        Config({"robot": [...]}, mode=Mode.DEPLOYED)

    Members:
        DEBUG: the default while you develop: a failing handler stops the node
            with a clear report, slow handlers are reported, the profiler is on.
        TEST: like DEBUG, quieter logs; used by ``SNRTestCase``.
        DEPLOYED: on the robot: a failing handler is logged and the node keeps
            running.
    """

    DEBUG = "debug"
    TEST = "test"
    DEPLOYED = "deployed"


TaskId = Union[TaskType, Tuple[TaskType, TaskName]]
"""How a handler is registered: ``(TaskType.store_page, "depth")`` for one
task name, or a bare ``TaskType.terminate`` for every task of that type."""

StatsCell = List[float]
"""A profiler's tally for one handler or loop: ``[times_called, total_seconds]``.

Example::

    cell = node.profiler.cell("Loop(clock)")
    cell[0], cell[1]        # 120 passes, 0.034 s in total
"""
