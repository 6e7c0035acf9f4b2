"""Tutorial step 6: the component to edit while the node runs.

Change ``GREETING`` below and save the file: the node running
``step06_hot_reload.py`` reloads this module and rebuilds the greeter,
and the count goes on where it was (it is kept on the factory).
"""

import sys

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType

GREETING = "Hello"


class Greeter(Endpoint):
    """Greets on every ``tick`` event."""

    def __init__(self, factory: "GreeterFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "greeter")
        self.counter = factory  # the count lives on the factory: it survives reloads
        self.task_handlers = {(TaskType.event, "tick"): self.greet}

    def greet(self, task: Task, key: TaskId) -> SomeTasks:
        self.counter.greetings += 1
        print(f"{GREETING} #{self.counter.greetings}", flush=True)
        return None


class GreeterFactory(EndpointFactory):
    """Builds the greeter; reloading re-reads this module from disk."""

    def __init__(self) -> None:
        super().__init__(sys.modules[__name__])
        self.greetings = 0

    def get(self, parent: AbstractNode) -> Greeter:
        # After a reload, this module's *new* Greeter class is used.
        return Greeter(self, parent)
