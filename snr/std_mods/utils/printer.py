"""`PrinterEndpointFactory`: print chosen tasks as they are handled."""

from __future__ import annotations

import sys
from typing import List, Optional, TextIO

from snr.core import Endpoint, EndpointFactory
from snr.prelude import AbstractNode, SomeTasks, Task, TaskId
from snr.prelude.task import format_task  # the one task formatter, exported here too

__all__ = ["PrinterEndpoint", "PrinterEndpointFactory", "format_task"]


class PrinterEndpoint(Endpoint):
    """Prints one line per watched task.

    Example output::

        (event, 'button_pressed'): ['A']
        (store_page, 'depth'): [Page 'depth' = 2.5 from 'robot' (0.0 s ago)]
    """

    def __init__(self, factory: PrinterEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.stream = factory.stream
        self.task_handlers = dict.fromkeys(factory.task_ids, self.print_task)

    def print_task(self, task: Task, key: TaskId) -> SomeTasks:
        """Print ``task`` on one line."""
        print(format_task(task), file=self.stream or sys.stdout, flush=True)
        return None


class PrinterEndpointFactory(EndpointFactory):
    """Builds a `PrinterEndpoint` for the given task ids.

    Example::

        snr.PrinterEndpointFactory([
            (snr.TaskType.event, "button_pressed"),
            (snr.TaskType.event, "button_released"),
        ])
    """

    def __init__(
        self,
        task_ids: List[TaskId],
        stream: Optional[TextIO] = None,
        name: Optional[str] = None,
    ) -> None:
        super().__init__()
        self.task_ids = list(task_ids)
        self.stream = stream
        self.name = name or "printer_endpoint"

    def get(self, parent: AbstractNode) -> PrinterEndpoint:
        return PrinterEndpoint(self, parent)
