"""Sockets comms between two node processes, against a bare TCP + json loop.

Two measurements, each made with SNR nodes and with the simplest loop that
does the same work (length-prefixed ``json`` frames over a TCP socket with
``TCP_NODELAY``, one process on each end), in the same run on the same
machine:

* **one-way throughput**: the sender stores 20,000 small pages as fast as it
  can; the time runs from the first store to the moment the receiver has
  stored (and processed) the last one.
* **round trip**: a ping page goes to the other node, which stores it and
  answers with a pong page; p50 and p99 over the round trips after a warm-up.

Each measurement is repeated (``--repeat``, default 5) in fresh processes and
the median is shown. SNR runs in DEPLOYED mode (no profiler) and in the
default DEBUG mode (every handler timed for the profiler).

Run: ``python bench/bench_comms.py [--pages N] [--round-trips N]`` (or ``nox -s bench``).
"""

from __future__ import annotations

import argparse
import collections
import json
import logging
import multiprocessing
import socket
import statistics
import sys
import threading
import time
from multiprocessing.connection import Connection
from typing import Any, Callable, Deque, Dict, List, Optional, Tuple

from snr import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    SocketsPair,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)

KEY = "bench"
SAFETY_S = 60.0


def small_data(i: int) -> Dict[str, Any]:
    return {"seq": i, "value": 0.5}


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


# -- SNR components --------------------------------------------------------------
def stop_when_peer_leaves(task: Task, key: TaskId) -> SomeTasks:
    return tasks.terminate("the other node has finished")


class Blaster(Endpoint):
    """Stores ``count`` pages at once when the link opens; reports the start time."""

    def __init__(self, factory: BlasterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "blaster")
        self.spec = factory
        self.task_handlers = {
            (TaskType.event, COMMS_CONNECTED): self.blast,
            (TaskType.event, COMMS_DISCONNECTED): stop_when_peer_leaves,
        }

    def blast(self, task: Task, key: TaskId) -> SomeTasks:
        self.spec.report.send(("start", time.perf_counter()))
        return [self.store_data_task(KEY, small_data(i)) for i in range(self.spec.count)]


class BlasterFactory(EndpointFactory):
    def __init__(self, report: Connection, count: int) -> None:
        super().__init__()
        self.report, self.count = report, count

    def get(self, parent: AbstractNode) -> Blaster:
        return Blaster(self, parent)


class Counter(Endpoint):
    """Reports the time the ``count``-th page was processed, then stops."""

    def __init__(self, factory: CounterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counter")
        self.spec = factory
        self.seen = 0
        self.task_handlers = {(TaskType.process_data, KEY): self.count}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        self.seen += 1
        if self.seen == self.spec.count:
            self.spec.report.send(("done", time.perf_counter()))
            return tasks.terminate("all pages arrived")
        return None


class CounterFactory(EndpointFactory):
    def __init__(self, report: Connection, count: int) -> None:
        super().__init__()
        self.report, self.count = report, count

    def get(self, parent: AbstractNode) -> Counter:
        return Counter(self, parent)


class Pinger(Endpoint):
    """Sends a ping, times the pong, sends the next; reports every round trip."""

    def __init__(self, factory: PingerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pinger")
        self.spec = factory
        self.sent_at = 0.0
        self.round_trips: List[float] = []
        self.task_handlers = {
            (TaskType.event, COMMS_CONNECTED): self.first_ping,
            (TaskType.process_data, "pong"): self.on_pong,
        }

    def ping(self) -> Task:
        self.sent_at = time.perf_counter()
        return self.store_data_task("ping", small_data(len(self.round_trips)))

    def first_ping(self, task: Task, key: TaskId) -> SomeTasks:
        return self.ping()

    def on_pong(self, task: Task, key: TaskId) -> SomeTasks:
        self.round_trips.append(time.perf_counter() - self.sent_at)
        if len(self.round_trips) < self.spec.count:
            return self.ping()
        self.spec.report.send(("round_trips", self.round_trips))
        return tasks.terminate("all round trips done")


class PingerFactory(EndpointFactory):
    def __init__(self, report: Connection, count: int) -> None:
        super().__init__()
        self.report, self.count = report, count

    def get(self, parent: AbstractNode) -> Pinger:
        return Pinger(self, parent)


class Ponger(Endpoint):
    """Answers every ping page with a pong page holding the same data."""

    def __init__(self, factory: PongerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "ponger")
        self.task_handlers = {
            (TaskType.process_data, "ping"): self.pong,
            (TaskType.event, COMMS_DISCONNECTED): stop_when_peer_leaves,
        }

    def pong(self, task: Task, key: TaskId) -> SomeTasks:
        return self.store_data_task("pong", task.val_list[0].data)


class PongerFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Ponger:
        return Ponger(self, parent)


def run_node(role: str, factories: List[Any], mode: Mode) -> None:
    logging.disable(logging.WARNING)  # keep the table readable (peers leaving is normal here)
    safety = TimeoutLoopFactory(seconds=SAFETY_S)
    SynchronousRunner(role, Config({role: [*factories, safety]}, mode=mode)).run()


# -- the bare loop ---------------------------------------------------------------
def page_frame(i: int, key: str = KEY) -> bytes:
    """The same JSON an SNR page would be, framed the same way."""
    body = json.dumps(
        {
            "v": 1,
            "kind": "page",
            "key": key,
            "data": small_data(i),
            "origin": "bare",
            "created_at_s": time.time(),
            "process": True,
        },
        separators=(",", ":"),
    ).encode("utf-8")
    return len(body).to_bytes(4, "big") + body


def read_frame(stream: Any) -> Dict[str, Any]:
    n = int.from_bytes(stream.read(4), "big")
    obj: Dict[str, Any] = json.loads(stream.read(n).decode("utf-8"))
    return obj


def bare_listen(port: int) -> socket.socket:
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", port))
    listener.listen()
    return listener


def bare_accept(listener: socket.socket) -> socket.socket:
    sock, _ = listener.accept()
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    listener.close()
    return sock


def bare_connect(port: int) -> socket.socket:
    for _ in range(500):
        try:
            sock = socket.create_connection(("127.0.0.1", port))
        except ConnectionRefusedError:
            time.sleep(0.01)
            continue
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return sock
    raise RuntimeError(f"nothing listens on {port}")


def bare_receiver(listener: socket.socket, count: int, report: Connection) -> None:
    with bare_accept(listener) as sock, sock.makefile("rb") as stream:
        for _ in range(count):
            read_frame(stream)
        report.send(("done", time.perf_counter()))


def bare_sender(port: int, count: int, report: Connection) -> None:
    with bare_connect(port) as sock:
        report.send(("start", time.perf_counter()))
        for i in range(count):
            sock.sendall(page_frame(i))
        sock.shutdown(socket.SHUT_WR)
        sock.recv(1)  # wait for the receiver to finish and close


def bare_echo(listener: socket.socket, count: int) -> None:
    with bare_accept(listener) as sock, sock.makefile("rb") as stream:
        for _ in range(count):
            ping = read_frame(stream)
            sock.sendall(page_frame(ping["data"]["seq"], "pong"))


def bare_pinger(port: int, count: int, report: Connection) -> None:
    round_trips: List[float] = []
    with bare_connect(port) as sock, sock.makefile("rb") as stream:
        for i in range(count):
            started = time.perf_counter()
            sock.sendall(page_frame(i, "ping"))
            read_frame(stream)
            round_trips.append(time.perf_counter() - started)
    report.send(("round_trips", round_trips))


class HandOver:
    """Frames read on a reader thread and handed to the main thread by an Event.

    The bare loop with the one extra step every SNR node has: the thread that
    reads the socket is not the thread that handles the data.
    """

    def __init__(self, stream: Any) -> None:
        self.frames: Deque[Dict[str, Any]] = collections.deque()
        self.ready = threading.Event()
        threading.Thread(target=self._read, args=(stream,), daemon=True).start()

    def _read(self, stream: Any) -> None:
        while True:
            try:
                frame = read_frame(stream)
            except (ValueError, OSError):  # end of stream
                return
            self.frames.append(frame)
            self.ready.set()

    def get(self) -> Dict[str, Any]:
        while True:
            if self.frames:
                return self.frames.popleft()
            self.ready.clear()
            if not self.frames:
                self.ready.wait()


def handover_echo(listener: socket.socket, count: int) -> None:
    with bare_accept(listener) as sock, sock.makefile("rb") as stream:
        inbox = HandOver(stream)
        for _ in range(count):
            ping = inbox.get()
            sock.sendall(page_frame(ping["data"]["seq"], "pong"))
        sock.shutdown(socket.SHUT_RDWR)  # ends the reader thread, which holds the stream


def handover_pinger(port: int, count: int, report: Connection) -> None:
    round_trips: List[float] = []
    with bare_connect(port) as sock, sock.makefile("rb") as stream:
        inbox = HandOver(stream)
        for i in range(count):
            started = time.perf_counter()
            sock.sendall(page_frame(i, "ping"))
            inbox.get()
            round_trips.append(time.perf_counter() - started)
        sock.shutdown(socket.SHUT_RDWR)
    report.send(("round_trips", round_trips))


# -- running a measurement in two fresh processes -------------------------------------
Target = Tuple[Callable[..., None], Tuple[Any, ...]]


def in_processes(make: Callable[[int, Connection], Tuple[Target, Target]], wanted: str) -> Any:
    """Run a receiver and a sender process; return their reports by kind."""
    ctx = multiprocessing.get_context("fork" if sys.platform == "linux" else "spawn")
    reader, writer = ctx.Pipe(duplex=False)
    (first, first_args), (second, second_args) = make(free_port(), writer)
    procs = [
        ctx.Process(target=first, args=first_args),
        ctx.Process(target=second, args=second_args),
    ]
    for proc in procs:
        proc.start()
    for arg in (*first_args, *second_args):
        if isinstance(arg, socket.socket):
            arg.close()  # the child has its own copy
    reports: Dict[str, Any] = {}
    try:
        while wanted not in reports:
            if not reader.poll(SAFETY_S):
                raise RuntimeError(f"no {wanted!r} report within {SAFETY_S} s")
            kind, value = reader.recv()
            reports[kind] = value
    finally:
        for proc in procs:
            proc.join(2.0)
            if proc.is_alive():
                proc.terminate()
                proc.join(2.0)
        reader.close()
        writer.close()
    return reports


def snr_throughput(count: int, mode: Mode) -> float:
    def make(port: int, report: Connection) -> Tuple[Target, Target]:
        pair = SocketsPair(server_tuple=("127.0.0.1", port))
        receiver = [pair.server(), CounterFactory(report, count)]
        sender = [pair.client(KEY), BlasterFactory(report, count)]
        return (run_node, ("receiver", receiver, mode)), (run_node, ("sender", sender, mode))

    reports = in_processes(make, "done")
    return count / float(reports["done"] - reports["start"])


def bare_throughput(count: int) -> float:
    def make(port: int, report: Connection) -> Tuple[Target, Target]:
        listener = bare_listen(port)  # listening before either process starts
        return (bare_receiver, (listener, count, report)), (bare_sender, (port, count, report))

    reports = in_processes(make, "done")
    return count / float(reports["done"] - reports["start"])


def snr_round_trips(count: int, mode: Mode) -> List[float]:
    def make(port: int, report: Connection) -> Tuple[Target, Target]:
        pair = SocketsPair(server_tuple=("127.0.0.1", port))
        server = [pair.server("pong"), PongerFactory()]
        client = [pair.client("ping"), PingerFactory(report, count)]
        return (run_node, ("ponger", server, mode)), (run_node, ("pinger", client, mode))

    trips: List[float] = in_processes(make, "round_trips")["round_trips"]
    return trips


def bare_round_trips(count: int) -> List[float]:
    def make(port: int, report: Connection) -> Tuple[Target, Target]:
        listener = bare_listen(port)
        return (bare_echo, (listener, count)), (bare_pinger, (port, count, report))

    trips: List[float] = in_processes(make, "round_trips")["round_trips"]
    return trips


def handover_round_trips(count: int) -> List[float]:
    def make(port: int, report: Connection) -> Tuple[Target, Target]:
        listener = bare_listen(port)
        return (handover_echo, (listener, count)), (handover_pinger, (port, count, report))

    trips: List[float] = in_processes(make, "round_trips")["round_trips"]
    return trips


def percentile(values: List[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def summarize_trips(runs: List[List[float]], warm_up: int) -> Tuple[float, float]:
    """Median over runs of each run's p50 and p99, in milliseconds."""
    p50 = statistics.median(percentile(r[warm_up:], 0.50) for r in runs)
    p99 = statistics.median(percentile(r[warm_up:], 0.99) for r in runs)
    return p50 * 1000, p99 * 1000


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pages", type=int, default=20000, help="pages one way (20000)")
    parser.add_argument("--round-trips", type=int, default=1000, help="ping-pongs (1000)")
    parser.add_argument("--repeat", type=int, default=5, help="fresh runs of each (5)")
    args = parser.parse_args(argv)
    pages, trips, repeat = args.pages, args.round_trips, args.repeat
    warm_up = min(100, trips // 10)

    # Interleaved, so a busy moment on the machine hits every variant alike.
    names = ["bare", "handover", "SNR DEPLOYED", "SNR DEBUG"]
    labels = {"bare": "bare TCP + json loop", "handover": "  + reader thread handoff"}
    modes = {"SNR DEPLOYED": Mode.DEPLOYED, "SNR DEBUG": Mode.DEBUG}
    rate_runs: Dict[str, List[float]] = {name: [] for name in names}
    trip_runs: Dict[str, List[List[float]]] = {name: [] for name in names}
    for _ in range(repeat):
        for name in names:
            if name == "bare":
                rate_runs[name].append(bare_throughput(pages))
                trip_runs[name].append(bare_round_trips(trips))
            elif name == "handover":
                trip_runs[name].append(handover_round_trips(trips))
            else:
                rate_runs[name].append(snr_throughput(pages, modes[name]))
                trip_runs[name].append(snr_round_trips(trips, modes[name]))
    rates = {name: statistics.median(runs) for name, runs in rate_runs.items() if runs}
    latency = {name: summarize_trips(runs, warm_up) for name, runs in trip_runs.items()}

    bare_rate, (bare_p50, bare_p99) = rates["bare"], latency["bare"]
    print(f"Comms between two processes on 127.0.0.1: {pages:,} pages one way, {trips:,} round")
    print(f"trips ({warm_up} warm-up not counted), median of {repeat} fresh runs each.\n")
    columns = [("pages/s", 10), ("ratio", 8), ("p50 ms", 10), ("ratio", 8), ("p99 ms", 10)]
    header = f"{'':26}" + "".join(f"{title:>{width}}" for title, width in columns) + f"{'ratio':>8}"
    print(header)
    print("-" * len(header))
    for name in names:
        p50, p99 = latency[name]
        rate = (
            f"{rates[name]:>10,.0f}{rates[name] / bare_rate:>8.2f}" if name in rates else " " * 18
        )
        print(
            f"{labels.get(name, name):26}{rate}"
            f"{p50:>10.3f}{p50 / bare_p50:>8.2f}{p99:>10.3f}{p99 / bare_p99:>8.2f}"
        )
    deployed_rate = rates["SNR DEPLOYED"] / bare_rate
    deployed_p50 = latency["SNR DEPLOYED"][0] / bare_p50
    print(
        f"\nTargets (SNR DEPLOYED): throughput >= 0.50 of bare: {deployed_rate:.2f} "
        f"({'met' if deployed_rate >= 0.5 else 'MISSED'}); p50 round trip <= 2.0x bare: "
        f"{deployed_p50:.2f}x ({'met' if deployed_p50 <= 2.0 else 'MISSED'})"
    )


if __name__ == "__main__":
    main()
