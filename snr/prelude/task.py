"""`Task`: one unit of work flowing through a node's queue (thesis 4.3.1).

Beside it, the aliases that name it: `SomeTasks`, `TaskHandler`, `TaskHandlerMap`,
`BurstHandler` and `TaskScheduler` (thesis 6.2.2).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Literal, Optional, Tuple, Union

from snr.prelude.json_dataclass import JsonDataclass
from snr.prelude.names import TaskId, TaskName, TaskPriority, TaskType
from snr.prelude.page import Page, preview

__all__ = ["BurstHandler", "SomeTasks", "Task", "TaskHandler", "TaskHandlerMap", "TaskScheduler"]
__all__ += ["format_task"]


@dataclass(slots=True)
class Task(JsonDataclass):
    """An ephemeral event handed to every endpoint that registered for it.

    Its id is ``(type, name)``; ``val_list`` carries values for the handlers
    (build tasks with ``snr.tasks``).

    Example::

        task = Task(TaskType.event, "button_pressed", ["A"])
        task.id()            # (TaskType.event, 'button_pressed')
        Task.deserialize(task.serialize()) == task   # True
    """

    type: TaskType
    name: TaskName
    val_list: List[Any] = field(default_factory=list)
    priority: TaskPriority = TaskPriority.normal

    def id(self) -> Tuple[TaskType, TaskName]:
        """The specific task id ``(type, name)`` this task matches first."""
        return (self.type, self.name)

    def page(self) -> Optional[Page]:
        """The page this task carries (a ``store_page`` or ``process_data`` task's), or None.

        Example::

            def update_filter(self, task: Task, key: TaskId) -> SomeTasks:
                page = task.page()
                if page is None:
                    return None
                return self.store_data_task("depth_avg", self.average(page.data))
        """
        values: object = self.val_list  # a task built by hand may hold anything
        if isinstance(values, list) and values and isinstance(values[0], Page):
            return values[0]
        return None

    def serialize(self) -> str:
        """This task as JSON text (``val_list`` must hold JSON-able values)."""
        return self.to_json()

    @classmethod
    def deserialize(cls, text: str) -> Task:
        """Rebuild a task from :meth:`serialize`'s JSON text."""
        return cls.from_json(text)

    def __str__(self) -> str:
        """The task in one line, as thesis figure 5.4 prints it: `format_task`.

        ``repr(task)`` shows every field in full, for debugging.
        """
        return format_task(self)


SomeTasks = Union[Task, List[Task], None]
"""What a task handler returns: one task, a list of tasks, or ``None``."""

TaskHandler = Callable[[Task, TaskId], SomeTasks]
"""A handler: ``def handler(self, task: Task, key: TaskId) -> SomeTasks``."""

TaskHandlerMap = Dict[TaskId, TaskHandler]
"""An endpoint's ``task_handlers``: which handler runs for which task id."""

BurstHandler = Callable[[List[Task]], SomeTasks]
"""A handler for a run of ``store_page`` tasks under one key, in one call (see
`AbstractComponent.burst_handlers`): ``def forward_burst(self, run) -> SomeTasks``."""

TaskScheduler = Callable[[SomeTasks], None]
"""Something that queues tasks on a node, such as ``endpoint.schedule``."""


def format_task(task: Union[Task, TaskId], values: Literal["all", "data", "none"] = "all") -> str:
    """A task (or a task id) in one line: the one way SNR prints tasks.

    Pages show in their short form; ``values="data"`` shows only a page's
    data, ``"none"`` only the id.

    Example::

        format_task(Task(TaskType.event, "button_pressed", ["A"]))
        # "(event, 'button_pressed'): ['A']"
        format_task(tasks.store_page(Page("depth", 2.5, "robot", time.time())))
        # "(store_page, 'depth'): [Page 'depth' = 2.5 from 'robot' (0.0 s ago)]"
        format_task(tasks.store_data("depth", 2.5), values="data")   # "(store_page, 'depth'): 2.5"
        format_task((TaskType.event, "go"))                          # "(event, 'go')"
        format_task(TaskType.terminate)                              # "(terminate)"
    """
    if isinstance(task, TaskType):
        return f"({task.name})"
    if isinstance(task, tuple):
        return f"({task[0].name}, {task[1]!r})"
    label = f"({task.type.name}, {task.name!r})"
    page = task.page()
    if values == "none":
        return label
    if values == "data" and page is not None:
        return f"{label}: {preview(page.data)}"
    shown: object = task.val_list  # a task built by hand may hold anything
    if isinstance(shown, list):
        items = ", ".join(str(v) if isinstance(v, Page) else repr(v) for v in shown)
        return f"{label}: [{items}]"
    return f"{label}: {shown!r}"
