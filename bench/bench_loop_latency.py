"""Loop -> handler latency: from a loop's ``store_data`` to the handler running.

A `ThreadLoop` stores ``time.perf_counter_ns()`` under a key, on its own
thread, about every 2 ms; an endpoint's handler for ``(TaskType.store_page,
key)`` reads the clock as its first statement and keeps the difference. That
is the whole path a sensor reading takes into a node: ``store_data`` builds a
page and a task and queues it, the node's thread wakes (it sleeps on the task
queue's bell when idle), looks the task up, runs the node core's
``store_page`` handler (into the datastore) and then ours.

The baseline, measured in the same run, is the bare hand-off the node cannot
beat: one thread putting ``time.perf_counter_ns()`` into a
``queue.SimpleQueue`` and another thread ``get()``-ting it.

Two conditions for each:

* **idle**: nothing else to do, so the consumer sleeps between stamps and
  every stamp pays a wake-up;
* **load**: the consumer is never idle. The node runs a ping-pong endpoint
  (every ``ping`` event answered by a ``pong`` and back, as in
  ``bench_dispatch.py``); the bare consumer bounces a ``Task`` through its
  own queue the same way. A stamp then waits behind the task being handled,
  and the stamping thread must win the GIL from a busy thread.

Cases are interleaved, one of each per round; every figure is the median over
the rounds of that round's figure (p50, p99, max), the first samples of each
run not counted. SNR runs in the default DEBUG mode (every handler timed for
the profiler) and in DEPLOYED mode.

Run: ``python bench/bench_loop_latency.py [--samples N] [--rounds N]``
(or ``nox -s bench``).
"""

from __future__ import annotations

import argparse
import queue
import statistics
import sys
import threading
import time
from functools import partial
from typing import Callable, Dict, List, Optional, Tuple, Union

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    tasks,
)

KEY = "stamp"
PING = (TaskType.event, "ping")
PONG = (TaskType.event, "pong")
SAFETY_S = 60.0
TARGET_RATIO = 2.0


# -- SNR components --------------------------------------------------------------
class Stamper(ThreadLoop):
    """Stores the time, in perf_counter nanoseconds, at its tick rate."""

    def __init__(self, factory: StamperFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stamper", max_tick_rate_hz=1.0 / factory.interval_s)

    def loop(self) -> None:
        self.store_data(KEY, time.perf_counter_ns())


class StamperFactory(LoopFactory):
    def __init__(self, interval_s: float) -> None:
        super().__init__()
        self.interval_s = interval_s

    def get(self, parent: AbstractNode) -> Stamper:
        return Stamper(self, parent)


class Receiver(Endpoint):
    """Keeps how long each stamp took to reach it; stops the node when it has enough."""

    def __init__(self, factory: ReceiverFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "receiver")
        self.wanted = factory.wanted
        self.latencies_ns = factory.latencies_ns
        self.task_handlers = {(TaskType.store_page, KEY): self.on_stamp}

    def on_stamp(self, task: Task, key: TaskId) -> SomeTasks:
        now = time.perf_counter_ns()
        self.latencies_ns.append(now - task.val_list[0].data)
        if len(self.latencies_ns) >= self.wanted:
            return tasks.terminate("enough samples")
        return None


class ReceiverFactory(EndpointFactory):
    def __init__(self, wanted: int) -> None:
        super().__init__()
        self.wanted = wanted
        self.latencies_ns: List[int] = []

    def get(self, parent: AbstractNode) -> Receiver:
        return Receiver(self, parent)


class PingPong(Endpoint):
    """Keeps the node busy: every ping answered by a pong and every pong by a ping."""

    def __init__(self, factory: PingPongFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "ping_pong")
        self.task_handlers = {PING: self.on_ping, PONG: self.on_pong}

    def begin(self) -> None:
        self.schedule(Task(TaskType.event, "ping"))

    def on_ping(self, task: Task, key: TaskId) -> SomeTasks:
        return Task(TaskType.event, "pong")

    def on_pong(self, task: Task, key: TaskId) -> SomeTasks:
        return Task(TaskType.event, "ping")


class PingPongFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> PingPong:
        return PingPong(self, parent)


def node_latencies(samples: int, interval_s: float, mode: Mode, load: bool) -> List[int]:
    """Nanoseconds from each ``store_data`` to the store_page handler, in a node."""
    receiver = ReceiverFactory(samples)
    factories: List[Union[EndpointFactory, LoopFactory]] = [receiver]
    if load:
        factories.append(PingPongFactory())
    factories.append(StamperFactory(interval_s))
    # Mode.DEBUG is what Config(factories) gives: the profiler times every handler.
    config = Config({"bench": factories}, mode=mode)
    node = Node("bench", config)
    node.log.setLevel("WARNING")
    watchdog = threading.Timer(SAFETY_S, node.set_terminate_flag, args=("too slow",))
    watchdog.start()
    try:
        node.loop()
    finally:
        watchdog.cancel()
    if len(receiver.latencies_ns) < samples:
        raise RuntimeError(f"only {len(receiver.latencies_ns)} of {samples} stamps arrived")
    return receiver.latencies_ns


# -- the bare hand-off ----------------------------------------------------------
def bare_latencies(samples: int, interval_s: float, load: bool) -> List[int]:
    """The same measurement with one SimpleQueue between two plain threads."""
    inbox: queue.SimpleQueue[Union[int, Task]] = queue.SimpleQueue()
    stop = threading.Event()

    def produce() -> None:
        while not stop.is_set():
            time.sleep(interval_s)
            inbox.put(time.perf_counter_ns())

    handlers: Dict[Tuple[TaskType, str], Callable[[Task], Task]] = {
        PING: lambda task: Task(TaskType.event, "pong"),
        PONG: lambda task: Task(TaskType.event, "ping"),
    }
    if load:
        inbox.put(Task(TaskType.event, "ping"))
    latencies: List[int] = []
    producer = threading.Thread(target=produce, daemon=True)
    producer.start()
    deadline = time.monotonic() + SAFETY_S
    try:
        while len(latencies) < samples:
            item = inbox.get(timeout=SAFETY_S)
            if isinstance(item, Task):
                inbox.put(handlers[(item.type, item.name)](item))
                continue
            latencies.append(time.perf_counter_ns() - item)
            if time.monotonic() > deadline:
                raise RuntimeError(f"only {len(latencies)} of {samples} stamps arrived")
    finally:
        stop.set()
        producer.join()
    return latencies


# -- running and reporting -----------------------------------------------------------
def percentile(values: List[int], fraction: float) -> int:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=2000, help="stamps per case (2000)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (3)")
    parser.add_argument("--interval-ms", type=float, default=2.0, help="time between stamps (2.0)")
    args = parser.parse_args(argv)
    samples, rounds, interval_s = args.samples, args.rounds, args.interval_ms / 1000
    warm_up = min(100, samples // 10)
    wanted = samples + warm_up

    cases: List[Tuple[str, Callable[[], List[int]]]] = []
    for load in (False, True):
        condition = "load" if load else "idle"
        cases.append(
            (f"bare SimpleQueue, {condition}", partial(bare_latencies, wanted, interval_s, load))
        )
        for mode in (Mode.DEBUG, Mode.DEPLOYED):
            cases.append(
                (
                    f"SNR {mode.name}, {condition}",
                    partial(node_latencies, wanted, interval_s, mode, load),
                )
            )

    # Interleaved, so a busy moment on the shared machine hits every case alike.
    per_round: Dict[str, List[Tuple[int, int, int]]] = {label: [] for label, _ in cases}
    for _ in range(rounds):
        for label, measure in cases:
            latencies = measure()[warm_up:]
            per_round[label].append(
                (percentile(latencies, 0.50), percentile(latencies, 0.99), max(latencies))
            )

    def median_us(label: str, column: int) -> float:
        return statistics.median(row[column] for row in per_round[label]) / 1000

    print(
        f"\nLoop -> handler latency: {samples:,} stamps per case ({warm_up} warm-up not "
        f"counted), one every {args.interval_ms:g} ms,\nmedian of {rounds} interleaved "
        f"rounds (Python {sys.version.split()[0]})\n"
    )
    header = (
        f"{'case':<26}{'p50 us':>9}{'p99 us':>9}{'max us':>9}{'vs bare p50':>13}"
        f"{'p50 per round us':>20}"
    )
    print(header)
    print("-" * len(header))
    verdicts: List[str] = []
    bare_p50 = 0.0
    for label, _ in cases:
        p50, p99, most = (median_us(label, column) for column in range(3))
        if label.startswith("bare"):
            bare_p50 = p50
        ratio = p50 / bare_p50
        spread = ", ".join(f"{row[0] / 1000:.0f}" for row in per_round[label])
        print(f"{label:<26}{p50:>9.1f}{p99:>9.1f}{most:>9.0f}{ratio:>12.2f}x{spread:>20}")
        if not label.startswith("bare"):
            met = "met" if ratio <= TARGET_RATIO else "MISSED"
            verdicts.append(f"  {label}: {ratio:.2f}x ({met})")
    print(f"\nTarget: node p50 <= {TARGET_RATIO:g}x the bare hand-off's p50")
    print("\n".join(verdicts))


if __name__ == "__main__":
    main()
