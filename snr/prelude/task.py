"""`Task`: one unit of work flowing through a node's queue (thesis 4.3.1)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, List, Tuple

from snr.prelude.json_dataclass import JsonDataclass
from snr.prelude.names import TaskName, TaskPriority, TaskType

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
        return f"({self.type.name}, {self.name!r}): {self.val_list!r}"
