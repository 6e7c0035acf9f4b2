"""The small vocabulary every SNR program shares: type aliases and enums.

Students mostly meet these names in annotations::

    from snr import DataKey, TaskId, SomeTasks, TaskType

    def on_depth(self, task: Task, key: TaskId) -> SomeTasks: ...

Aliases that mention `Task`, `Page` or the ABCs are full dotted names in strings:
this module, the bottom layer, imports nothing of the package.
"""

from __future__ import annotations

import enum
from typing import TYPE_CHECKING, Callable, Dict, List, Sequence, Tuple, Union

if TYPE_CHECKING:  # pragma: no cover - only for the type checker
    import snr.prelude.abstract
    import snr.prelude.page
    import snr.prelude.task

__all__ = ["BurstHandler", "ComponentName", "ComponentsByRole", "DataDict", "DataKey", "Mode"]
__all__ += ["Role", "SomeTasks", "StatsCell", "TaskHandler", "TaskHandlerMap", "TaskId", "TaskName"]
__all__ += ["TaskPriority", "TaskScheduler", "TaskType"]

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

SomeTasks = Union["snr.prelude.task.Task", List["snr.prelude.task.Task"], None]
"""What a task handler returns: one task, a list of tasks, or ``None``."""

TaskHandler = Callable[["snr.prelude.task.Task", TaskId], SomeTasks]
"""A handler: ``def handler(self, task: Task, key: TaskId) -> SomeTasks``."""

TaskHandlerMap = Dict[TaskId, TaskHandler]
"""An endpoint's ``task_handlers``: which handler runs for which task id."""

BurstHandler = Callable[[List["snr.prelude.task.Task"]], SomeTasks]
"""A handler for a run of ``store_page`` tasks under one key, in one call (see
`AbstractComponent.burst_handlers`): ``def forward_burst(self, run) -> SomeTasks``."""

TaskScheduler = Callable[[SomeTasks], None]
"""Something that queues tasks on a node, such as ``endpoint.schedule``."""

DataDict = Dict[DataKey, "snr.prelude.page.Page"]
"""A node's datastore: the newest page for every data key."""

ComponentsByRole = Dict[Role, Sequence["snr.prelude.abstract.AbstractFactory"]]
"""A whole system: for every role, the factories that build its components."""

StatsCell = List[float]
"""A profiler's tally for one handler or loop: ``[times_called, total_seconds]``.

Example::

    cell = node.profiler.cell("Loop(clock)")
    cell[0], cell[1]        # 120 passes, 0.034 s in total
"""
