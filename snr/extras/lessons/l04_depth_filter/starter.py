"""Lesson 4: a filter: your file (docs/lessons.md, "Lesson 4: a filter").

A depth sensor's readings are noisy: the true depth is a slow wave, 2 m ± 1 m,
and each reading is off by about 0.5 m. Write `DepthFilterEndpoint.smooth`
so that the ``depth`` it stores is near the true depth: a moving average of
the last `WINDOW` readings. As it is, it stores each reading as it came,
noise and all.

Run it, and grade it::

    python depth_filter.py --seconds 8
    python -m snr lesson grade 4

The readings and the runner are the lesson's (``make_signal`` and ``main``);
your part is the endpoint below.
"""

from __future__ import annotations

import sys
from typing import List

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.lessons.l04_depth_filter.solution import main, make_signal

__all__ = ["DepthFilterEndpoint", "DepthFilterFactory", "make_signal"]

WINDOW = 8
"""How many readings the moving average takes: more is smoother, but later."""


class DepthFilterEndpoint(Endpoint):
    """Smooths ``depth_raw``: stores the mean of the last `WINDOW` readings as ``depth``.

    Example (`WINDOW` 8, after the first two readings)::

        depth_raw 1.9  -> depth 1.9
        depth_raw 2.3  -> depth 2.1
    """

    def __init__(self, factory: DepthFilterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_filter")
        self.task_handlers = {(TaskType.store_page, "depth_raw"): self.smooth}
        self.recent: List[float] = []
        """The last `WINDOW` readings, the oldest first."""

    def smooth(self, task: Task, key: TaskId) -> SomeTasks:
        """One ``depth`` page for one ``depth_raw`` page."""
        reading = task.val_list[0].data
        # TODO (step 2): append the reading to self.recent; when it holds more
        #                than WINDOW readings, forget the oldest (pop(0)).
        # TODO (step 2): store the mean of self.recent instead of the reading.
        return self.store_data_task("depth", reading)  # for now: the noise and all


class DepthFilterFactory(EndpointFactory):
    """Builds a `DepthFilterEndpoint`.

    Example::

        DepthFilterFactory()
    """

    def get(self, parent: AbstractNode) -> DepthFilterEndpoint:
        return DepthFilterEndpoint(self, parent)


if __name__ == "__main__":
    main(sys.argv, DepthFilterFactory())
