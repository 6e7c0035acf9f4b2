"""Run the moving average filter on a noisy depth sensor and print both.

    python filter_demo.py

A list replayer plays 40 noisy depth readings, one every 50 ms; the filter
averages the newest 5; a small display endpoint prints each reading beside the
filter's mean. The node stops by itself after 3 seconds.
"""

import math
import random
from typing import List

from moving_average import MovingAvgFilterFactory

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
)


class DepthDisplay(Endpoint):
    """Prints the newest raw reading beside each new mean."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_display")
        self.task_handlers = {(TaskType.store_page, "depth"): self.show}

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        raw = self.get_data("depth_raw")
        mean = task.val_list[0].data
        print(f"raw {raw:5.2f} m   filtered {mean:5.2f} m")
        return None


class DepthDisplayFactory(EndpointFactory):
    """Builds the `DepthDisplay`."""

    def get(self, parent: AbstractNode) -> DepthDisplay:
        return DepthDisplay(self, parent)


def noisy_depths(count: int, seed: int = 7) -> List[float]:
    """Depth readings around 5 m that rise and fall, with sensor noise."""
    rng = random.Random(seed)
    return [round(5 + math.sin(i / 8) + rng.gauss(0, 0.3), 2) for i in range(count)]


def make_config(readings: List[float], period_s: float = 0.05, seconds: float = 3.0) -> Config:
    """One node: replay the readings, filter them, show raw and filtered."""
    return Config(
        {
            "filter_demo": [
                ListReplayerFactory(readings, "depth_raw", period_s=period_s),
                MovingAvgFilterFactory("depth_raw", "depth", length=5),
                DepthDisplayFactory(),
                TimeoutLoopFactory(seconds=seconds),
            ]
        }
    )


if __name__ == "__main__":
    SynchronousRunner("filter_demo", make_config(noisy_depths(40))).run()
