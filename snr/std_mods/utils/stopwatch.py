"""`StopwatchEndpointFactory`: record when chosen tasks are handled."""

from __future__ import annotations

from typing import List, Optional

from snr.core import Endpoint, EndpointFactory
from snr.prelude import AbstractNode, SomeTasks, Task, TaskId

__all__ = ["StopwatchEndpoint", "StopwatchEndpointFactory"]


class StopwatchEndpoint(Endpoint):
    """Appends ``node.get_time_s()`` to a list whenever a watched task runs.

    Example::

        times: List[float] = []
        StopwatchEndpointFactory(times, [TaskType.terminate])
        # after the run: times[0] is when the node handled terminate
    """

    def __init__(self, factory: StopwatchEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.times = factory.times
        self.task_handlers = dict.fromkeys(factory.task_ids, self.record)

    def record(self, task: Task, key: TaskId) -> SomeTasks:
        """Note the node time at which ``task`` was handled."""
        self.times.append(self.parent.get_time_s())
        return None


class StopwatchEndpointFactory(EndpointFactory):
    """Builds a `StopwatchEndpoint` writing into the list ``times``.

    Example::

        StopwatchEndpointFactory(times, [TaskType.terminate])
    """

    def __init__(
        self, times: List[float], task_ids: List[TaskId], name: Optional[str] = None
    ) -> None:
        super().__init__()
        self.times = times
        self.task_ids = list(task_ids)
        self.name = name or "stopwatch_endpoint"

    def get(self, parent: AbstractNode) -> StopwatchEndpoint:
        return StopwatchEndpoint(self, parent)
