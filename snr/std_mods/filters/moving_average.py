"""Moving average filter endpoint and factory (thesis listings A.1, A.2).

The filter's samples live on the factory, so they survive a hot reload of
this module: the rebuilt endpoint picks up where the old one stopped.
`MovingAvgFilter` itself is in the runtime layer (`snr.core`), where listing
A.1 finds it; it is re-exported here.
"""

from __future__ import annotations

import collections
import sys
from typing import Deque, Optional

from snr.core import Endpoint, EndpointFactory, MovingAvgFilter, tasks
from snr.prelude import (
    AbstractNode,
    ComponentError,
    DataKey,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)

__all__ = [
    "DEFAULT_FILTER_LENGTH",
    "MovingAvgEndpoint",
    "MovingAvgFilter",
    "MovingAvgFilterFactory",
]

DEFAULT_FILTER_LENGTH: int = 3
"""How many samples the filter averages when no length is given."""


class MovingAvgEndpoint(Endpoint):
    """Averages numbers stored under ``input``; stores the mean under ``output``.

    Example::

        MovingAvgFilterFactory("depth_raw", "depth", length=5)
    """

    def __init__(
        self,
        factory: EndpointFactory,
        parent: AbstractNode,
        name: str,
        input: DataKey,
        output: DataKey,
        filter: MovingAvgFilter,
    ) -> None:
        super().__init__(factory, parent, name)
        self.input = input
        self.output = output
        self.task_handlers = {(TaskType.store_page, self.input): self.update_filter}
        self.filter = filter

    def update_filter(self, task: Task, key: TaskId) -> SomeTasks:
        """Add the stored number to the filter and store the new mean."""
        page = task.page()
        if not (
            task.name == self.input
            and page is not None
            and isinstance(page.data, (int, float))
            and not isinstance(page.data, bool)
        ):
            self.warn("Invalid data from %s: expected a number", task)
            return None
        self.filter.update(page.data)
        return tasks.store_page(self.page(self.output, self.filter.avg()))


class MovingAvgFilterFactory(EndpointFactory):
    """Builds a `MovingAvgEndpoint`; keeps the samples across reloads.

    Args:
        input: the data key to read numbers from.
        output: the data key to store the average under.
        length: how many samples to average.
        name: the endpoint's name (default ``"moving_avg_filter"``).

    Example::

        MovingAvgFilterFactory("input_data", "filtered_data", 2)
    """

    def __init__(
        self,
        input: DataKey,
        output: DataKey,
        length: int = DEFAULT_FILTER_LENGTH,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        if length < 1:
            raise ComponentError(
                f"MovingAvgFilterFactory(length={length}): length must be at least 1."
            )
        self.input = input
        self.output = output
        self.name = name or "moving_avg_filter"
        self.backing_deque: Deque[float] = collections.deque(maxlen=length)

    def get(self, parent: AbstractNode) -> MovingAvgEndpoint:
        filter = MovingAvgFilter(self.backing_deque)
        return MovingAvgEndpoint(self, parent, self.name, self.input, self.output, filter)
