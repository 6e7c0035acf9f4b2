"""A moving average filter endpoint and its factory (thesis 5.2, listings A.1, A.2).

This is the filter a student writes in the thesis, importing only from
``snr``. SNR ships the same filter as ``snr.MovingAvgFilterFactory``; this
file shows how it is built, and behaves the same (the README says where the
two differ, and ``tests/test_moving_average_twins.py`` checks they give the
same output). Three small classes, side by side:

* `MovingAvgFilter` holds the numbers and computes their mean.
* `MovingAvgEndpoint` (listing A.1) reacts when a number is stored under its
  input key and stores the new mean under its output key.
* `MovingAvgFilterFactory` (listing A.2) builds the endpoint, and keeps the
  filter's samples, so they survive a hot reload of this file.

Example::

    MovingAvgFilterFactory("depth_raw", "depth", length=5)
"""

import collections
import sys
from typing import Deque

from snr import (
    AbstractNode,
    DataKey,
    Endpoint,
    EndpointFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)

__all__ = [
    "DEFAULT_FILTER_LENGTH",
    "MovingAvgEndpoint",
    "MovingAvgFilter",
    "MovingAvgFilterFactory",
]

DEFAULT_FILTER_LENGTH: int = 3
"""How many samples are averaged when no length is given."""


class MovingAvgFilter:
    """The mean of the newest samples kept in a deque.

    The deque belongs to the factory: a new filter made after a reload sees
    the same samples.

    Example::

        f = MovingAvgFilter(collections.deque(maxlen=2))
        f.update(1.0)
        f.update(3.0)
        f.avg()   # 2.0
    """

    def __init__(self, backing_deque: Deque[float]) -> None:
        self.samples = backing_deque

    def update(self, value: float) -> None:
        """Add a sample; when the deque is full the oldest one drops out."""
        self.samples.append(value)

    def avg(self) -> float:
        """The mean of the samples (0.0 before the first one)."""
        if not self.samples:
            return 0.0
        return sum(self.samples) / len(self.samples)


class MovingAvgEndpoint(Endpoint):
    """Averages the numbers stored under ``input``; stores the mean under ``output``.

    Example::

        MovingAvgEndpoint(factory, parent, "depth_filter", "depth_raw", "depth", f)
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
        self.task_handlers = {
            (TaskType.store_page, self.input): self.update_filter,
        }
        self.filter = filter

    def update_filter(self, task: Task, key: TaskId) -> SomeTasks:
        """Add the stored number to the filter, then store the new mean."""
        page = task.page()
        # Check the data first: after this, the type checker knows it is a number.
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
    """Builds a `MovingAvgEndpoint` and keeps its samples between reloads.

    Args:
        input: the data key to read numbers from.
        output: the data key to store the mean under.
        length: how many of the newest samples to average.

    Example::

        MovingAvgFilterFactory("input_data", "filtered_data", 2)
    """

    def __init__(
        self,
        input: DataKey,
        output: DataKey,
        length: int = DEFAULT_FILTER_LENGTH,
    ) -> None:
        # This module is what a reload re-reads: edit it while the node runs.
        super().__init__(sys.modules[__name__])
        self.input = input
        self.output = output
        self.backing_deque: Deque[float] = collections.deque(maxlen=length)

    def get(self, parent: AbstractNode) -> MovingAvgEndpoint:
        filter = MovingAvgFilter(self.backing_deque)
        return MovingAvgEndpoint(
            self,
            parent,
            "moving_avg_filter",
            self.input,
            self.output,
            filter,
        )
