"""Sockets comms between two node processes, against bare TCP loops and pyzmq.

Every measurement runs two fresh processes that talk over 127.0.0.1 (ports
chosen at run time): SNR nodes joined by a `SocketsPair`, and beside them, in
the same run on the same machine, programs that do the same job with no
framework:

* **bare TCP, one sendall a frame**: length-prefixed JSON frames (the same
  bytes an SNR page frame holds) over TCP with ``TCP_NODELAY``, one
  ``sendall`` per frame, a buffered reader at the other end;
* **bare TCP, batched sends**: the same frames joined into one buffer and
  handed to ``send`` as a batch, as much as the socket takes per call;
* **pyzmq PUSH/PULL** (one way, pipelined: a fair line for throughput) and
  **pyzmq REQ/REP** (strict request then reply: a fair line for round trips),
  carrying the same JSON bodies. pyzmq is a development dependency
  (``pip install pyzmq``); without it those rows are skipped.

JSON is written and read with the backend SNR's page codec uses (orjson when
it is installed, else the standard ``json``), in every row, so only the
messaging differs. SNR runs as students build it (``Config(factories)``: the
default DEBUG mode, every handler timed for the profiler) and in DEPLOYED mode.

What is measured:

* **one-way throughput**: the sender stores ``--pages`` small pages
  (``{"seq": i, "value": 0.5}``) as fast as it can, a thousand per handler
  call; the time runs from the first store to the moment the receiver has
  handled the last page. The receiver checks the sequence numbers and counts
  pages lost, duplicated and out of order (all must be 0: the link stays up).
* **round trip**: a ping goes to the other process, which answers with a pong
  holding the same data; p50 and p99 over ``--round-trips`` round trips after a
  warm-up. The row "+ reader thread hand-off" is the bare loop with the one
  step every SNR node has by design: a reader thread receives each frame and
  hands it to the thread that handles it.
* **idle CPU**: a connected pair of SNR nodes doing nothing for ``--idle-s``
  seconds, measured once start-up work has settled (``--settle-s``, 0.3 s);
  CPU time of both processes (all threads, from /proc) as % of a core.

All variants run once per round, interleaved, for ``--rounds`` rounds, so a busy
moment on the machine hits every variant alike. The table shows the median of
the per-round figures, their spread (min-max), and ratios taken within each
round (median over rounds).

Run: ``python bench/bench_comms.py [--pages N] [--round-trips N] [--rounds N]``,
``--quick`` for a smoke run of a few seconds (or ``nox -s bench``).
"""

from __future__ import annotations

import argparse
import collections
import json
import logging
import multiprocessing
import os
import queue
import socket
import statistics
import struct
import sys
import threading
import time
from multiprocessing.connection import Connection
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from snr import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    SocketsPair,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)
from snr.std_mods import codec

zmq: Any
try:
    import zmq
except ImportError:  # a development dependency: the pyzmq rows are skipped
    zmq = None

KEY = "bench"
SAFETY_S = 120.0  # a node or a report that takes longer than this is a failure
QUIET_S = 2.0  # a receiver that hears nothing for this long reports what it got
BLAST_CHUNK = 1000  # pages stored per handler call by the SNR sender
BATCH_BYTES = 256 * 1024  # the batched bare sender joins frames up to this size
READ_BUFFER = 256 * 1024  # buffered readers of the bare receivers
HEADER = struct.Struct(">I")

# JSON as SNR's page codec does it: the same backend for every row.
BACKEND = codec.backend()
if BACKEND == "orjson":
    import orjson

    dumps: Callable[[Any], bytes] = orjson.dumps
    loads: Callable[[bytes], Any] = orjson.loads
else:

    def dumps(obj: Any) -> bytes:
        return json.dumps(obj, separators=(",", ":")).encode("utf-8")

    loads = json.loads


def install_note() -> str:
    """Which installs the backend of this run stands for, and how to run the other."""
    if BACKEND == "orjson":
        return (
            "orjson is what the [fast] and [dev] extras give. A student's plain install "
            "uses the standard library's json: SNR_JSON=json runs that."
        )
    return "the standard library's json is what a student's plain install uses."


def small_data(i: int) -> Dict[str, Any]:
    return {"seq": i, "value": 0.5}


def body(i: int, key: str = KEY) -> bytes:
    """The JSON body of an SNR page frame, field for field."""
    return dumps(
        {
            "v": 1,
            "kind": "page",
            "key": key,
            "data": small_data(i),
            "origin": "bare",
            "created_at_s": time.time(),
            "process": True,
        }
    )


def frame(i: int, key: str = KEY) -> bytes:
    data = body(i, key)
    return HEADER.pack(len(data)) + data


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class SeqCheck:
    """Counts pages lost, duplicated and out of order from their sequence numbers."""

    def __init__(self, count: int) -> None:
        self.seen = bytearray(count)
        self.unique = 0
        self.duplicated = 0
        self.reordered = 0
        self.top = -1
        self.last_s = 0.0

    def note(self, seq: int) -> None:
        if not 0 <= seq < len(self.seen) or self.seen[seq]:
            self.duplicated += 1
            return
        self.seen[seq] = 1
        self.unique += 1
        if seq < self.top:
            self.reordered += 1
        else:
            self.top = seq

    def counts(self) -> Tuple[int, int, int]:
        """(lost, duplicated, out of order)."""
        return len(self.seen) - self.unique, self.duplicated, self.reordered


# -- SNR components --------------------------------------------------------------
def stop_when_peer_leaves(task: Task, key: TaskId) -> SomeTasks:
    return tasks.terminate("the other node has finished")


class Blaster(Endpoint):
    """Stores ``count`` pages, a chunk per handler call, once the link opens."""

    def __init__(self, factory: BlasterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "blaster")
        self.spec = factory
        self.next_seq = 0
        self.task_handlers = {
            (TaskType.event, COMMS_CONNECTED): self.start,
            (TaskType.event, "blast"): self.blast,
            (TaskType.event, COMMS_DISCONNECTED): stop_when_peer_leaves,
        }

    def start(self, task: Task, key: TaskId) -> SomeTasks:
        self.spec.report.send(("start", time.perf_counter()))
        return self.blast(task, key)

    def blast(self, task: Task, key: TaskId) -> SomeTasks:
        end = min(self.next_seq + BLAST_CHUNK, self.spec.count)
        batch = [self.store_data_task(KEY, small_data(i)) for i in range(self.next_seq, end)]
        self.next_seq = end
        if end < self.spec.count:
            batch.append(tasks.event("blast"))  # queued after this chunk's pages
        return batch


class BlasterFactory(EndpointFactory):
    def __init__(self, report: Connection, count: int) -> None:
        super().__init__()
        self.report, self.count = report, count

    def get(self, parent: AbstractNode) -> Blaster:
        return Blaster(self, parent)


class Progress:
    """What the receiving node has seen; shared by its counter and its quiet watch."""

    def __init__(self, report: Connection, count: int) -> None:
        self.report = report
        self.check = SeqCheck(count)
        self.link_drops = 0
        self.reported = False
        self.lock = threading.Lock()

    def send_report(self) -> None:
        with self.lock:
            if self.reported:
                return
            self.reported = True
        self.report.send(("done", (self.check.last_s, self.check.counts(), self.link_drops)))


class Counter(Endpoint):
    """Checks every page's sequence number; reports when all have arrived."""

    def __init__(self, factory: CounterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counter")
        self.progress = factory.progress
        self.task_handlers = {
            (TaskType.process_data, KEY): self.count,
            (TaskType.event, COMMS_DISCONNECTED): self.link_lost,
        }

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        check = self.progress.check
        check.note(task.val_list[0].data["seq"])
        check.last_s = time.perf_counter()
        if check.unique == len(check.seen):
            self.progress.send_report()
            return tasks.terminate("all pages arrived")
        return None

    def link_lost(self, task: Task, key: TaskId) -> SomeTasks:
        self.progress.link_drops += 1
        return None


class CounterFactory(EndpointFactory):
    def __init__(self, progress: Progress) -> None:
        super().__init__()
        self.progress = progress

    def get(self, parent: AbstractNode) -> Counter:
        return Counter(self, parent)


class QuietWatch(ThreadLoop):
    """Reports what arrived and stops the node once pages stop coming (some were lost)."""

    def __init__(self, factory: QuietWatchFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "quiet_watch")
        self.progress = factory.progress

    def loop(self) -> None:
        if self.wait_s(0.25):
            return
        last_s = self.progress.check.last_s
        if last_s and time.perf_counter() - last_s > QUIET_S:
            self.progress.send_report()
            self.schedule(tasks.terminate("no more pages"))
            self.set_terminate_flag("no more pages")


class QuietWatchFactory(LoopFactory):
    def __init__(self, progress: Progress) -> None:
        super().__init__()
        self.progress = progress

    def get(self, parent: AbstractNode) -> QuietWatch:
        return QuietWatch(self, parent)


class Pinger(Endpoint):
    """Sends a ping, times the pong, sends the next; reports every round trip."""

    def __init__(self, factory: PingerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pinger")
        self.spec = factory
        self.sent_at = 0.0
        self.wrong = 0
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
        if task.val_list[0].data["seq"] != len(self.round_trips) - 1:
            self.wrong += 1
        if len(self.round_trips) < self.spec.count:
            return self.ping()
        self.spec.report.send(("round_trips", (self.round_trips, self.wrong)))
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


def thread_names() -> Dict[int, str]:
    """Native thread id -> Python thread name, for this process."""
    return {t.native_id: t.name for t in threading.enumerate() if t.native_id is not None}


class Announcer(Endpoint):
    """Tells the bench when the link is up (the idle measurement starts then).

    It reports the process id and the names of its threads, which
    bench_idle.py reads CPU time by.
    """

    def __init__(self, factory: AnnouncerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "announcer")
        self.report = factory.report
        self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.connected}

    def connected(self, task: Task, key: TaskId) -> SomeTasks:
        self.report.send(("connected", (os.getpid(), thread_names())))
        return None


class AnnouncerFactory(EndpointFactory):
    def __init__(self, report: Connection) -> None:
        super().__init__()
        self.report = report

    def get(self, parent: AbstractNode) -> Announcer:
        return Announcer(self, parent)


def run_node(role: str, factories: List[Any], mode: Optional[Mode]) -> None:
    """One SNR node; ``mode`` None is what ``Config(factories)`` gives (DEBUG)."""
    logging.disable(logging.WARNING)  # keep the table readable (peers leaving is normal here)
    factories = [*factories, TimeoutLoopFactory(seconds=SAFETY_S)]
    config = Config({role: factories}) if mode is None else Config({role: factories}, mode=mode)
    SynchronousRunner(role, config).run()


def run_receiving_node(port: int, count: int, report: Connection, mode: Optional[Mode]) -> None:
    progress = Progress(report, count)  # made in the node's process, shared by two components
    pair = SocketsPair(server_tuple=("127.0.0.1", port))
    factories = [pair.server(), CounterFactory(progress), QuietWatchFactory(progress)]
    run_node("receiver", factories, mode)


# -- the bare loops ----------------------------------------------------------------
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


def read_body(stream: Any) -> bytes:
    data: bytes = stream.read(HEADER.unpack(stream.read(4))[0])
    return data


def bare_receiver(listener: socket.socket, count: int, report: Connection) -> None:
    check = SeqCheck(count)
    with bare_accept(listener) as sock, sock.makefile("rb", buffering=READ_BUFFER) as stream:
        for _ in range(count):
            check.note(loads(read_body(stream))["data"]["seq"])
        report.send(("done", (time.perf_counter(), check.counts(), 0)))


def bare_sender(port: int, count: int, report: Connection) -> None:
    with bare_connect(port) as sock:
        report.send(("start", time.perf_counter()))
        for i in range(count):
            sock.sendall(frame(i))
        sock.shutdown(socket.SHUT_WR)
        sock.recv(1)  # wait for the receiver to finish and close


def batched_sender(port: int, count: int, report: Connection) -> None:
    """Joins frames into one buffer and sends as much of it as the socket takes."""
    with bare_connect(port) as sock:
        report.send(("start", time.perf_counter()))
        pending = bytearray()
        i = 0
        while i < count or pending:
            while i < count and len(pending) < BATCH_BYTES:
                pending += frame(i)
                i += 1
            del pending[: sock.send(pending)]
        sock.shutdown(socket.SHUT_WR)
        sock.recv(1)


def bare_echo(listener: socket.socket, count: int) -> None:
    with bare_accept(listener) as sock, sock.makefile("rb", buffering=READ_BUFFER) as stream:
        for _ in range(count):
            ping = loads(read_body(stream))
            sock.sendall(frame(ping["data"]["seq"], "pong"))


def bare_pinger(port: int, count: int, report: Connection) -> None:
    round_trips: List[float] = []
    wrong = 0
    with bare_connect(port) as sock, sock.makefile("rb", buffering=READ_BUFFER) as stream:
        for i in range(count):
            started = time.perf_counter()
            sock.sendall(frame(i, "ping"))
            pong = loads(read_body(stream))
            round_trips.append(time.perf_counter() - started)
            wrong += pong["data"]["seq"] != i
    report.send(("round_trips", (round_trips, wrong)))


class HandOver:
    """Frames read on a reader thread and handed to the main thread by a SimpleQueue.

    The bare loop with the one extra step every SNR node has: the thread that
    reads the socket is not the thread that handles the data.
    """

    def __init__(self, stream: Any) -> None:
        self.inbox: queue.SimpleQueue[Dict[str, Any]] = queue.SimpleQueue()
        threading.Thread(target=self._read, args=(stream,), daemon=True).start()

    def _read(self, stream: Any) -> None:
        while True:
            try:
                obj = loads(read_body(stream))
            except (ValueError, OSError, struct.error):  # end of stream
                return
            self.inbox.put(obj)

    def get(self) -> Dict[str, Any]:
        return self.inbox.get()


def handover_echo(listener: socket.socket, count: int) -> None:
    with bare_accept(listener) as sock, sock.makefile("rb", buffering=READ_BUFFER) as stream:
        inbox = HandOver(stream)
        for _ in range(count):
            ping = inbox.get()
            sock.sendall(frame(ping["data"]["seq"], "pong"))
        sock.shutdown(socket.SHUT_RDWR)  # ends the reader thread, which holds the stream


def handover_pinger(port: int, count: int, report: Connection) -> None:
    round_trips: List[float] = []
    wrong = 0
    with bare_connect(port) as sock, sock.makefile("rb", buffering=READ_BUFFER) as stream:
        inbox = HandOver(stream)
        for i in range(count):
            started = time.perf_counter()
            sock.sendall(frame(i, "ping"))
            pong = inbox.get()
            round_trips.append(time.perf_counter() - started)
            wrong += pong["data"]["seq"] != i
        sock.shutdown(socket.SHUT_RDWR)
    report.send(("round_trips", (round_trips, wrong)))


# -- pyzmq -------------------------------------------------------------------------
def zmq_puller(port: int, count: int, report: Connection) -> None:
    context = zmq.Context()
    sock = context.socket(zmq.PULL)
    sock.bind(f"tcp://127.0.0.1:{port}")
    report.send(("ready", None))
    check = SeqCheck(count)
    for _ in range(count):
        check.note(loads(sock.recv())["data"]["seq"])
    report.send(("done", (time.perf_counter(), check.counts(), 0)))
    sock.close(linger=0)
    context.term()


def zmq_pusher(port: int, count: int, report: Connection) -> None:
    context = zmq.Context()
    sock = context.socket(zmq.PUSH)
    sock.connect(f"tcp://127.0.0.1:{port}")
    report.send(("start", time.perf_counter()))
    for i in range(count):
        sock.send(body(i))
    sock.close()  # waits until every message has gone (the default linger)
    context.term()


def zmq_replier(port: int, count: int, report: Connection) -> None:
    context = zmq.Context()
    sock = context.socket(zmq.REP)
    sock.bind(f"tcp://127.0.0.1:{port}")
    report.send(("ready", None))
    for _ in range(count):
        ping = loads(sock.recv())
        sock.send(body(ping["data"]["seq"], "pong"))
    sock.close()
    context.term()


def zmq_requester(port: int, count: int, report: Connection) -> None:
    context = zmq.Context()
    sock = context.socket(zmq.REQ)
    sock.connect(f"tcp://127.0.0.1:{port}")
    round_trips: List[float] = []
    wrong = 0
    for i in range(count):
        started = time.perf_counter()
        sock.send(body(i, "ping"))
        pong = loads(sock.recv())
        round_trips.append(time.perf_counter() - started)
        wrong += pong["data"]["seq"] != i
    sock.close(linger=0)
    context.term()
    report.send(("round_trips", (round_trips, wrong)))


# -- running a measurement in two fresh processes -------------------------------------
Target = Tuple[Callable[..., None], Tuple[Any, ...]]
CTX: Any = multiprocessing.get_context("fork" if sys.platform == "linux" else "spawn")


class Processes:
    """Child processes with one pipe on which they report ``(kind, value)``."""

    def __init__(self) -> None:
        self.reader, self.writer = CTX.Pipe(duplex=False)
        self.procs: List[Any] = []
        self.reports: Dict[str, List[Any]] = collections.defaultdict(list)

    def start(self, target: Callable[..., None], args: Tuple[Any, ...]) -> int:
        proc = CTX.Process(target=target, args=args)
        proc.start()
        self.procs.append(proc)
        for arg in args:
            if isinstance(arg, socket.socket):
                arg.close()  # the child has its own copy
        pid: int = proc.pid
        return pid

    def wait_for(self, kind: str, n: int = 1) -> List[Any]:
        deadline = time.monotonic() + SAFETY_S
        while len(self.reports[kind]) < n:
            if not self.reader.poll(max(0.0, deadline - time.monotonic())):
                raise RuntimeError(f"no {kind!r} report within {SAFETY_S} s")
            got, value = self.reader.recv()
            self.reports[got].append(value)
        return self.reports[kind]

    def close(self, stop: bool = False) -> None:
        for proc in self.procs:
            if stop:
                proc.terminate()
            proc.join(3.0)
            if proc.is_alive():
                proc.terminate()
                proc.join(2.0)
        self.reader.close()
        self.writer.close()


Make = Callable[[int, Connection], Tuple[Target, Target]]
Integrity = Tuple[int, int, int]  # pages lost, duplicated, out of order
RateRun = Tuple[float, Integrity, int]  # pages/s, integrity, link drops
TripRun = Tuple[List[float], int]  # round trips in s, wrong answers


def measure_rate(count: int, make: Make, ready_first: bool) -> RateRun:
    """Runs a receiver, then a sender; pages/s from the first store to the last page handled."""
    procs = Processes()
    try:
        receiver, sender = make(free_port(), procs.writer)
        procs.start(*receiver)
        if ready_first:
            procs.wait_for("ready")
        procs.start(*sender)
        start = procs.wait_for("start")[0]
        end, integrity, drops = procs.wait_for("done")[0]
    finally:
        procs.close()
    arrived = count - integrity[0]
    return arrived / float(end - start), integrity, drops


def measure_trips(make: Make, ready_first: bool) -> TripRun:
    """Runs an answerer, then a pinger; its round trips and how many pongs were wrong."""
    procs = Processes()
    try:
        answerer, pinger = make(free_port(), procs.writer)
        procs.start(*answerer)
        if ready_first:
            procs.wait_for("ready")
        procs.start(*pinger)
        trips, wrong = procs.wait_for("round_trips")[0]
    finally:
        procs.close()
    return trips, int(wrong)


def cpu_s(pid: int) -> Optional[float]:
    """CPU time used so far by every thread of process ``pid`` (Linux /proc), or None."""
    total_ns = 0
    try:
        threads = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return None
    for tid in threads:
        try:
            with open(f"/proc/{pid}/task/{tid}/schedstat") as stat:
                total_ns += int(stat.read().split()[0])
        except FileNotFoundError:
            continue  # the thread ended meanwhile
        except (OSError, ValueError, IndexError):
            return _cpu_s_from_ticks(pid)
    return total_ns / 1e9


def _cpu_s_from_ticks(pid: int) -> Optional[float]:
    """User + system time from /proc/<pid>/stat (clock ticks: coarser)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure_idle(
    mode: Optional[Mode], seconds: float, settle_s: float = 0.3
) -> Optional[Tuple[float, float]]:
    """% of a core used by a connected, idle server node and client node; None without /proc."""
    procs = Processes()
    try:
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        pids = [
            procs.start(
                run_node, ("server", [pair.server(), AnnouncerFactory(procs.writer)], mode)
            ),
            procs.start(
                run_node, ("client", [pair.client(), AnnouncerFactory(procs.writer)], mode)
            ),
        ]
        procs.wait_for("connected", n=2)
        time.sleep(settle_s)  # let start-up work (imports, hellos, first beats) settle
        before = [cpu_s(pid) for pid in pids]
        started = time.perf_counter()
        time.sleep(seconds)
        after = [cpu_s(pid) for pid in pids]
        elapsed = time.perf_counter() - started
    finally:
        procs.close(stop=True)
    if None in before or None in after:
        return None
    server, client = (100.0 * (b - a) / elapsed for a, b in zip(before, after))  # type: ignore[operator]
    return server, client


# -- the variants ------------------------------------------------------------------
BARE, BATCHED, HANDOVER, PUSH_PULL, REQ_REP = (
    "bare TCP, one sendall a frame",
    "bare TCP, batched sends",
    "  + reader thread hand-off",
    "pyzmq PUSH/PULL",
    "pyzmq REQ/REP",
)
SNR_MODES: Dict[str, Optional[Mode]] = {
    "SNR default (DEBUG)": None,
    "SNR DEPLOYED": Mode.DEPLOYED,
}


def rate_variants(count: int) -> Dict[str, Tuple[Make, bool]]:
    """Name -> (how to build the receiver and the sender, receiver reports ready first)."""

    def bare_with(sender: Callable[..., None]) -> Make:
        def make(port: int, report: Connection) -> Tuple[Target, Target]:
            listener = bare_listen(port)  # listening before either process starts
            return (bare_receiver, (listener, count, report)), (sender, (port, count, report))

        return make

    def pushpull(port: int, report: Connection) -> Tuple[Target, Target]:
        return (zmq_puller, (port, count, report)), (zmq_pusher, (port, count, report))

    def snr(mode: Optional[Mode]) -> Make:
        def make(port: int, report: Connection) -> Tuple[Target, Target]:
            pair = SocketsPair(server_tuple=("127.0.0.1", port))
            sender = [pair.client(KEY), BlasterFactory(report, count)]
            return (run_receiving_node, (port, count, report, mode)), (
                run_node,
                ("sender", sender, mode),
            )

        return make

    variants = {BARE: (bare_with(bare_sender), False), BATCHED: (bare_with(batched_sender), False)}
    if zmq is not None:
        variants[PUSH_PULL] = (pushpull, True)
    for name, mode in SNR_MODES.items():
        variants[name] = (snr(mode), False)
    return variants


def trip_variants(count: int) -> Dict[str, Tuple[Make, bool]]:
    def bare_with(echo: Callable[..., None], pinger: Callable[..., None]) -> Make:
        def make(port: int, report: Connection) -> Tuple[Target, Target]:
            listener = bare_listen(port)
            return (echo, (listener, count)), (pinger, (port, count, report))

        return make

    def reqrep(port: int, report: Connection) -> Tuple[Target, Target]:
        return (zmq_replier, (port, count, report)), (zmq_requester, (port, count, report))

    def snr(mode: Optional[Mode]) -> Make:
        def make(port: int, report: Connection) -> Tuple[Target, Target]:
            pair = SocketsPair(server_tuple=("127.0.0.1", port))
            server = [pair.server("pong"), PongerFactory()]
            client = [pair.client("ping"), PingerFactory(report, count)]
            return (run_node, ("ponger", server, mode)), (run_node, ("pinger", client, mode))

        return make

    variants = {
        BARE: (bare_with(bare_echo, bare_pinger), False),
        HANDOVER: (bare_with(handover_echo, handover_pinger), False),
    }
    if zmq is not None:
        variants[REQ_REP] = (reqrep, True)
    for name, mode in SNR_MODES.items():
        variants[name] = (snr(mode), False)
    return variants


# -- summing up --------------------------------------------------------------------
def percentile(values: Sequence[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def spread(values: Sequence[float], fmt: str) -> str:
    return f"{min(values):{fmt}}-{max(values):{fmt}}"


def ratios(runs: Dict[str, List[float]], name: str, base: str) -> List[float]:
    """``name``'s figure over ``base``'s, round by round."""
    return [a / b for a, b in zip(runs[name], runs[base])]


def verdict(values: List[float], ok: Callable[[float], bool], fmt: str = ".2f") -> str:
    """Median of the per-round values, met/MISSED on it, and in how many rounds it held."""
    median = statistics.median(values)
    held = sum(1 for value in values if ok(value))
    word = "met" if ok(median) else "MISSED"
    return f"{median:{fmt}}x {word} ({held}/{len(values)} rounds)"


def print_report(
    args: argparse.Namespace,
    rates: Dict[str, List[RateRun]],
    trips: Dict[str, List[TripRun]],
    idle: Dict[str, List[Tuple[float, float]]],
    warm_up: int,
) -> None:
    rounds = args.rounds
    print(
        f"Comms between two processes on 127.0.0.1: {args.pages:,} pages one way, "
        f"{args.round_trips:,} round trips ({warm_up} warm-up not counted), idle pair "
        f"{args.idle_s:g} s; {rounds} interleaved rounds, fresh processes each time; "
        f"median of the rounds, spread = min-max over rounds, ratios taken within each round."
    )
    print(f"JSON backend: {BACKEND} (SNR's page codec and every baseline); {install_note()}")
    if zmq is None:
        print("pyzmq is not installed (pip install pyzmq): the pyzmq rows and targets are skipped.")
    else:
        print(f"pyzmq {zmq.pyzmq_version()} (libzmq {zmq.zmq_version()}).")

    rate = {name: [run[0] for run in runs] for name, runs in rates.items()}
    header = (
        f"\n{'one-way throughput':30}{'pages/s':>9}{'spread':>17}{'x bare':>8}"
        f"{'x PUSH/PULL':>13}{'lost':>6}{'dup':>5}{'order':>7}{'drops':>7}"
    )
    print(header)
    print("-" * (len(header) - 1))
    for name, runs in rates.items():
        vs_pp = (
            f"{statistics.median(ratios(rate, name, PUSH_PULL)):>13.2f}"
            if PUSH_PULL in rate
            else f"{'-':>13}"
        )
        lost, dup, order = (sum(run[1][i] for run in runs) for i in range(3))
        print(
            f"{name:30}{statistics.median(rate[name]):>9,.0f}{spread(rate[name], ',.0f'):>17}"
            f"{statistics.median(ratios(rate, name, BARE)):>8.2f}{vs_pp}"
            f"{lost:>6}{dup:>5}{order:>7}{sum(run[2] for run in runs):>7}"
        )
    print("(lost, dup, order: pages lost, duplicated, out of order, summed over the rounds;")
    print(" drops: times the receiving node saw its link go down)")

    p50 = {
        name: [percentile(run[0][warm_up:], 0.5) * 1e6 for run in runs]
        for name, runs in trips.items()
    }
    p99 = {
        name: [percentile(run[0][warm_up:], 0.99) * 1e6 for run in runs]
        for name, runs in trips.items()
    }
    header = (
        f"\n{'round trip':30}{'p50 us':>9}{'spread':>17}{'x bare':>8}{'x REQ/REP':>13}"
        f"{'p99 us':>9}{'x bare':>8}{'wrong':>7}"
    )
    print(header)
    print("-" * (len(header) - 1))
    for name, trip_runs in trips.items():
        vs_rr = (
            f"{statistics.median(ratios(p50, name, REQ_REP)):>13.2f}"
            if REQ_REP in p50
            else f"{'-':>13}"
        )
        print(
            f"{name:30}{statistics.median(p50[name]):>9.0f}{spread(p50[name], '.0f'):>17}"
            f"{statistics.median(ratios(p50, name, BARE)):>8.2f}{vs_rr}"
            f"{statistics.median(p99[name]):>9.0f}"
            f"{statistics.median(ratios(p99, name, BARE)):>8.2f}"
            f"{sum(run[1] for run in trip_runs):>7}"
        )
    print("(wrong: pongs that did not answer the ping just sent, summed over the rounds)")

    pair_cpu: Dict[str, List[float]] = {}
    header = f"\n{'idle connected pair':30}{'% core':>9}{'spread':>17}{'server':>8}{'client':>8}"
    print(header)
    print("-" * (len(header) - 1))
    for name, idle_runs in idle.items():
        if not idle_runs:
            print(f"{name:30}{'n/a (no /proc to read CPU time from)':>42}")
            continue
        pair_cpu[name] = [server + client for server, client in idle_runs]
        print(
            f"{name:30}{statistics.median(pair_cpu[name]):>9.3f}{spread(pair_cpu[name], '.3f'):>17}"
            f"{statistics.median(run[0] for run in idle_runs):>8.3f}"
            f"{statistics.median(run[1] for run in idle_runs):>8.3f}"
        )
    print("(% of one core, both node processes together, all their threads)")

    print("\nTargets (median of the per-round ratios; rounds where it held):")
    for name in SNR_MODES:
        print(f"  {name}:")
        lines = [
            (
                "throughput >= 0.50x bare, one sendall a frame",
                verdict(ratios(rate, name, BARE), lambda r: r >= 0.5),
            )
        ]
        if PUSH_PULL in rate:
            to_pp = ratios(rate, name, PUSH_PULL)
            lines.append(
                ("throughput >= 0.75x pyzmq PUSH/PULL", verdict(to_pp, lambda r: r >= 0.75))
            )
            lines.append(
                ("  moonshot: >= 1.00x pyzmq PUSH/PULL", verdict(to_pp, lambda r: r >= 1.0))
            )
        lines.append(
            ("p50 round trip <= 1.3x bare", verdict(ratios(p50, name, BARE), lambda r: r <= 1.3))
        )
        lines.append(  # the hand-off row pays the one thread hop every node has by design
            (
                "p50 round trip <= 1.25x reader thread hand-off",
                verdict(ratios(p50, name, HANDOVER), lambda r: r <= 1.25),
            )
        )
        if REQ_REP in p50:
            lines.append(
                (
                    "p50 round trip <= pyzmq REQ/REP",
                    verdict(ratios(p50, name, REQ_REP), lambda r: r <= 1.0),
                )
            )
        lost, dup, order = (sum(run[1][i] for run in rates[name]) for i in range(3))
        wrong = sum(run[1] for run in trips[name])
        clean = lost == dup == order == wrong == 0
        lines.append(
            (
                "0 pages lost / duplicated / reordered",
                f"{lost} / {dup} / {order} ({wrong} wrong pongs) {'met' if clean else 'MISSED'}",
            )
        )
        if name in pair_cpu:
            cpu = pair_cpu[name]
            held = sum(1 for value in cpu if value < 1.0)
            word = "met" if statistics.median(cpu) < 1.0 else "MISSED"
            lines.append(
                (
                    "idle pair < 1% of a core",
                    f"{statistics.median(cpu):.3f}% {word} ({held}/{len(cpu)} rounds)",
                )
            )
        else:
            lines.append(("idle pair < 1% of a core", "n/a (no /proc)"))
        for target, result in lines:
            print(f"    {target:48}{result}")


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run of a few seconds")
    parser.add_argument("--pages", type=int, help="pages one way (200000; --quick 10000)")
    parser.add_argument("--round-trips", type=int, help="ping-pongs (5000; --quick 500)")
    parser.add_argument("--rounds", type=int, help="interleaved rounds (5; --quick 2)")
    parser.add_argument(
        "--idle-s", type=float, help="seconds the idle pair is measured (3; --quick 0.5)"
    )
    parser.add_argument(
        "--settle-s",
        type=float,
        default=0.3,
        help="seconds the idle pair runs before it is measured (0.3)",
    )
    args = parser.parse_args(argv)
    defaults = (10_000, 500, 2, 0.5) if args.quick else (200_000, 5000, 5, 3.0)
    for field, default in zip(("pages", "round_trips", "rounds", "idle_s"), defaults):
        if getattr(args, field) is None:
            setattr(args, field, default)
    warm_up = min(200, args.round_trips // 10)

    rate_cases = rate_variants(args.pages)
    trip_cases = trip_variants(args.round_trips)
    rates: Dict[str, List[RateRun]] = {name: [] for name in rate_cases}
    trips: Dict[str, List[TripRun]] = {name: [] for name in trip_cases}
    idle: Dict[str, List[Tuple[float, float]]] = {name: [] for name in SNR_MODES}
    for _ in range(args.rounds):
        # Interleaved, so a busy moment on the machine hits every variant alike.
        for name, (make, ready_first) in rate_cases.items():
            rates[name].append(measure_rate(args.pages, make, ready_first))
        for name, (make, ready_first) in trip_cases.items():
            trips[name].append(measure_trips(make, ready_first))
        for name, mode in SNR_MODES.items():
            cpu = measure_idle(mode, args.idle_s, args.settle_s)
            if cpu is not None:
                idle[name].append(cpu)
    print_report(args, rates, trips, idle, warm_up)


if __name__ == "__main__":
    main()
