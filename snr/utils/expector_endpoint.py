"""`ExpectorEndpointFactory`: an endpoint that reports tasks to an expector."""

from __future__ import annotations

from typing import Any, Optional

from snr.core import Endpoint, EndpointFactory, tasks
from snr.prelude import AbstractNode, SomeTasks, Task, TaskId
from snr.utils.expector import Expector

__all__ = [
    "ExpecterEndpointFactory",
    "ExpectorEndpoint",
    "ExpectorEndpointFactory",
]


class ExpectorEndpoint(Endpoint):
    """Registers a handler for every id the expector watches and counts them.

    With ``exit_when_satisfied`` it stops the node once every expectation is
    met; other tasks of the same types are told too, for the failure message.

    Example::

        ExpectorEndpointFactory(expector, exit_when_satisfied=True).get(node)
    """

    def __init__(self, factory: ExpectorEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.expector = factory.expector
        self.exit_when_satisfied = factory.exit_when_satisfied
        expected = self.expector.task_ids()
        # the same type, any other name: observed; the ids expected: counted
        self.task_handlers = {
            **{k[0]: self.observe for k in expected if isinstance(k, tuple)},
            **{key: self.expect for key in expected},
        }

    def observe(self, task: Task, key: TaskId) -> SomeTasks:
        """Tell the expector about a task it does not expect (for its failure message)."""
        self.expector.call((task.type, task.name))
        return None

    def expect(self, task: Task, key: TaskId) -> SomeTasks:
        """Count the task; stop the node once satisfied, if asked to."""
        self.expector.call(key)
        if self.exit_when_satisfied and self.expector.is_satisfied():
            return tasks.terminate("expectations satisfied")
        return None


class ExpectorEndpointFactory(EndpointFactory):
    """Builds an `ExpectorEndpoint` for ``expector`` (thesis listing A.3).

    Example::

        with self.expector({(TaskType.store_page, "out"): 4}) as expector:
            self.run_test_node([
                ListReplayerFactory([0, 1, 2, 4], "in"),
                MovingAvgFilterFactory("in", "out", 2),
                ExpectorEndpointFactory(expector, exit_when_satisfied=True),
            ])
    """

    def __init__(
        self,
        expector: Expector[Any],
        exit_when_satisfied: bool = False,
        name: Optional[str] = None,
    ) -> None:
        super().__init__()
        self.expector = expector
        self.exit_when_satisfied = exit_when_satisfied
        self.name = name or "expector_endpoint"

    def get(self, parent: AbstractNode) -> ExpectorEndpoint:
        return ExpectorEndpoint(self, parent)


ExpecterEndpointFactory = ExpectorEndpointFactory
"""The spelling used in thesis listing A.3; the same class."""
