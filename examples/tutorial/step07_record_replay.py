"""Tutorial step 7: recording a run and replaying it.

Record what a sensor measured, then replay it as often as you like: through a
different filter, on a computer without the sensor, in a test.

    python step07_record_replay.py record     # writes runs/depth_run.jsonl
    python step07_record_replay.py replay     # filters and prints the recording

The recording is a text file with one JSON page per line, in the ``runs``
folder (made if missing; git ignores it). The replayer stores each page
again, under its key and with its origin, as if the sensor were there;
``fast=True`` skips the waiting between pages. ``--file`` picks another file.
"""

import argparse
import math
import os
import random
import sys
from typing import List, Sequence, Tuple

from snr import (
    AbstractNode,
    CliRunner,
    ComponentsByRole,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    MovingAvgFilterFactory,
    RecorderEndpointFactory,
    ReplayerLoopFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
)


def noisy_depths(count: int = 20, seed: int = 3) -> List[float]:
    """What the sensor measures: about 2 m, rising and falling, with noise."""
    rng = random.Random(seed)
    return [round(2.0 + math.sin(i / 4) + rng.gauss(0, 0.2), 2) for i in range(count)]


class DepthPrinter(Endpoint):
    """Prints each replayed reading beside the filter's mean."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_printer")
        self.task_handlers = {(TaskType.store_page, "depth"): self.show}

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        raw_page = self.get_page("depth_raw")
        origin = raw_page.origin if raw_page else "?"
        print(f"filtered depth {task.val_list[0].data:.2f} m (recorded by {origin})")
        return None


class DepthPrinterFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> DepthPrinter:
        return DepthPrinter(self, parent)


RECORDING = os.path.join("runs", "depth_run.jsonl")
"""Where ``record`` writes and ``replay`` reads, unless ``--file`` says otherwise."""


def make_components(filename: str = RECORDING) -> ComponentsByRole:
    """Two roles: one records a (simulated) sensor, one replays the recording."""
    return {
        "record": [
            # The "sensor": 20 readings in 0.2 s, then the node stops.
            ListReplayerFactory(noisy_depths(), "depth_raw", period_s=0.01, exit_when_done=True),
            RecorderEndpointFactory(filename, ["depth_raw"]),  # writes every depth_raw page
            TimeoutLoopFactory(seconds=5),  # a safety net: never record for ever
        ],
        "replay": [
            ReplayerLoopFactory(filename, fast=True, exit_when_done=True),
            MovingAvgFilterFactory("depth_raw", "depth", length=4),
            DepthPrinterFactory(),
        ],
    }


def parse_options(argv: Sequence[str]) -> Tuple[argparse.Namespace, List[str]]:
    """Our option (--file); the rest (the role) goes to the CliRunner."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--file", default=RECORDING)
    options, rest = parser.parse_known_args(argv[1:])
    return options, [argv[0], *rest]


if __name__ == "__main__":
    options, runner_argv = parse_options(sys.argv)
    os.makedirs(os.path.dirname(options.file) or ".", exist_ok=True)  # the runs folder
    CliRunner(make_components(options.file), runner_argv).run()
