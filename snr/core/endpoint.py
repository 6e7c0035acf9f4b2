"""`Endpoint`: user code that runs in task handlers on the node's thread."""

from __future__ import annotations

from snr.core.component import Component
from snr.prelude import AbstractEndpoint

__all__ = ["Endpoint"]


class Endpoint(Component, AbstractEndpoint):
    """Subclass this to react to tasks (thesis 4.4, 6.3.2).

    Call ``super().__init__(factory, parent, name)``, then fill
    ``self.task_handlers``. ``begin``, ``halt`` and ``terminate`` are optional.

    Example::

        class Doubler(Endpoint):
            def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "doubler")
                self.task_handlers = {(TaskType.store_page, "x"): self.double}

            def double(self, task: Task, key: TaskId) -> SomeTasks:
                page = task.val_list[0]
                return self.store_data_task("2x", page.data * 2)
    """
