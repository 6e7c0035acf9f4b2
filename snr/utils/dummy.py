"""`DummyEndpointFactory`: an endpoint that does nothing but count.

Useful as a placeholder in a config while the real component is written,
and as the "idle endpoints" of the dispatch benchmark.
"""

from __future__ import annotations

from typing import List, Optional, Sequence

from snr.core import Endpoint, EndpointFactory
from snr.prelude import AbstractNode, SomeTasks, Task, TaskId

__all__ = ["DummyEndpoint", "DummyEndpointFactory"]


class DummyEndpoint(Endpoint):
    """Counts the tasks it is registered for in ``calls``; returns nothing.

    Example::

        DummyEndpointFactory("placeholder", [(TaskType.event, "ping")])
    """

    def __init__(self, factory: DummyEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.calls = 0
        self.task_handlers = dict.fromkeys(factory.task_ids, self.count)

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        """Count the task."""
        self.calls += 1
        return None


class DummyEndpointFactory(EndpointFactory):
    """Builds a `DummyEndpoint` named ``name`` for ``task_ids``.

    Example::

        config = Config({"robot": [DummyEndpointFactory("motors")]})
    """

    def __init__(
        self, name: str = "dummy_endpoint", task_ids: Optional[Sequence[TaskId]] = None
    ) -> None:
        super().__init__()
        self.name = name
        self.task_ids: List[TaskId] = list(task_ids or [])
        self.built: List[DummyEndpoint] = []

    def get(self, parent: AbstractNode) -> DummyEndpoint:
        endpoint = DummyEndpoint(self, parent)
        self.built.append(endpoint)
        return endpoint
