"""Lesson 4: a filter (docs/lessons.md), the reference solution.

A depth sensor's readings are noisy: the true depth is a slow wave, 2 m ± 1 m
with a period of 4 s, and each reading is off by Gaussian noise of 0.5 m
(seeded: the same readings every run; bench/bench_filters.py's signal). The
brain, `DepthFilterEndpoint`, reads each ``depth_raw`` page and stores a
``depth`` page: the mean of the last `WINDOW` readings, a moving average
written by hand (SNR's own is `snr.std_mods.filters.MovingAvgFilter`).

Run it: the readings are replayed into one node, 50 a second, in simulated
time as fast as the computer goes; it prints every 25th sample and how far
the raw and the filtered depth are from the true one::

    python depth_filter.py --seconds 8

To write the filter yourself, ``python -m snr lesson start 4`` writes the
lesson's starter file into your folder, and ``python -m snr lesson grade 4``
grades it.
"""

from __future__ import annotations

import argparse
import math
import random
import sys
from typing import List, Optional, Sequence, Tuple

import snr
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType

__all__ = [
    "DepthFilterEndpoint",
    "DepthFilterFactory",
    "RATE_HZ",
    "WINDOW",
    "lag_samples",
    "main",
    "make_signal",
    "rms_error",
    "run",
]

WINDOW = 8
"""How many readings the moving average takes: more is smoother, but later."""
RATE_HZ = 50
"""Readings a second."""
NOISE_SD_M = 0.5
"""The sensor's noise: the standard deviation of a reading's error, in metres."""
SEED = 42
"""The noise's random seed: the same readings on every run."""


def make_signal(samples: int, seed: int = SEED) -> Tuple[List[float], List[float]]:
    """The true depth and the sensor's noisy readings of it, ``samples`` of each.

    The true depth is ``2 + sin(2 pi i / 200)`` metres (a wave of 200 samples,
    4 s); each reading adds Gaussian noise of `NOISE_SD_M`, from ``seed``.

    Example::

        clean, raw = make_signal(400)
        clean[50], raw[50]    # (3.0, 2.73...): the top of the wave, and a reading of it
    """
    rng = random.Random(seed)
    clean = [2.0 + math.sin(2 * math.pi * i / 200) for i in range(samples)]
    return clean, [depth + rng.gauss(0.0, NOISE_SD_M) for depth in clean]


def rms_error(values: Sequence[float], truth: Sequence[float]) -> float:
    """The root mean square of ``values - truth``: a typical error, in metres.

    Example::

        rms_error([1.0, 3.0], [2.0, 2.0])    # 1.0
    """
    pairs = list(zip(values, truth))
    return math.sqrt(sum((v - t) ** 2 for v, t in pairs) / max(1, len(pairs)))


def lag_samples(filtered: Sequence[float], clean: Sequence[float], most: int = 20) -> int:
    """How many samples ``filtered`` lags behind ``clean``: the best shift, 0 to ``most``.

    The shift ``s`` for which ``filtered[i]`` is nearest ``clean[i - s]``
    (the smallest RMS error, over the samples from ``most`` on). ``most``
    itself means ``most`` or more.

    Example::

        clean, _ = make_signal(400)
        lag_samples([0.0] * 3 + clean, clean)    # 3: three samples late
    """
    count = min(len(filtered), len(clean))
    if count <= most:
        return 0

    def error(shift: int) -> float:
        return rms_error(filtered[most:count], clean[most - shift : count - shift])

    return min(range(most + 1), key=error)


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
        self.recent.append(task.val_list[0].data)
        if len(self.recent) > WINDOW:
            self.recent.pop(0)  # forget the oldest
        return self.store_data_task("depth", sum(self.recent) / len(self.recent))


class DepthFilterFactory(EndpointFactory):
    """Builds a `DepthFilterEndpoint`.

    Example::

        DepthFilterFactory()
    """

    def get(self, parent: AbstractNode) -> DepthFilterEndpoint:
        return DepthFilterEndpoint(self, parent)


class _Keeper(Endpoint):
    """Keeps every ``depth`` page's number, in order."""

    def __init__(self, factory: _KeeperFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "keeper")
        self.kept = factory.kept
        self.task_handlers = {(TaskType.store_page, "depth"): self.keep}

    def keep(self, task: Task, key: TaskId) -> SomeTasks:
        self.kept.append(task.val_list[0].data)
        return None


class _KeeperFactory(EndpointFactory):
    def __init__(self) -> None:
        super().__init__()
        self.kept: List[float] = []

    def get(self, parent: AbstractNode) -> _Keeper:
        return _Keeper(self, parent)


def run(seconds: float, brain: Optional[snr.AbstractFactory] = None) -> List[float]:
    """Replay ``seconds`` of readings into ``brain`` in one node; print how it did.

    ``brain`` is this file's `DepthFilterFactory` unless given (the starter
    file passes its own). The node runs on a `SimClock` as fast as it goes:
    each reading is filtered before the next is stored. Returns the ``depth``
    values.

    Example::

        depths = run(8.0)
    """
    clean, raw = make_signal(max(1, round(seconds * RATE_HZ)))
    keeper = _KeeperFactory()
    components = [
        snr.ListReplayerFactory(raw, "depth_raw", period_s=1 / RATE_HZ, exit_when_done=True),
        brain or DepthFilterFactory(),
        keeper,
    ]
    config = snr.Config({"filter": components}, clock=snr.SimClock(speed=None))
    snr.SynchronousRunner("filter", config).run()
    depths = keeper.kept
    print(" sample  true depth  reading  filtered")
    for i in range(0, min(len(depths), len(raw)), 25):
        print(f"{i:7}  {clean[i]:10.2f}  {raw[i]:7.2f}  {depths[i]:8.2f}")
    print(
        f"{len(raw)} readings, {len(depths)} depth pages. RMS error against the true depth: "
        f"readings {rms_error(raw, clean):.2f} m, filtered {rms_error(depths, clean):.2f} m; "
        f"the filter lags {lag_samples(depths, clean)} samples."
    )
    return depths


def main(argv: List[str], brain: Optional[snr.AbstractFactory] = None) -> None:
    """``python depth_filter.py [--seconds S]``: filter S seconds of readings (50 a second).

    ``brain``: the endpoint's factory that filters (this file's by default).
    """
    parser = argparse.ArgumentParser(prog=argv[0], description="Lesson 4: a filter.")
    parser.add_argument(
        "--seconds", type=float, default=8.0, help="how many seconds of readings (50 a second)"
    )
    options = parser.parse_args(argv[1:])
    if options.seconds <= 0:
        parser.error(f"--seconds {options.seconds:g}: give more than 0")
    run(options.seconds, brain)


if __name__ == "__main__":
    main(sys.argv)
