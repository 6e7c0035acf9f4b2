"""Tutorial step 4: two nodes talking.

One node per computer: a ``sensor`` node (on the robot) measures depth with
step 3's sensor loop and sends it to a ``display`` node (on the laptop) over
TCP. The components know nothing of the network; a `SocketsPair` adds a loop
to each node that forwards pages by key. Run the display in one terminal and
the sensor in another:

    python step04_two_nodes.py display
    python step04_two_nodes.py sensor

or both at once, each in its own process:

    python step04_two_nodes.py display sensor

The sensor measures for five seconds (``--seconds`` changes that), then
stops; the display stops when the sensor has left. On two computers, change
``127.0.0.1`` to the display computer's address. ``--port`` picks another port.
"""

import argparse
import sys
from typing import List, Sequence, Tuple

# The sensor of step 3, unchanged: components do not know about the network.
from step03_a_loop import DepthSensorFactory

from snr import (
    COMMS_DISCONNECTED,
    AbstractNode,
    CliRunner,
    ComponentsByRole,
    Endpoint,
    EndpointFactory,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)


class DepthDisplay(Endpoint):
    """Prints each depth page and which node made it; stops when the sensor leaves."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_display")
        self.task_handlers = {
            (TaskType.store_page, "depth_m"): self.show,
            # The link schedules this event when a peer goes away.
            (TaskType.event, COMMS_DISCONNECTED): self.sensor_left,
        }

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        print(f"depth {page.data:.2f} m (measured by {page.origin})", flush=True)
        return None

    def sensor_left(self, task: Task, key: TaskId) -> SomeTasks:
        return tasks.terminate("the sensor has left")


class DepthDisplayFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> DepthDisplay:
        return DepthDisplay(self, parent)


def make_components(port: int = 9010, seconds: float = 5.0) -> ComponentsByRole:
    """Both roles; the sockets pair joins them (the server listens on ``port``).

    The sensor stops after ``seconds``; the display runs until the sensor has
    left (or Ctrl-C).
    """
    link = SocketsPair(server_tuple=("127.0.0.1", port))
    return {
        "sensor": [
            DepthSensorFactory(rate_hz=5),
            link.client(["depth_m"]),  # sends every page stored under depth_m
            TimeoutLoopFactory(seconds=seconds),  # then the sensor stops
        ],
        "display": [
            link.server(),  # stores the pages the client sends
            DepthDisplayFactory(),
        ],
    }


def parse_options(argv: Sequence[str]) -> Tuple[argparse.Namespace, List[str]]:
    """Our options; the rest (the roles) goes to the CliRunner."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--port", type=int, default=9010)
    parser.add_argument("--seconds", type=float, default=5.0)
    options, rest = parser.parse_known_args(argv[1:])
    return options, [argv[0], *rest]


if __name__ == "__main__":
    options, runner_argv = parse_options(sys.argv)
    CliRunner(make_components(options.port, options.seconds), runner_argv).run()
