"""Tutorial step 4: two nodes talking.

One node per computer: a ``sensor`` node (on the robot) measures depth with
step 3's sensor loop and sends it to a ``display`` node (on the laptop) over
TCP. The nodes know nothing
of the network; a `SocketsPair` adds a loop to each that forwards pages by
key. Run the display in one terminal and the sensor in another:

    python step04_two_nodes.py display
    python step04_two_nodes.py sensor

or both at once, each in its own process:

    python step04_two_nodes.py display sensor

On two computers, change ``127.0.0.1`` to the display computer's address.
``--port`` picks another port; ``--seconds`` how long both nodes run.
"""

import argparse
import sys
from typing import List, Sequence, Tuple

# The sensor of step 3, unchanged: components do not know about the network.
from step03_a_loop import DepthSensorFactory

from snr import (
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
)


class DepthDisplay(Endpoint):
    """Prints each depth page, and which node it came from."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_display")
        self.task_handlers = {(TaskType.store_page, "depth_m"): self.show}

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        print(f"depth {page.data:.2f} m (measured by {page.origin})", flush=True)
        return None


class DepthDisplayFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> DepthDisplay:
        return DepthDisplay(self, parent)


def make_components(port: int = 9010, seconds: float = 10.0) -> ComponentsByRole:
    """Both roles; the sockets pair joins them (the server listens on ``port``)."""
    link = SocketsPair(server_tuple=("127.0.0.1", port))
    return {
        "sensor": [
            DepthSensorFactory(rate_hz=5),
            link.client(["depth_m"]),  # sends every page stored under depth_m
            TimeoutLoopFactory(seconds=seconds),
        ],
        "display": [
            link.server(),  # stores the pages the client sends
            DepthDisplayFactory(),
            TimeoutLoopFactory(seconds=seconds),
        ],
    }


def parse_options(argv: Sequence[str]) -> Tuple[argparse.Namespace, List[str]]:
    """Our options; the rest (the roles) goes to the CliRunner."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--port", type=int, default=9010)
    parser.add_argument("--seconds", type=float, default=10.0)
    options, rest = parser.parse_known_args(argv[1:])
    return options, [argv[0], *rest]


if __name__ == "__main__":
    options, runner_argv = parse_options(sys.argv)
    CliRunner(make_components(options.port, options.seconds), runner_argv).run()
