"""`Task`: one unit of work flowing through a node's queue (thesis 4.3.1)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, List, Tuple

from snr.prelude.json_dataclass import JsonDataclass
from snr.prelude.names import TaskName, TaskPriority, TaskType
from snr.prelude.page import Page

__all__ = ["Task"]


@dataclass
class Task(JsonDataclass):
    """An ephemeral event handed to every endpoint that registered for it.

    A task is identified by its ``type`` and ``name``; ``val_list`` carries any
    values the handlers need. It is gone once every matching handler ran.

    Example::

        task = Task(TaskType.event, "button_pressed", ["A"])
        task.id()            # (TaskType.event, 'button_pressed')
        Task.deserialize(task.serialize()) == task   # True

    Usually you build tasks with the helpers in ``snr.tasks`` instead.
    """

    type: TaskType
    name: TaskName
    val_list: List[Any] = field(default_factory=list)
    priority: TaskPriority = TaskPriority.normal

    def id(self) -> Tuple[TaskType, TaskName]:
        """The specific task id ``(type, name)`` this task matches first."""
        return (self.type, self.name)

    def serialize(self) -> str:
        """This task as JSON text (``val_list`` must hold JSON-able values)."""
        return self.to_json()

    @classmethod
    def deserialize(cls, text: str) -> Task:
        """Rebuild a task from :meth:`serialize`'s JSON text."""
        return cls.from_json(text)

    def __str__(self) -> str:
        """The task in one line, as thesis figure 5.4 prints it; pages in their short form.

        ``repr(task)`` shows every field in full, for debugging.

        Example::

            str(Task(TaskType.event, "button_pressed", ["A"]))
            # "(event, 'button_pressed'): ['A']"
            str(tasks.store_page(Page("depth", 2.5, "robot", time.time())))
            # "(store_page, 'depth'): [Page 'depth' = 2.5 from 'robot' (0.0 s ago)]"
        """
        values: object = self.val_list  # a task built by hand may hold anything
        if isinstance(values, list):
            shown = ", ".join(str(v) if isinstance(v, Page) else repr(v) for v in values)
            return f"({self.type.name}, {self.name!r}): [{shown}]"
        return f"({self.type.name}, {self.name!r}): {values!r}"
