"""A test endpoint that keeps every page stored under some keys (not part of the library)."""

from __future__ import annotations

import time
from typing import List, Optional, Sequence

from snr import (
    AbstractNode,
    Endpoint,
    EndpointFactory,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)


class PageCollector(Endpoint):
    """Appends each stored page (and when it arrived) to lists on its factory."""

    def __init__(self, factory: PageCollectorFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.collection = factory
        self.task_handlers = {(TaskType.store_page, key): self.collect for key in factory.keys}

    def collect(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        assert isinstance(page, Page)
        self.collection.pages.append(page)
        self.collection.arrived_s.append(time.monotonic())
        stop_after = self.collection.stop_after
        if stop_after is not None and len(self.collection.pages) >= stop_after:
            return tasks.terminate(f"collected {stop_after} pages")
        return None


class PageCollectorFactory(EndpointFactory):
    """Collect pages under ``keys``; stop the node after ``stop_after`` of them."""

    def __init__(
        self, keys: Sequence[str], stop_after: Optional[int] = None, name: str = "collector"
    ) -> None:
        super().__init__()
        self.keys = list(keys)
        self.stop_after = stop_after
        self.name = name
        self.pages: List[Page] = []
        self.arrived_s: List[float] = []

    def data(self, key: Optional[str] = None) -> List[object]:
        """The data of the collected pages (under ``key`` only, if given)."""
        return [p.data for p in self.pages if key is None or p.key == key]

    def get(self, parent: AbstractNode) -> PageCollector:
        return PageCollector(self, parent)
