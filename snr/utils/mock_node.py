"""`MockNode`: a stand-in node for testing one component on its own."""

from __future__ import annotations

import logging
import time
from typing import Any, Dict, List, Optional

from snr.core.config import Config
from snr.core.timer import Clock, Timer
from snr.prelude import (
    AbstractComponent,
    AbstractFactory,
    AbstractNode,
    ComponentName,
    DataDict,
    DataKey,
    Mode,
    Page,
    SomeTasks,
    Task,
    TaskHandler,
    TaskId,
    TaskType,
)

__all__ = ["MockNode"]


class MockNode(AbstractNode):
    """Records what a component schedules instead of running it.

    Pages passed to ``store_data`` go straight into ``datastore`` as well,
    so ``get_data`` works in the test. Pass ``clock`` to control time.

    Example::

        node = MockNode()
        endpoint = MovingAvgFilterFactory("in", "out", 2).get(node)
        endpoint.update_filter(tasks.store_data("in", 4.0), (TaskType.store_page, "in"))
        node.scheduled      # the tasks the endpoint asked for
    """

    def __init__(
        self, role: str = "mock", mode: Mode = Mode.TEST, clock: Optional[Clock] = None
    ) -> None:
        self.role = role
        self.config = Config({role: []}, mode=mode, profile=False)
        self.mode = mode
        self.components: Dict[ComponentName, AbstractComponent] = {}
        self.log = logging.getLogger(f"snr.{role}")
        self.profiler = None
        self.datastore: DataDict = {}
        self.scheduled: List[Task] = []
        self.terminate_reason: Optional[str] = None
        self._timer = Timer(clock or time.perf_counter)

    def loop(self) -> None:
        """Does nothing: a mock node has no event loop."""

    def set_terminate_flag(self, reason: str) -> None:
        self.terminate_reason = reason

    def terminate(self) -> None:
        if self.terminate_reason is None:
            self.terminate_reason = "terminate() called"

    def is_terminated(self) -> bool:
        return self.terminate_reason is not None

    def get_task_handlers(self, task: Task) -> List[tuple[TaskHandler, TaskId]]:
        found: List[tuple[TaskHandler, TaskId]] = []
        for component in self.components.values():
            for key in (task.id(), task.type):
                if key in component.task_handlers:
                    found.append((component.task_handlers[key], key))
                    break
        return found

    def handle_task(self, handler: TaskHandler, task: Task, key: TaskId) -> Optional[List[Task]]:
        result = handler(task, key)
        if result is None:
            return None
        return [result] if isinstance(result, Task) else list(result)

    def execute_task(self, t: Task) -> None:
        for handler, key in self.get_task_handlers(t):
            self.schedule(self.handle_task(handler, t, key))

    def schedule(self, t: SomeTasks) -> None:
        """Record the tasks (they are not run)."""
        if isinstance(t, Task):
            self.scheduled.append(t)
        elif t is not None:
            self.scheduled.extend(t)

    def store_page_task(self, page: Page) -> Task:
        return Task(TaskType.store_page, page.key, [page])

    def store_data_task(self, key: DataKey, data: Any, process: bool = True) -> Task:
        return self.store_page_task(self.page(key, data, process))

    def page(self, key: DataKey, data: Any, process: bool = True) -> Page:
        return Page(key, data, self.role, time.time(), process)

    def store_data(self, key: DataKey, data: Any, process: bool = True) -> None:
        """Store at once (so ``get_data`` sees it) and record the task."""
        task = self.store_data_task(key, data, process)
        self.datastore[key] = task.val_list[0]
        self.scheduled.append(task)

    def get_page(self, key: DataKey) -> Optional[Page]:
        return self.datastore.get(key)

    def get_data(self, key: DataKey) -> Optional[Any]:
        page = self.datastore.get(key)
        return None if page is None else page.data

    def get_time_s(self) -> float:
        return self._timer.current_s()

    def write_page(self, page: Page) -> None:
        """Put ``page`` in the datastore at once."""
        self.datastore[page.key] = page

    def build_component(self, factory: AbstractFactory) -> Optional[AbstractComponent]:
        """``factory.get(self)``: the component, built on this mock node."""
        return factory.get(self)

    def add_component(self, component: AbstractComponent, start: bool = True) -> None:
        """Remember ``component`` by name (a mock node starts nothing)."""
        self.components[component.name] = component

    def remove_component(self, name: ComponentName) -> None:
        """Forget the component called ``name``."""
        self.components.pop(name, None)

    def reload_component(self, name: ComponentName = "all") -> List[ComponentName]:
        """A mock node reloads nothing; returns ``[]``."""
        return []
