"""Small components shared by the core tests (not part of the library)."""

from __future__ import annotations

from typing import Any, Callable, Dict, List, Optional, Tuple

from snr import (
    AbstractNode,
    Endpoint,
    EndpointFactory,
    SomeTasks,
    Task,
    TaskId,
)

Log = List[Tuple[str, Any]]


class Recorder(Endpoint):
    """Appends ``(endpoint name, task id or key)`` to a shared log per task."""

    def __init__(
        self,
        factory: RecorderFactory,
        parent: AbstractNode,
        name: str,
        keys: List[TaskId],
        log: Log,
        reply: Optional[Callable[[Task, TaskId], SomeTasks]],
    ) -> None:
        super().__init__(factory, parent, name)
        self.log_list = log
        self.reply = reply
        self.task_handlers = {key: self.record for key in keys}

    def record(self, task: Task, key: TaskId) -> SomeTasks:
        self.log_list.append((self.name, (task.type, task.name, key)))
        return self.reply(task, key) if self.reply else None


class RecorderFactory(EndpointFactory):
    def __init__(
        self,
        name: str,
        keys: List[TaskId],
        log: Log,
        reply: Optional[Callable[[Task, TaskId], SomeTasks]] = None,
    ) -> None:
        super().__init__()
        self.name, self.keys, self.log, self.reply = name, keys, log, reply
        self.built: Dict[str, Recorder] = {}

    def get(self, parent: AbstractNode) -> Recorder:
        endpoint = Recorder(self, parent, self.name, self.keys, self.log, self.reply)
        self.built[self.name] = endpoint
        return endpoint
