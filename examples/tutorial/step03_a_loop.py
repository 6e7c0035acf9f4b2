"""Tutorial step 3: a loop.

An endpoint only runs when a task arrives. A loop runs on its own thread,
over and over: the place for reading a sensor or a socket. Here a simulated
depth sensor stores a reading ten times a second, an endpoint prints each
one, and a ready-made timeout loop stops the node after one second.

    python step03_a_loop.py              # about ten lines such as ``depth 2.33 m``
    python step03_a_loop.py --seconds 3  # runs for three seconds instead
"""

import argparse
import math

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
)


class DepthSensorLoop(ThreadLoop):
    """Stores a (simulated) depth reading at most ``rate_hz`` times a second."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode, rate_hz: float) -> None:
        super().__init__(factory, parent, "depth_sensor", max_tick_rate_hz=rate_hz)
        self.readings = 0

    def setup(self) -> None:
        # Runs once on the loop's thread: open the device here.
        self.info("depth sensor ready")

    def loop(self) -> None:
        # Runs again and again on the loop's thread. From here, only queue
        # work for the node: store_data() and schedule() are thread-safe.
        depth = 2.0 + math.sin(self.readings / 3)
        self.store_data("depth_m", round(depth, 2))
        self.readings += 1


class DepthSensorFactory(LoopFactory):
    def __init__(self, rate_hz: float = 10) -> None:
        super().__init__()
        self.rate_hz = rate_hz

    def get(self, parent: AbstractNode) -> DepthSensorLoop:
        return DepthSensorLoop(self, parent, self.rate_hz)


class DepthPrinter(Endpoint):
    """Runs on the node's thread, once per stored reading."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_printer")
        self.task_handlers = {(TaskType.store_page, "depth_m"): self.show}

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        print(f"depth {task.val_list[0].data:.2f} m", flush=True)
        return None


class DepthPrinterFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> DepthPrinter:
        return DepthPrinter(self, parent)


def make_config(seconds: float = 1.0) -> Config:
    """The submarine's node: the sensor, the printer, and a stop after ``seconds``."""
    return Config(
        {
            "submarine": [
                DepthSensorFactory(rate_hz=10),
                DepthPrinterFactory(),
                TimeoutLoopFactory(seconds=seconds),  # schedules terminate after that
            ]
        }
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="A simulated depth sensor, printed.")
    parser.add_argument("--seconds", type=float, default=1.0, help="stop after this long")
    SynchronousRunner("submarine", make_config(parser.parse_args().seconds)).run()
