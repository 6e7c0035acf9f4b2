"""What DEBUG mode adds to one hop on the node's thread, check by check.

One node plays both ends of ``bench_comms.py``'s ping-pong on its own thread,
with no sockets: a ``ping`` page arrives as a link delivers one (a
``store_page`` task holding a freshly decoded dict), an answering endpoint
stores a ``pong`` page with the same data, and a stand-in for the link's send
handler encodes the pong page (`snr.std_mods.codec.encode_page`) and hands in
the next ping. That is the node's share of one hop of a round trip, with
nothing else on the thread to blur it.

It runs in five set-ups, interleaved round by round, public API only:

* **DEPLOYED**: no checks;
* **DEPLOYED, profiler on**: every handler timed (``Config(profile=True)``);
* **TEST**: handlers timed, page data read-only, ``store_data`` arguments checked;
* **DEBUG, data not read-only**: the default mode with the node core's
  ``freeze`` set to None;
* **DEBUG**: the default mode, as students run it.

Differences between them give each check's share (see docs/performance.md,
"What DEBUG adds to a hop").

Run: ``python bench/bench_debug_hop.py [--hops N] [--rounds N]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Callable, Dict, List, Optional

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    Node,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.core import NodeCore
from snr.std_mods import codec


class Answerer(Endpoint):
    """Answers every ping page with a pong page holding the same data (bench_comms' Ponger)."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "answerer")
        self.task_handlers = {(TaskType.process_data, "ping"): self.pong}

    def pong(self, task: Task, key: TaskId) -> SomeTasks:
        return self.store_data_task("pong", task.val_list[0].data)


class Wire(Endpoint):
    """Stands in for a link: encodes each pong page and hands in the next ping page."""

    def __init__(self, factory: WireFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "wire")
        self.hops = factory.hops
        self.count = 0
        self.started = self.cpu_s = 0.0
        self.task_handlers = {(TaskType.store_page, "pong"): self.send}

    def begin(self) -> None:
        self.started = time.perf_counter()
        self.cpu_s = time.process_time()
        self.schedule(self.next_ping())

    def next_ping(self) -> Task:
        # A new dict each time, as the decoder makes one for every frame.
        page = Page("ping", {"seq": self.count, "value": 0.5}, "pinger", time.time())
        return Task(TaskType.store_page, "ping", [page])

    def send(self, task: Task, key: TaskId) -> SomeTasks:
        codec.encode_page(task.val_list[0])
        self.count += 1
        if self.count >= self.hops:
            self.started = time.perf_counter() - self.started
            self.cpu_s = time.process_time() - self.cpu_s
            return tasks.terminate("done")
        return self.next_ping()


class WireFactory(EndpointFactory):
    def __init__(self, hops: int) -> None:
        super().__init__()
        self.hops = hops
        self.endpoint: Optional[Wire] = None

    def get(self, parent: AbstractNode) -> Wire:
        self.endpoint = Wire(self, parent)
        return self.endpoint


class AnswererFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Answerer:
        return Answerer(self, parent)


def run(hops: int, mode: Mode, profile: Optional[bool], read_only: bool = True) -> float:
    """CPU µs a hop (the node's thread does all the work: CPU time, not wall time)."""
    wire = WireFactory(hops)
    config = Config({"hop": [AnswererFactory(), wire]}, mode=mode, profile=profile)
    node = Node("hop", config)
    node.log.setLevel("WARNING")
    if not read_only:
        core = node.components["node_core"]
        assert isinstance(core, NodeCore)
        core.freeze = None  # as in DEPLOYED: page data passed as it is
    node.loop()
    assert wire.endpoint is not None and wire.endpoint.count == hops
    return wire.endpoint.cpu_s / hops * 1e6


SETUPS: Dict[str, Callable[[int], float]] = {
    "DEPLOYED": lambda n: run(n, Mode.DEPLOYED, False),
    "DEPLOYED, profiler on": lambda n: run(n, Mode.DEPLOYED, True),
    "TEST": lambda n: run(n, Mode.TEST, None),
    "DEBUG, data not read-only": lambda n: run(n, Mode.DEBUG, None, read_only=False),
    "DEBUG": lambda n: run(n, Mode.DEBUG, None),
}


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hops", type=int, default=50_000, help="hops per run (50000)")
    parser.add_argument("--rounds", type=int, default=7, help="interleaved rounds (7)")
    args = parser.parse_args(argv)
    results: Dict[str, List[float]] = {name: [] for name in SETUPS}
    for measure in SETUPS.values():
        measure(min(1000, args.hops))  # warm-up, not counted: first-use imports, the codec
    for _ in range(args.rounds):
        for name, measure in SETUPS.items():  # interleaved: a busy moment hits all alike
            results[name].append(measure(args.hops))
    print(f"Node's thread, CPU per hop ({args.hops:,} hops, {args.rounds} interleaved rounds)")
    print(f"backend {codec.backend()}; median, spread (min-max), and the median over rounds")
    print("of each round's difference to DEPLOYED\n")
    print(f"{'set-up':28}{'µs/hop':>8}{'spread':>14}{'+ vs DEPLOYED':>16}")
    base = results["DEPLOYED"]
    for name, values in results.items():
        extra = statistics.median(v - b for v, b in zip(values, base))
        spread = f"{min(values):.2f}-{max(values):.2f}"
        print(f"{name:28}{statistics.median(values):8.2f}{spread:>14}{extra:+16.2f}")


if __name__ == "__main__":
    main()
