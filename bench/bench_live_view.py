"""What the live view costs the node, and whether a stalled viewer slows it.

A node stores N pages as fast as it can (one key, a dict of numbers, as an
IMU would) with a `FoxgloveBridgeFactory` showing that key, and:

1. no viewer connected (the baseline);
2. a viewer that reads every frame it is sent;
3. a stalled viewer: it subscribes, then never reads again.

Each viewer is a separate process (the ``websockets`` client), as Foxglove
would be. Target: the node's rate with a stalled viewer is at least 0.9 of
its rate without it (the issue's bound: a slow viewer never slows the node).
The pages a stalled viewer misses are dropped, newest kept, and counted.

Run: ``python bench/bench_live_view.py [--pages N]`` (or ``nox -s bench``).
Needs ``pip install 'snr-robotics[view]'``.
"""

from __future__ import annotations

import argparse
import logging
import socket
import statistics
import subprocess
import sys
import threading
import time
from typing import Dict, List, Optional, Tuple

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    FoxgloveBridgeFactory,
    Mode,
    Node,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)

IMU = {"ax": 0.01, "ay": -9.81, "az": 0.2, "gx": 0.001, "gy": 0.002, "gz": -0.003}

# The viewer process: subscribe to every channel, say so, then read or stall.
VIEWER = """
import json, socket, sys, time
from websockets.sync.client import connect
port, mode = int(sys.argv[1]), sys.argv[2]
sock = socket.create_connection(("127.0.0.1", port))
sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 16)
with connect(f"ws://127.0.0.1:{port}", sock=sock, subprotocols=["foxglove.sdk.v1"],
             max_queue=1, close_timeout=0.5) as ws:
    json.loads(ws.recv())                      # serverInfo
    channels = json.loads(ws.recv())["channels"]
    subs = [{"id": c["id"], "channelId": c["id"]} for c in channels]
    ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
    ws.recv()                                  # the current page: subscribed
    print("subscribed", flush=True)
    frames = 0
    if mode == "stall":
        sys.stdin.readline()                   # read nothing until told to go
    else:
        try:
            while True:
                ws.recv(timeout=2.0)
                frames += 1
        except Exception:
            pass
"""


class Burst(Endpoint):
    """On a ``go`` event, stores ``count`` pages from the node's own thread; stops at the last."""

    def __init__(self, factory: BurstFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "burst")
        self.burst = factory
        self.seen = 0
        self.task_handlers = {
            (TaskType.event, "go"): self.go,
            (TaskType.store_page, "imu"): self.on_page,
        }

    def go(self, task: Task, key: TaskId) -> SomeTasks:
        # Returned by a handler, so the tasks never wait for room in the queue.
        self.seen = 0
        self.burst.started = time.perf_counter()
        return [self.store_data_task("imu", IMU) for _ in range(self.burst.count)]

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        self.seen += 1
        if self.seen < self.burst.count or not self.burst.started:
            return None
        self.burst.finished = time.perf_counter()
        return tasks.terminate("burst stored")


class BurstFactory(EndpointFactory):
    def __init__(self, count: int) -> None:
        super().__init__()
        self.count = count
        self.started = 0.0
        self.finished = 0.0

    def get(self, parent: AbstractNode) -> Burst:
        return Burst(self, parent)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def run(count: int, viewer: Optional[str]) -> Tuple[float, int, int]:
    """(pages/s, pages sent, pages dropped) of one burst; ``viewer``: None, 'read' or 'stall'."""
    burst = BurstFactory(count)
    bridge = FoxgloveBridgeFactory("imu", port=free_port())
    config = Config({"bench": [burst, bridge]}, mode=Mode.DEPLOYED, profile=False)
    node = Node("bench", config)
    node.log.setLevel(logging.WARNING)
    thread = threading.Thread(target=node.loop)
    thread.start()
    deadline = time.monotonic() + 5.0
    while bridge.stats.pages_sent == 0 and node.get_page("imu") is None:
        node.store_data("imu", IMU)  # the first page advertises the channel
        time.sleep(0.01)
        if time.monotonic() > deadline:
            raise RuntimeError("the node did not start")
    process = None
    if viewer is not None:
        process = subprocess.Popen(
            [sys.executable, "-c", VIEWER, str(bridge.port), viewer],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert process.stdout is not None
        if process.stdout.readline().strip() != "subscribed":
            raise RuntimeError("the viewer did not subscribe")
    node.schedule(Task(TaskType.event, "go"))
    thread.join(60.0)
    if process is not None:
        process.communicate("go\n", timeout=10.0)
    rate = count / (burst.finished - burst.started)
    return rate, bridge.stats.pages_sent, bridge.stats.pages_dropped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--pages", type=int, default=50_000)
    parser.add_argument("--rounds", type=int, default=7, help="rounds of the three runs")
    args, _ = parser.parse_known_args()
    logging.getLogger("snr.bench").setLevel(logging.ERROR)  # drops are counted below
    n = args.pages
    cases = {"no viewer (baseline)": None, "a reading viewer": "read", "a stalled viewer": "stall"}
    results: Dict[str, List[Tuple[float, int, int]]] = {label: [] for label in cases}
    for round_ in range(args.rounds):
        labels = list(cases)
        labels = labels[round_ % 3 :] + labels[: round_ % 3]  # interleaved: load hits all
        for label in labels:
            results[label].append(run(n, cases[label]))
    print(f"A node storing {n} pages with a live view, DEPLOYED mode ({args.rounds} rounds)")
    print(f"  {'':24} {'best pages/s':>13} {'ratio':>6} {'median':>10} {'ratio':>6} {'dropped':>8}")
    best_base = max(r[0] for r in results["no viewer (baseline)"])
    median_base = statistics.median(r[0] for r in results["no viewer (baseline)"])
    for label, runs in results.items():
        best = max(r[0] for r in runs)
        median = statistics.median(r[0] for r in runs)
        dropped = max(r[2] for r in runs)
        print(
            f"  {label:24} {best:13,.0f} {best / best_base:6.2f} {median:10,.0f} "
            f"{median / median_base:6.2f} {dropped:8}"
        )
    stalled = max(r[0] for r in results["a stalled viewer"]) / best_base
    verdict = "met" if stalled >= 0.9 else "NOT met"
    print(f"  target: best rate with a stalled viewer >= 0.9 of without: {stalled:.2f} ({verdict})")


if __name__ == "__main__":
    main()
