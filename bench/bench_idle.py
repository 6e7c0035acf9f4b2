"""What an idle, connected pair of nodes costs, thread by thread.

Two fresh processes on 127.0.0.1 (ports chosen at run time): a server node and
a client node joined by a `SocketsPair`, doing nothing once the link is up. After
``--settle-s`` seconds the bench reads the CPU time of every thread of both
processes from ``/proc/<pid>/task/<tid>/schedstat`` (first field, ns), waits
``--idle-s`` seconds and reads it again: each thread's share of one core, and
the pair's total. SNR runs as students build it (``Config(factories)``: the
default DEBUG mode, with its watchdog) and in DEPLOYED mode.

The baseline, measured in the same run, interleaved: the least a link that
finds a dead peer within 5 s must do, with no framework. Each process has one
thread that sleeps in ``select`` until its next beat is due, sends a 4-byte
frame every second, reads the peer's, and would call the peer dead after 4 s of
silence. With pyzmq installed, a pyzmq PAIR pair with ZMTP heartbeats (1 s,
dead after 4 s) and a thread blocked in ``recv`` is measured too.

CPU time is fairly robust to a busy machine, but not wholly: the table shows
the median over ``--rounds`` rounds (fresh processes each round) and the spread.

Run: ``python bench/bench_idle.py [--rounds N] [--idle-s S]``, ``--quick`` for a
smoke run of a few seconds. Linux only (it reads /proc).
"""

from __future__ import annotations

import argparse
import os
import re
import select
import socket
import statistics
import time
from multiprocessing.connection import Connection
from typing import Any, Callable, Dict, List, Optional, Tuple

from bench_comms import (
    SAFETY_S,
    AnnouncerFactory,
    Processes,
    free_port,
    run_node,
    thread_names,
    zmq,
)

from snr import (
    Mode,
    SocketsPair,
)

BEAT_S = 1.0  # the baselines' beat, as SNR's default (a quarter of 4 s, at most 1 s)
DEAD_AFTER_S = 4.0
Threads = Dict[str, float]  # "server io" -> % of a core


def short_name(role: str, name: str) -> str:
    """``snr-server-io`` -> ``io``; the node's thread (named after the role) -> ``node``."""
    for prefix in (f"snr-{role}-", f"{role}-", "snr-"):
        if name.startswith(prefix):
            name = name[len(prefix) :]
    name = re.sub(r"_\d+$", "", name)  # "sockets_client_42857": the port changes each run
    return "node" if name in (role, "MainThread") else name


# -- reading CPU time ----------------------------------------------------------------
def thread_cpu_ns(pid: int) -> Dict[int, int]:
    """Thread id -> CPU time used so far (ns), for every thread of ``pid``."""
    times: Dict[int, int] = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{tid}/schedstat") as stat:
                times[int(tid)] = int(stat.read().split()[0])
        except (FileNotFoundError, ProcessLookupError):
            continue  # the thread ended meanwhile
    return times


def measure(
    procs: Processes, named: List[Tuple[str, int, Dict[int, str]]], seconds: float, settle: float
) -> Threads:
    """% of a core per thread, "<process> <thread>", over ``seconds`` after ``settle``."""
    try:
        time.sleep(settle)
        before = [thread_cpu_ns(pid) for _, pid, _ in named]
        started = time.perf_counter()
        time.sleep(seconds)
        after = [thread_cpu_ns(pid) for _, pid, _ in named]
        elapsed = time.perf_counter() - started
    finally:
        procs.close(stop=True)
    shares: Threads = {}
    for (role, _, names), old, new in zip(named, before, after):
        for tid, ns in new.items():
            label = f"{role} {short_name(role, names.get(tid, 'not Python (C library)'))}"
            used = ns - old.get(tid, 0)
            shares[label] = shares.get(label, 0.0) + 100.0 * used / 1e9 / elapsed
    return shares


def measure_pair(
    start: Callable[[Processes], Dict[int, str]], seconds: float, settle: float
) -> Threads:
    """Start a server and a client (``start`` gives their pids and roles), then measure them."""
    procs = Processes()
    try:
        pids = start(procs)
        reports = procs.wait_for("connected", n=2)
    except BaseException:
        procs.close(stop=True)
        raise
    named = sorted((pids[pid], pid, names) for pid, names in reports)
    return measure(procs, named, seconds, settle)


def measure_snr(mode: Optional[Mode], seconds: float, settle: float) -> Threads:
    def start(procs: Processes) -> Dict[int, str]:
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        pids = {}
        for role, comms in (("server", pair.server()), ("client", pair.client())):
            pid = procs.start(run_node, (role, [comms, AnnouncerFactory(procs.writer)], mode))
            pids[pid] = role
        return pids

    return measure_pair(start, seconds, settle)


# -- the baselines -------------------------------------------------------------------
def beating_peer(port: int, serve: bool, report: Connection) -> None:
    """One thread: sleep until the next beat is due or bytes come; beat, read, judge silence."""
    if serve:
        listener = socket.create_server(("127.0.0.1", port))
        sock, _ = listener.accept()
        listener.close()
    else:
        deadline = time.monotonic() + SAFETY_S
        while True:
            try:
                sock = socket.create_connection(("127.0.0.1", port))
                break
            except ConnectionRefusedError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.01)
    report.send(("connected", (os.getpid(), thread_names())))
    sent_at = heard_at = time.monotonic()
    while True:
        now = time.monotonic()
        if now - heard_at > DEAD_AFTER_S:
            return  # the peer is dead
        if now - sent_at >= BEAT_S:
            sock.send(b"\0\0\0\0")
            sent_at = now
        wait_s = min(sent_at + BEAT_S, heard_at + DEAD_AFTER_S) - now
        readable, _, _ = select.select([sock], [], [], max(0.0, wait_s))
        if readable:
            if not sock.recv(4096):
                return
            heard_at = time.monotonic()


def zmq_peer(port: int, serve: bool, report: Connection) -> None:
    """A pyzmq PAIR socket with ZMTP heartbeats, its thread blocked in recv."""
    context = zmq.Context()
    sock = context.socket(zmq.PAIR)
    sock.setsockopt(zmq.HEARTBEAT_IVL, int(BEAT_S * 1000))
    sock.setsockopt(zmq.HEARTBEAT_TIMEOUT, int(DEAD_AFTER_S * 1000))
    if serve:
        sock.bind(f"tcp://127.0.0.1:{port}")
        sock.recv()  # the client's hello
        sock.send(b"hi")
    else:
        sock.connect(f"tcp://127.0.0.1:{port}")
        sock.send(b"hello")
        sock.recv()
    report.send(("connected", (os.getpid(), thread_names())))
    sock.recv()  # never comes: the bench ends the process


def measure_peers(target: Any, seconds: float, settle: float) -> Threads:
    def start(procs: Processes) -> Dict[int, str]:
        port = free_port()
        pids = {procs.start(target, (port, True, procs.writer)): "server"}
        pids[procs.start(target, (port, False, procs.writer))] = "client"
        return pids

    return measure_pair(start, seconds, settle)


# -- summing up ----------------------------------------------------------------------
BASELINE = "bare TCP, one thread, beats"
VARIANTS: Dict[str, Any] = {
    BASELINE: lambda s, settle: measure_peers(beating_peer, s, settle),
    "SNR default (DEBUG)": lambda s, settle: measure_snr(None, s, settle),
    "SNR DEPLOYED": lambda s, settle: measure_snr(Mode.DEPLOYED, s, settle),
}
if zmq is not None:
    VARIANTS["pyzmq PAIR, heartbeats"] = lambda s, settle: measure_peers(zmq_peer, s, settle)


def print_report(args: argparse.Namespace, runs: Dict[str, List[Threads]]) -> None:
    print(
        f"Idle connected pair on 127.0.0.1: {args.idle_s:g} s measured after {args.settle_s:g} s "
        f"settling; {args.rounds} interleaved rounds, fresh processes each time; median of the "
        "rounds, spread = min-max; % of one core."
    )
    totals = {name: [sum(threads.values()) for threads in rounds] for name, rounds in runs.items()}
    base = totals[BASELINE]
    header = f"\n{'idle pair (both processes)':34}{'% core':>9}{'spread':>15}{'x baseline':>12}"
    print(header)
    print("-" * (len(header) - 1))
    for name, cpu in totals.items():
        ratio = statistics.median(a / b for a, b in zip(cpu, base))
        print(
            f"{name:34}{statistics.median(cpu):>9.3f}"
            f"{f'{min(cpu):.3f}-{max(cpu):.3f}':>15}{ratio:>12.2f}"
        )
    for name, rounds in runs.items():
        labels = sorted({label for threads in rounds for label in threads})
        print(f"\n{name}, per thread{'':14}{'% core':>9}{'spread':>15}")
        for label in labels:
            cpu = [threads.get(label, 0.0) for threads in rounds]
            print(
                f"  {label:40}{statistics.median(cpu):>9.3f}{f'{min(cpu):.3f}-{max(cpu):.3f}':>15}"
            )
    print("\nTarget: an SNR pair idles at <= 0.100% of a core (both nodes, all threads).")
    for name in runs:
        if name.startswith("SNR"):
            median = statistics.median(totals[name])
            word = "met" if median <= 0.1 else "MISSED"
            held = sum(1 for value in totals[name] if value <= 0.1)
            print(f"  {name:32}{median:.3f}% {word} ({held}/{len(totals[name])} rounds)")


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run of a few seconds")
    parser.add_argument("--rounds", type=int, help="interleaved rounds (5; --quick 1)")
    parser.add_argument("--idle-s", type=float, help="seconds measured (15; --quick 2)")
    parser.add_argument(
        "--settle-s", type=float, help="seconds before measuring, past the start-up checks (4)"
    )
    args = parser.parse_args(argv)
    defaults = (1, 2.0, 4.0) if args.quick else (5, 15.0, 4.0)
    for field, default in zip(("rounds", "idle_s", "settle_s"), defaults):
        if getattr(args, field) is None:
            setattr(args, field, default)
    runs: Dict[str, List[Threads]] = {name: [] for name in VARIANTS}
    for _ in range(args.rounds):
        for name, run in VARIANTS.items():  # interleaved: a busy moment hits every variant
            runs[name].append(run(args.idle_s, args.settle_s))
    print_report(args, runs)


if __name__ == "__main__":
    main()
