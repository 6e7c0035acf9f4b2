"""A student's file with the type-level mistakes of docs/errors.md.

`python -m mypy --strict tests/data/mypy_mistakes.py` finds every one of them
before the robot runs; docs/errors.md shows its output. Not run by the tests.
"""

from snr import (
    AbstractNode,
    Endpoint,
    EndpointFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)


class DepthPrinter(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(parent, factory, "depth_printer")  # arguments swapped
        self.task_handlers = {
            (TaskType.store_page, "depth"): self.on_depth,  # wrong signature
            (TaskType.event, "ping"): self.on_ping,
            "speed": self.on_speed,  # a bare string key
        }

    def on_depth(self, task: Task) -> SomeTasks:
        return None

    def on_ping(self, task: Task, key: TaskId) -> SomeTasks:
        return 5  # not a Task, a list of Tasks or None

    def on_speed(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class DepthPrinterFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> DepthPrinter:
        DepthPrinter(self, parent)  # forgot to return it
