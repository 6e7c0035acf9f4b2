"""Console command round trips, against a bare TCP echo on the same machine.

A `RemoteConsole` sends commands to a node's `CommandReceiverFactory` and
waits for each reply; the baseline is a one-line echo server in a thread
(the floor any request/reply over loopback TCP pays). The node idles between
commands, so this is the latency a user or a script sees.

Run from the repository root: ``python bench/bench_console.py [--rounds N]``.
"""

from __future__ import annotations

import argparse
import socket
import statistics
import threading
import time
from functools import partial
from typing import Callable, List, Tuple

from snr import CommandReceiverFactory, Config, Mode, Node
from snr.std_mods.io import RemoteConsole


def echo_server() -> Tuple[socket.socket, threading.Thread]:
    listener = socket.create_server(("127.0.0.1", 0))

    def serve() -> None:
        conn, _ = listener.accept()
        with conn, conn.makefile("rb") as lines:
            for line in lines:
                conn.sendall(line)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return listener, thread


def time_round_trips(send: Callable[[], object], rounds: int) -> List[float]:
    for _ in range(min(50, rounds)):  # warm up
        send()
    times = []
    for _ in range(rounds):
        started = time.perf_counter()
        send()
        times.append(time.perf_counter() - started)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=2000)
    rounds = parser.parse_args().rounds

    listener, server = echo_server()
    with socket.create_connection(listener.getsockname()[:2]) as client:
        client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with client.makefile("rb") as replies:

            def echo() -> bytes:
                client.sendall(b"help\n")
                return replies.readline()

            baseline = time_round_trips(echo, rounds)
    listener.close()
    server.join(1)

    receiver = CommandReceiverFactory(port=0)
    node = Node("bench", Config({"bench": [receiver]}, mode=Mode.DEPLOYED, profile=False))
    node.log.setLevel("WARNING")
    thread = threading.Thread(target=node.loop, daemon=True)
    thread.start()
    host, port = receiver.wait_until_listening()
    results = {"TCP echo (baseline)": baseline}
    with RemoteConsole(host, port) as console:
        for line in ("help", "task event beep 1", "list endpoints"):
            results[f"console: {line}"] = time_round_trips(partial(console.send, line), rounds)
    node.set_terminate_flag("bench done")
    thread.join(5)

    base = statistics.median(baseline)
    print(f"{rounds} round trips each, median and 95th percentile, loopback TCP")
    print(f"{'request':<28} {'median us':>10} {'p95 us':>10} {'x baseline':>11}")
    for name, times in results.items():
        median = statistics.median(times)
        p95 = sorted(times)[int(len(times) * 0.95)]
        print(f"{name:<28} {median * 1e6:>10.1f} {p95 * 1e6:>10.1f} {median / base:>11.2f}")


if __name__ == "__main__":
    main()
