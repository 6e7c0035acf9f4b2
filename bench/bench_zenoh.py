"""SNR over Zenoh against raw Zenoh and SNR's own sockets, and fan-out / fan-in with CPU.

Needs the Zenoh extra (``pip install 'snr-robotics[zenoh]'``). Every process talks
over 127.0.0.1 with multicast scouting off and explicit endpoints (ports
chosen at run time). Side by side, in one run, interleaved round by round:

* **raw Zenoh**: a program with no framework that ``put``\\ s the same JSON
  bodies an SNR page sample holds (encoded per page, as SNR does) and a
  subscriber callback that decodes each one and checks its sequence number,
  with Zenoh's default settings and, for throughput, again with the batching
  time limit SNR sets (`BATCH_TIME_LIMIT_MS`): SNR against the engine as it
  comes, and against the engine set up as SNR sets it up;
* **SNR over Zenoh** (`ZenohCommsFactory`), as students build it (DEBUG, the
  default) and DEPLOYED;
* **SNR SocketsPair** (DEPLOYED), SNR's own TCP comms (bench_comms.py).

Throughput: ``--pages`` pages one way as fast as they can be stored, time from
the first store to the last page handled; every row with congestion control
BLOCK, so nothing may be lost (lost / duplicated / reordered are shown). The
row "SNR over Zenoh, drop" is the default (DROP): it shows what arrives when
the sender outruns the receiver, and the receiver's count of lost pages.
Round trip: ping then pong, p50 and p99. Fan-out: one publisher, 8
subscribers; fan-in: 8 publishers, one subscriber; pages/s and % of a core
used by each node process while the pages flow (all threads, from /proc).

Targets (issue 14): SNR over Zenoh >= 0.8x raw Zenoh throughput, p50 round
trip <= 1.2x raw Zenoh. Throughput is judged against both raw rows.

Run: ``python bench/bench_zenoh.py [--pages N] [--round-trips N] [--rounds N]``,
``--quick`` for a smoke run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import threading
import time
from importlib.metadata import version
from multiprocessing.connection import Connection
from typing import Any, Dict, List, Optional, Sequence, Tuple

import bench_comms as bc

from snr import (
    COMMS_CONNECTED,
    AbstractNode,
    Endpoint,
    EndpointFactory,
    Mode,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ZenohCommsFactory,
    tasks,
)
from snr.extras.zenoh.comms import BATCH_TIME_LIMIT_MS
from snr.prelude.install import install_hint

try:
    import zenoh
except ImportError:  # pragma: no cover - the extra is optional
    zenoh = None

SYSTEM = "bench"
FAN = 8
BATCHING_PATH = "transport/link/tx/queue/batching/time_limit"


def ep(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def raw_session(
    listen: Sequence[str] = (), connect: Sequence[str] = (), snr_batching: bool = False
) -> Any:
    config = zenoh.Config()
    if snr_batching:  # the one transport setting SNR changes from Zenoh's defaults
        config.insert_json5(BATCHING_PATH, str(BATCH_TIME_LIMIT_MS))
    config.insert_json5("mode", '"peer"')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/delay", "0")
    config.insert_json5("listen/endpoints", json.dumps(list(listen) or ["tcp/127.0.0.1:0"]))
    config.insert_json5("connect/endpoints", json.dumps(list(connect)))
    return zenoh.open(config)


def zenoh_comms(**kwargs: Any) -> ZenohCommsFactory:
    kwargs.setdefault("listen", ["tcp/127.0.0.1:0"])
    return ZenohCommsFactory(SYSTEM, scouting=False, **kwargs)


# -- raw Zenoh ---------------------------------------------------------------------
def raw_receiver(port: int, count: int, report: Connection, snr_batching: bool = False) -> None:
    check = bc.SeqCheck(count)
    done = threading.Event()

    def on_sample(sample: Any) -> None:
        check.note(bc.loads(sample.payload.to_bytes())["data"]["seq"])
        check.last_s = time.perf_counter()
        if check.unique == count:
            done.set()

    session = raw_session(listen=[ep(port)], snr_batching=snr_batching)
    sub = session.declare_subscriber(f"snr/{SYSTEM}/{bc.KEY}", on_sample)
    report.send(("ready", None))
    while not done.wait(0.25):
        if check.last_s and time.perf_counter() - check.last_s > bc.QUIET_S:
            break
    report.send(("done", (check.last_s, check.counts(), 0)))
    sub.undeclare()
    session.close()


def wait_matching(publisher: Any) -> None:
    """Wait for a subscriber, then 0.1 s more: samples put at once can still be lost."""
    deadline = time.monotonic() + 10
    while not publisher.matching_status and time.monotonic() < deadline:
        time.sleep(0.002)
    time.sleep(0.1)


def raw_sender(port: int, count: int, report: Connection, snr_batching: bool = False) -> None:
    session = raw_session(connect=[ep(port)], snr_batching=snr_batching)
    pub = session.declare_publisher(
        f"snr/{SYSTEM}/{bc.KEY}",
        encoding=zenoh.Encoding.APPLICATION_JSON,
        congestion_control=zenoh.CongestionControl.BLOCK,
    )
    wait_matching(pub)
    report.send(("start", time.perf_counter()))
    for i in range(count):
        pub.put(bc.body(i))
    time.sleep(0.5)  # let the last pages leave before the session closes
    session.close()


def raw_ponger(port: int, count: int) -> None:
    session = raw_session(listen=[ep(port)])
    pub = session.declare_publisher(f"snr/{SYSTEM}/pong")
    left = threading.Semaphore(0)

    def on_ping(sample: Any) -> None:
        ping = bc.loads(sample.payload.to_bytes())
        pub.put(bc.dumps({**ping, "key": "pong"}))
        left.release()

    sub = session.declare_subscriber(f"snr/{SYSTEM}/ping", on_ping)
    # Until the pinger has been quiet for 2 s: it may repeat its first ping.
    for _ in range(count * 2):
        if not left.acquire(timeout=2):
            break
    sub.undeclare()
    session.close()


def raw_pinger(port: int, count: int, report: Connection) -> None:
    session = raw_session(connect=[ep(port)])
    got = threading.Event()
    answer: List[Any] = []

    def on_pong(sample: Any) -> None:
        answer.append(bc.loads(sample.payload.to_bytes()))
        got.set()

    sub = session.declare_subscriber(f"snr/{SYSTEM}/pong", on_pong)
    pub = session.declare_publisher(f"snr/{SYSTEM}/ping")
    wait_matching(pub)  # the ponger's publisher meets our subscriber meanwhile
    for _ in range(50):  # until the ponger's publisher has met our subscriber
        got.clear()
        pub.put(bc.body(-1, "ping"))
        if got.wait(0.1):
            break
    time.sleep(0.1)
    answer.clear()
    trips: List[float] = []
    wrong = 0
    for i in range(count):
        got.clear()
        started = time.perf_counter()
        pub.put(bc.body(i, "ping"))
        if not got.wait(5):
            break
        trips.append(time.perf_counter() - started)
        wrong += answer.pop()["data"]["seq"] != i
    report.send(("round_trips", (trips, wrong)))
    sub.undeclare()
    session.close()


# -- SNR over Zenoh ----------------------------------------------------------------
def run_zenoh_receiver(
    port: int, count: int, report: Connection, mode: Optional[Mode], congestion: str
) -> None:
    progress = bc.Progress(report, count)
    factories = [
        zenoh_comms(subscribe=bc.KEY, listen=[ep(port)], congestion=congestion),
        bc.CounterFactory(progress),
        bc.QuietWatchFactory(progress),
    ]
    bc.run_node("receiver", factories, mode)


def rate_variants(count: int) -> Dict[str, Tuple[bc.Make, bool]]:
    def raw(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
        return (raw_receiver, (port, count, report)), (raw_sender, (port, count, report))

    def raw_snr_batching(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
        args = (port, count, report, True)
        return (raw_receiver, args), (raw_sender, args)

    def snr(mode: Optional[Mode], congestion: str) -> bc.Make:
        def make(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
            sender = [
                zenoh_comms(publish=bc.KEY, connect=[ep(port)], congestion=congestion),
                bc.BlasterFactory(report, count),
            ]
            return (run_zenoh_receiver, (port, count, report, mode, congestion)), (
                bc.run_node,
                ("sender", sender, mode),
            )

        return make

    def sockets(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
        pair = SocketsPair(server_tuple=("127.0.0.1", port))
        sender = [pair.client(bc.KEY), bc.BlasterFactory(report, count)]
        return (bc.run_receiving_node, (port, count, report, Mode.DEPLOYED)), (
            bc.run_node,
            ("sender", sender, Mode.DEPLOYED),
        )

    return {
        RAW: (raw, True),
        RAW_BATCHING: (raw_snr_batching, True),
        SNR_Z: (snr(None, "block"), False),
        SNR_Z_DEPLOYED: (snr(Mode.DEPLOYED, "block"), False),
        SNR_Z_DROP: (snr(None, "drop"), False),
        SOCKETS: (sockets, False),
    }


def trip_variants(count: int) -> Dict[str, Tuple[bc.Make, bool]]:
    def raw(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
        return (raw_ponger, (port, count)), (raw_pinger, (port, count, report))

    def snr(mode: Optional[Mode]) -> bc.Make:
        def make(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
            ponger = [
                zenoh_comms(publish="pong", subscribe="ping", listen=[ep(port)]),
                bc.PongerFactory(),
            ]
            pinger = [
                zenoh_comms(publish="ping", subscribe="pong", connect=[ep(port)]),
                bc.PingerFactory(report, count),
            ]
            return (bc.run_node, ("ponger", ponger, mode)), (bc.run_node, ("pinger", pinger, mode))

        return make

    def sockets(port: int, report: Connection) -> Tuple[bc.Target, bc.Target]:
        pair = SocketsPair(server_tuple=("127.0.0.1", port))
        server = [pair.server("pong"), bc.PongerFactory()]
        client = [pair.client("ping"), bc.PingerFactory(report, count)]
        return (bc.run_node, ("ponger", server, Mode.DEPLOYED)), (
            bc.run_node,
            ("pinger", client, Mode.DEPLOYED),
        )

    return {
        RAW: (raw, False),
        SNR_Z: (snr(None), False),
        SNR_Z_DEPLOYED: (snr(Mode.DEPLOYED), False),
        SOCKETS: (sockets, False),
    }


RAW, RAW_BATCHING, SNR_Z, SNR_Z_DEPLOYED, SNR_Z_DROP, SOCKETS = (
    "raw Zenoh put/subscribe",
    f"raw Zenoh, batching {BATCH_TIME_LIMIT_MS} ms",
    "SNR over Zenoh (DEBUG)",
    "SNR over Zenoh DEPLOYED",
    "SNR over Zenoh, drop (DEBUG)",
    "SNR SocketsPair DEPLOYED",
)


# -- fan-out and fan-in ------------------------------------------------------------
class FanBlaster(Endpoint):
    """Stores ``count`` pages under ``key`` (in chunks) once every role in ``wait_for`` joined."""

    def __init__(self, factory: FanBlasterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "fan_blaster")
        self.spec = factory
        self.joined: set[str] = set()
        self.next_seq = 0
        self.task_handlers = {
            (TaskType.event, COMMS_CONNECTED): self.on_joined,
            (TaskType.event, "blast"): self.blast,
        }

    def on_joined(self, task: Task, key: TaskId) -> SomeTasks:
        self.joined.add(task.val_list[1])
        if self.next_seq or not set(self.spec.wait_for) <= self.joined:
            return None
        self.spec.report.send(("start", time.perf_counter()))
        return self.blast(task, key)

    def blast(self, task: Task, key: TaskId) -> SomeTasks:
        end = min(self.next_seq + bc.BLAST_CHUNK, self.spec.count)
        batch = [
            self.store_data_task(self.spec.key, bc.small_data(i)) for i in range(self.next_seq, end)
        ]
        self.next_seq = end
        if end < self.spec.count:
            batch.append(tasks.event("blast"))
        return batch


class FanBlasterFactory(EndpointFactory):
    def __init__(self, report: Connection, key: str, count: int, wait_for: Sequence[str]) -> None:
        super().__init__()
        self.report, self.key, self.count, self.wait_for = report, key, count, list(wait_for)

    def get(self, parent: AbstractNode) -> FanBlaster:
        return FanBlaster(self, parent)


class Sink(Endpoint):
    """Counts pages under ``keys``; reports ``done`` once ``count`` arrived in all."""

    def __init__(self, factory: SinkFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sink")
        self.spec = factory
        self.got = 0
        self.task_handlers = {(TaskType.process_data, k): self.count for k in factory.keys}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        self.got += 1
        if self.got == self.spec.count:
            self.spec.report.send(("done", time.perf_counter()))
        return None


class SinkFactory(EndpointFactory):
    def __init__(self, report: Connection, keys: Sequence[str], count: int) -> None:
        super().__init__()
        self.report, self.keys, self.count = report, list(keys), count

    def get(self, parent: AbstractNode) -> Sink:
        return Sink(self, parent)


def measure_fan(count: int, fan_out: bool) -> Tuple[float, List[float], List[float]]:
    """Pages/s delivered in all, % of a core used by the hub and by each of the 8 others."""
    procs = bc.Processes()
    hub_port = bc.free_port()
    keys = [f"k{i}" for i in range(FAN)]
    others = [f"sub{i}" if fan_out else f"pub{i}" for i in range(FAN)]
    per_pub = count if fan_out else count // FAN
    try:
        if fan_out:
            hub = [
                zenoh_comms(publish=bc.KEY, listen=[ep(hub_port)], congestion="block"),
                FanBlasterFactory(procs.writer, bc.KEY, count, others),
            ]
            spokes = [
                [
                    zenoh_comms(subscribe=bc.KEY, connect=[ep(hub_port)]),
                    SinkFactory(procs.writer, [bc.KEY], count),
                ]
                for _ in others
            ]
        else:
            hub = [
                zenoh_comms(subscribe="*", listen=[ep(hub_port)]),
                SinkFactory(procs.writer, keys, per_pub * FAN),
            ]
            spokes = [
                [
                    zenoh_comms(publish=k, connect=[ep(hub_port)], congestion="block"),
                    FanBlasterFactory(procs.writer, k, per_pub, ["hub"]),
                ]
                for k in keys
            ]
        pids = [procs.start(bc.run_node, ("hub", hub, Mode.DEPLOYED))]
        for role, factories in zip(others, spokes):
            pids.append(procs.start(bc.run_node, (role, factories, Mode.DEPLOYED)))
        starts = procs.wait_for("start", 1 if fan_out else FAN)
        before = [bc.cpu_s(pid) or 0.0 for pid in pids]
        started = min(starts)
        ends = procs.wait_for("done", FAN if fan_out else 1)
        after = [bc.cpu_s(pid) or 0.0 for pid in pids]
        took = max(ends) - started
    finally:
        procs.close(stop=True)
    cpu = [100.0 * (b - a) / took for a, b in zip(before, after)]
    delivered = count * FAN if fan_out else per_pub * FAN
    return delivered / took, cpu[:1], cpu[1:]


# -- report ------------------------------------------------------------------------
def print_report(
    args: argparse.Namespace,
    rates: Dict[str, List[bc.RateRun]],
    trips: Dict[str, List[bc.TripRun]],
    fans: Dict[str, List[Tuple[float, List[float], List[float]]]],
    warm_up: int,
) -> None:
    print(
        f"Zenoh comms between processes on 127.0.0.1: {args.pages:,} pages one way, "
        f"{args.round_trips:,} round trips ({warm_up} warm-up not counted); {args.rounds} "
        "interleaved rounds, fresh processes each time; median of the rounds, ratios "
        "taken within each round."
    )
    print(f"eclipse-zenoh {version('eclipse-zenoh')}. JSON backend: {bc.BACKEND}; ", end="")
    print(bc.install_note())
    print()
    print(f"{'one-way throughput':32} {'pages/s':>10} {'spread':>17} {'x raw':>6}  lost dup reord")
    for name, runs in rates.items():
        per_s = [r[0] for r in runs]
        lost, dup, reord = (max(r[1][i] for r in runs) for i in range(3))
        ratio = statistics.median(a / b for a, b in zip(per_s, [r[0] for r in rates[RAW]]))
        print(
            f"{name:32} {statistics.median(per_s):>10,.0f} {bc.spread(per_s, ',.0f'):>17} "
            f"{ratio:>5.2f}x {lost:>5} {dup:>3} {reord:>5}"
        )
    print()
    print(f"{'round trip':32} {'p50 us':>10} {'p99 us':>10} {'x raw p50':>10}")
    p50s: Dict[str, List[float]] = {}
    for name, runs in trips.items():
        p50s[name] = [bc.percentile(t[warm_up:], 0.5) * 1e6 for t, _ in runs]
        p99 = statistics.median(bc.percentile(t[warm_up:], 0.99) * 1e6 for t, _ in runs)
        ratio = statistics.median(a / b for a, b in zip(p50s[name], p50s.get(RAW, p50s[name])))
        print(f"{name:32} {statistics.median(p50s[name]):>10.0f} {p99:>10.0f} {ratio:>9.2f}x")
    print()
    print(
        f"{'fan (SNR over Zenoh, DEPLOYED)':32} {'pages/s':>10} {'hub % core':>11} "
        f"{'others % core (min-max)':>24}"
    )
    for name, runs in fans.items():
        rate = statistics.median(r[0] for r in runs)
        hub = statistics.median(r[1][0] for r in runs)
        spokes = [c for r in runs for c in r[2]]
        print(f"{name:32} {rate:>10,.0f} {hub:>11.0f} {bc.spread(spokes, '.0f'):>24}")
    print()
    print("Targets:")
    for raw, label in ((RAW, "raw Zenoh"), (RAW_BATCHING, "raw, same batching")):
        for name, mode in ((SNR_Z, "DEBUG"), (SNR_Z_DEPLOYED, "DEPLOYED")):
            thr = [a[0] / b[0] for a, b in zip(rates[name], rates[raw])]
            what = f"throughput >= 0.8x {label}, {mode}"
            print(f"  {what:48} {bc.verdict(thr, lambda v: v >= 0.8)}")
    for name in (SNR_Z, SNR_Z_DEPLOYED):
        lat = [a / b for a, b in zip(p50s[name], p50s[RAW])]
        what = f"p50 round trip <= 1.2x raw, {name[15:]}"
        print(f"  {what:48} {bc.verdict(lat, lambda v: v <= 1.2)}")


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run")
    parser.add_argument("--pages", type=int, help="pages one way (50000; --quick 5000)")
    parser.add_argument("--round-trips", type=int, help="ping-pongs (2000; --quick 300)")
    parser.add_argument("--rounds", type=int, help="interleaved rounds (3; --quick 1)")
    args = parser.parse_args(argv)
    if zenoh is None:
        print(f"Zenoh is not installed: {install_hint('zenoh')}")
        sys.exit(0)
    defaults = (5000, 300, 1) if args.quick else (50_000, 2000, 3)
    for field, default in zip(("pages", "round_trips", "rounds"), defaults):
        if getattr(args, field) is None:
            setattr(args, field, default)
    warm_up = min(200, args.round_trips // 10)
    rate_cases, trip_cases = rate_variants(args.pages), trip_variants(args.round_trips)
    rates: Dict[str, List[bc.RateRun]] = {name: [] for name in rate_cases}
    trips: Dict[str, List[bc.TripRun]] = {name: [] for name in trip_cases}
    fan_names = {f"fan-out 1 -> {FAN}": True, f"fan-in {FAN} -> 1": False}
    fans: Dict[str, List[Tuple[float, List[float], List[float]]]] = {n: [] for n in fan_names}
    for _ in range(args.rounds):
        for name, (make, ready_first) in rate_cases.items():
            rates[name].append(bc.measure_rate(args.pages, make, ready_first))
        for name, (make, ready_first) in trip_cases.items():
            trips[name].append(bc.measure_trips(make, ready_first))
        for name, fan_out in fan_names.items():
            fans[name].append(measure_fan(args.pages // 4 if fan_out else args.pages, fan_out))
    print_report(args, rates, trips, fans, warm_up)


if __name__ == "__main__":
    main()
