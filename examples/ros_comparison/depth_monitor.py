"""The depth monitor of docs/coming-from-ros.md and docs/going-to-ros.md, in SNR.

A depth sensor measures ten times a second, a moving average smooths it, a
display prints it. The ROS 2 version of the same system is on those pages.

    python depth_monitor.py robot
"""

import collections
import math
import sys
from typing import Deque

from snr import (
    AbstractNode,
    CliRunner,
    ComponentsByRole,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
)


# -- the sensor: a loop, like a ROS timer callback ---------------------------
class DepthSensor(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_sensor", max_tick_rate_hz=10)
        self.readings = 0

    def loop(self) -> None:
        self.store_data("depth_raw", 5.0 + math.sin(self.readings / 8))
        self.readings += 1


class DepthSensorFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> DepthSensor:
        return DepthSensor(self, parent)


# -- the filter: an endpoint, like a ROS subscription callback ---------------
class MovingAverage(Endpoint):
    def __init__(self, factory: "MovingAverageFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "moving_average")
        self.samples: Deque[float] = collections.deque(maxlen=factory.length)
        self.task_handlers = {(TaskType.store_page, "depth_raw"): self.update}

    def update(self, task: Task, key: TaskId) -> SomeTasks:
        self.samples.append(task.val_list[0].data)
        return self.store_data_task("depth", sum(self.samples) / len(self.samples))


class MovingAverageFactory(EndpointFactory):
    def __init__(self, length: int = 5) -> None:  # a "parameter"
        super().__init__()
        self.length = length

    def get(self, parent: AbstractNode) -> MovingAverage:
        return MovingAverage(self, parent)


# -- the display --------------------------------------------------------------
class DepthDisplay(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_display")
        self.task_handlers = {(TaskType.store_page, "depth"): self.show}

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        self.info("depth %.2f m", task.val_list[0].data)
        return None


class DepthDisplayFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> DepthDisplay:
        return DepthDisplay(self, parent)


# -- the system: like a launch file --------------------------------------------
components: ComponentsByRole = {
    "robot": [
        DepthSensorFactory(),
        MovingAverageFactory(length=5),
        DepthDisplayFactory(),
        TimeoutLoopFactory(seconds=5),
    ],
}

if __name__ == "__main__":
    CliRunner(components, sys.argv).run()
