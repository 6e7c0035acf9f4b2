"""Task dispatch throughput of a node, against a bare deque + dict loop.

A ping-pong endpoint answers every ``ping`` event with a ``pong`` and every
``pong`` with a ``ping``. We count tasks per second in the default mode (as
the listings build a config: DEBUG, profiler on) and in DEPLOYED mode, with
0 to 1,000 idle endpoints in the node, and run the same endpoint's handlers in
the simplest possible loop (a ``deque`` and a ``dict``) in the same process:
the pure-Python floor the node's overheads are measured against. A loop of
closures is shown too, for reference.

Also measured: ``python -c "import snr"`` and a node's start-up time, and
what the DEBUG watchdog costs: the default-mode rate with the watchdog on
(one look at the node every 0.5 s, and every 10 ms: 50 times as often) against
off, in runs long enough for it to look several times.

Run: ``python bench/bench_dispatch.py [--tasks N]`` (or ``nox -s bench``);
``--watchdog-only`` runs only the watchdog comparison.
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics
import subprocess
import sys
import time
from typing import Callable, Deque, Dict, List, Optional, Tuple

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    Node,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.utils import DummyEndpointFactory, MockNode

PING = (TaskType.event, "ping")
PONG = (TaskType.event, "pong")


class PingPong(Endpoint):
    """Bounces ping/pong events until ``limit`` tasks have been handled."""

    def __init__(self, factory: PingPongFactory, parent: AbstractNode, limit: int) -> None:
        super().__init__(factory, parent, "ping_pong")
        self.limit = limit
        self.count = 0
        self.started = 0.0
        self.finished = 0.0
        self.cpu_s = 0.0  # the process's CPU time (every thread's) from begin to the end
        self.task_handlers = {PING: self.on_ping, PONG: self.on_pong}

    def begin(self) -> None:
        self.started = time.perf_counter()
        self.cpu_s = time.process_time()
        self.schedule(Task(TaskType.event, "ping"))

    def on_ping(self, task: Task, key: TaskId) -> SomeTasks:
        self.count += 1
        if self.count >= self.limit:
            self.finished = time.perf_counter()
            self.cpu_s = time.process_time() - self.cpu_s
            return tasks.terminate("done")
        return Task(TaskType.event, "pong")

    def on_pong(self, task: Task, key: TaskId) -> SomeTasks:
        self.count += 1
        if self.count >= self.limit:
            self.finished = time.perf_counter()
            self.cpu_s = time.process_time() - self.cpu_s
            return tasks.terminate("done")
        return Task(TaskType.event, "ping")


class PingPongFactory(EndpointFactory):
    def __init__(self, limit: int) -> None:
        super().__init__()
        self.limit = limit
        self.endpoint: Optional[PingPong] = None

    def get(self, parent: AbstractNode) -> PingPong:
        self.endpoint = PingPong(self, parent, self.limit)
        return self.endpoint


def node_rate(
    n_tasks: int,
    idle: int,
    mode: Optional[Mode] = Mode.DEPLOYED,
    watchdog_every_s: Optional[float] = 0.5,
) -> float:
    """Tasks per second through a node with ``idle`` idle endpoints.

    ``mode=None`` builds the config as the thesis listings do,
    ``Config(factories)``: the default mode (DEBUG), profiler on. In DEBUG
    mode the watchdog looks every ``watchdog_every_s`` (None: switched off).
    """
    ping_pong = PingPongFactory(n_tasks)
    idle_factories = [
        DummyEndpointFactory(f"idle_{i}", [(TaskType.event, f"idle_{i}")]) for i in range(idle)
    ]
    factories = {"bench": [*idle_factories, ping_pong]}
    # mode=None: as the listings build it, so DEBUG with the profiler on.
    config = Config(factories) if mode is None else Config(factories, mode=mode, profile=False)
    node = Node("bench", config)
    node.log.setLevel("WARNING")
    if node.watchdog is not None:
        if watchdog_every_s is None:
            node.watchdog = None
        else:
            node.watchdog.every_s = watchdog_every_s
    node.loop()
    endpoint = ping_pong.endpoint
    assert endpoint is not None and endpoint.count == n_tasks
    LAST_RUN_CPU_S[0] = endpoint.cpu_s
    return n_tasks / (endpoint.finished - endpoint.started)


LAST_RUN_CPU_S = [0.0]
"""The CPU time (all threads) of the last `node_rate` run, from the first task to the last."""


def bare_closure_rate(n_tasks: int) -> float:
    """Closures instead of the endpoint's methods, driven by a bare deque + dict loop.

    Shown for reference: a closure bumping a ``nonlocal`` counter is ~40 ns
    cheaper per call than a method bumping ``self.count``, so this floor mixes
    the cost of the handler's own code into the comparison.
    """
    count = 0

    def on_ping(task: Task) -> Optional[Task]:
        nonlocal count
        count += 1
        return None if count >= n_tasks else Task(TaskType.event, "pong")

    def on_pong(task: Task) -> Optional[Task]:
        nonlocal count
        count += 1
        return None if count >= n_tasks else Task(TaskType.event, "ping")

    handlers: Dict[Tuple[TaskType, str], Callable[[Task], Optional[Task]]] = {
        PING: on_ping,
        PONG: on_pong,
    }
    queue: Deque[Task] = collections.deque([Task(TaskType.event, "ping")])
    started = time.perf_counter()
    while queue:
        task = queue.popleft()
        result = handlers[(task.type, task.name)](task)
        if result is not None:
            queue.append(result)
    return n_tasks / (time.perf_counter() - started)


def bare_rate(n_tasks: int) -> float:
    """The node's very handlers (the same PingPong methods) driven by a bare deque + dict loop.

    The floor the node's dispatch is measured against: everything but the
    handlers' own work is the node's overhead.
    """
    factory = PingPongFactory(n_tasks)
    endpoint = factory.get(MockNode(mode=Mode.DEPLOYED))
    handlers: Dict[TaskId, Callable[[Task, TaskId], SomeTasks]] = {
        PING: endpoint.on_ping,
        PONG: endpoint.on_pong,
    }
    queue: Deque[Task] = collections.deque([Task(TaskType.event, "ping")])
    started = time.perf_counter()
    while queue:
        task = queue.popleft()
        key = (task.type, task.name)
        handler = handlers.get(key)
        if handler is None:  # the final terminate task
            break
        result = handler(task, key)
        if result is not None:
            queue.append(result)  # type: ignore[arg-type]
    assert endpoint.count == n_tasks
    return n_tasks / (time.perf_counter() - started)


def command_time_s(code: str, runs: int = 5) -> float:
    """Median wall time of ``python -c code`` (a fresh interpreter each run).

    Bytecode caching is allowed (PYTHONDONTWRITEBYTECODE removed) and one
    warm-up run fills the cache, as on a student's machine after the first run.
    """
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    times: List[float] = []
    for _ in range(runs):
        started = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True, env=env)
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def startup_s(components: int) -> float:
    """Seconds from Node() to a finished loop whose first task stops it."""
    factories = [
        DummyEndpointFactory(f"e{i}", [(TaskType.event, f"e{i}")]) for i in range(components)
    ]
    started = time.perf_counter()
    node = Node("bench", Config({"bench": factories}, mode=Mode.DEPLOYED))
    node.log.setLevel("WARNING")
    node.schedule(tasks.terminate("measured"))
    node.loop()
    return time.perf_counter() - started


def watchdog_cost(n_tasks: int, rounds: int) -> None:
    """Print the default-mode rate with the watchdog off and on, median of ``rounds``.

    Each run must last long enough for the watchdog to look a few times (it
    looks every 0.5 s). Two rates per run: tasks per second of wall time, and
    tasks per second of the process's CPU time (every thread's, the watchdog's
    too), which other programs on a busy machine disturb far less. Each round
    runs the cases back to back; a case's ratio is the median over rounds of
    its rate against the "off" run of the same round.
    """
    cases: List[Tuple[str, Optional[float]]] = [
        ("DEBUG, watchdog off", None),
        ("DEBUG, watchdog on (every 0.5 s)", 0.5),
        ("DEBUG, watchdog on (every 10 ms)", 0.01),
    ]
    wall: Dict[str, List[float]] = {label: [] for label, _ in cases}
    cpu: Dict[str, List[float]] = {label: [] for label, _ in cases}
    for _ in range(rounds):  # interleaved: the machine's drift spreads over every case
        for label, every_s in cases:
            wall[label].append(node_rate(n_tasks, 0, None, every_s))
            cpu[label].append(n_tasks / LAST_RUN_CPU_S[0])
    off = cases[0][0]
    print(
        f"\nWatchdog cost, ping-pong, {n_tasks:,} tasks a run, median of {rounds} "
        "interleaved rounds"
    )
    print(f"{'case':<34} {'tasks/s':>10} {'vs off':>7} {'tasks/CPU-s':>12} {'vs off':>7}")
    for label, _ in cases:
        wall_ratio = statistics.median(r / o for r, o in zip(wall[label], wall[off]))
        cpu_ratio = statistics.median(r / o for r, o in zip(cpu[label], cpu[off]))
        print(
            f"{label:<34} {statistics.median(wall[label]):>10,.0f} {wall_ratio:>7.3f} "
            f"{statistics.median(cpu[label]):>12,.0f} {cpu_ratio:>7.3f}"
        )
    print("target: DEBUG with the watchdog on (every 0.5 s) >= 0.95 of off")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--tasks", type=int, default=300_000, help="tasks per measurement")
    parser.add_argument("--runs", type=int, default=5, help="best of this many runs")
    parser.add_argument(
        "--watchdog-tasks", type=int, default=1_000_000, help="tasks per watchdog run"
    )
    parser.add_argument("--watchdog-rounds", type=int, default=11, help="watchdog rounds")
    parser.add_argument("--watchdog-only", action="store_true", help="only the watchdog comparison")
    args = parser.parse_args()
    n, runs = args.tasks, args.runs
    if args.watchdog_only:
        watchdog_cost(args.watchdog_tasks, args.watchdog_rounds)
        return

    # Interleave the cases, best of ``runs`` each: the machine's speed drifts
    # (shared cores, frequency scaling), and interleaving spreads that drift
    # over every case instead of penalising whichever ran last.
    cases: List[Tuple[str, Callable[[], float]]] = [
        ("bare loop, same handlers", lambda: bare_rate(n)),
        ("bare loop, closures (reference)", lambda: bare_closure_rate(n)),
    ]
    cases.append(("default mode (DEBUG), 0 idle", lambda: node_rate(n, 0, None)))
    cases.append(("default mode (DEBUG), 1000 idle", lambda: node_rate(n, 1000, None)))
    for idle in (0, 10, 100, 1000):
        cases.append(
            (f"DEPLOYED, {idle} idle endpoints", lambda idle=idle: node_rate(n, idle))  # type: ignore[misc]
        )
    best = {label: 0.0 for label, _ in cases}
    for _ in range(runs):
        for label, measure in cases:
            best[label] = max(best[label], measure())
    rows = [(label, best[label]) for label, _ in cases]
    bare = rows[0][1]
    zero_idle = {
        "default": best["default mode (DEBUG), 0 idle"],
        "DEPLOYED": best["DEPLOYED, 0 idle endpoints"],
    }

    print(
        f"\nTask dispatch, ping-pong, {n:,} tasks, best of {runs} (Python {sys.version.split()[0]})"
    )
    print(f"{'case':<34} {'tasks/s':>12} {'vs bare':>8} {'vs 0 idle':>10}")
    for label, rate in rows:
        same_mode = zero_idle["DEPLOYED" if label.startswith("DEPLOYED") else "default"]
        print(f"{label:<34} {rate:>12,.0f} {rate / bare:>8.0%} {rate / same_mode:>10.0%}")
    print("targets: default mode >= 60% of bare, DEPLOYED >= 80%, 1000 idle >= 90% of 0 idle")

    python_s = command_time_s("pass")
    import_s = command_time_s("import snr")
    print(f"\n{'start-up':<34} {'seconds':>12}")
    print(f"{'python -c pass':<34} {python_s:>12.3f}")
    label = 'python -c "import snr"'
    print(f"{label:<34} {import_s:>12.3f}")
    print(f"{'  of which importing snr':<34} {import_s - python_s:>12.3f}")
    for components in (1, 100):
        value = min(startup_s(components) for _ in range(runs))
        print(f"{f'node start+stop, {components} endpoints':<34} {value:>12.4f}")

    watchdog_cost(args.watchdog_tasks, args.watchdog_rounds)


if __name__ == "__main__":
    main()
