"""Ctrl-C stops a node at once, wherever it lands in the idle wait (docs/design.md).

A Ctrl-C is a KeyboardInterrupt raised in the node's thread at whatever line
it is on. If it landed while that thread held the I/O loop's read role and
the role was not given back, the I/O thread could not close the links and
the node took seconds to stop, warning that its loop and its I/O thread
"did not stop". The in-process tests raise it at each place it can land; the
last test sends real Ctrl-Cs to real clients whose server has just stopped.
"""

from __future__ import annotations

import multiprocessing.connection
import selectors
import socket
import threading
import time
import unittest
from typing import Any, Callable, Dict, List, Optional, Tuple, cast
from unittest import mock

from snr import COMMS_CONNECTED, AbstractNode, SocketsPair
from snr.core.task_queue import TaskQueue
from snr.std_mods.comms.io_loop import IOLoop
from tests.comms_helpers import (
    EventReporterFactory,
    LogForwarderFactory,
    NodeProcess,
    Reports,
    TickerFactory,
    context,
)
from tests.helpers import free_port
from tests.test_comms_io_loop import QuietNode

Events = List[Tuple[int, int]]
POLL = "snr.std_mods.comms.io_loop._poll"


def role_is_free(loop: IOLoop, timeout_s: float = 1.0) -> bool:
    """Whether another thread (as the I/O thread would) gets the read role within ``timeout_s``."""
    got: List[bool] = []

    def take() -> None:
        if loop._role.acquire(timeout=timeout_s):
            loop._role.release()
            got.append(True)

    thread = threading.Thread(target=take, daemon=True)
    thread.start()
    thread.join(timeout_s + 1.0)
    return bool(got)


class OneLink:
    """A socket pair's near end, served by the loop; its reads run ``on_read``."""

    def __init__(self, on_read: Callable[[], None]) -> None:
        self.near, self.far = socket.socketpair()
        self.near.setblocking(False)
        self.on_read = on_read

    def fileno(self) -> int:
        return self.near.fileno()

    def on_readable(self) -> None:
        self.near.recv(4096)
        self.on_read()

    def on_writable(self) -> None:
        pass

    def write_waiting(self) -> None:
        pass

    def on_io_stop(self) -> None:
        pass

    def close(self) -> None:
        self.near.close()
        self.far.close()


def ctrl_c() -> None:
    raise KeyboardInterrupt


class TestCtrlCInTheIdleWait(unittest.TestCase):
    """The node's thread sleeps on its queue, which waits on the I/O loop."""

    def setUp(self) -> None:
        self.loop = IOLoop(cast(AbstractNode, QuietNode()))
        self.addCleanup(self.loop.stop)
        self.loop._thread.start()
        if not self.loop.node_reads:
            self.skipTest("the node's thread reads only where epoll is")
        self.queue = TaskQueue()
        self.assertTrue(self.queue.use_waiter(self.loop))
        self.queue.wait(0)  # takes the bell's ring use_waiter left

    def watch(self, link: OneLink) -> None:
        """Serve ``link`` (on the loop's thread, as comms do); only this thread reads it."""
        watched = threading.Event()

        def watch() -> None:
            self.loop.watch(link, selectors.EVENT_READ)
            self.loop._set_io_reads(
                False
            )  # as once the node first sleeps: the I/O thread leaves it
            watched.set()

        self.loop.call_soon(watch)
        self.assertTrue(watched.wait(2.0))

    def test_in_the_poll(self) -> None:
        def poll(epoll: Any, timeout_s: float) -> Events:
            raise KeyboardInterrupt

        with mock.patch(POLL, poll), self.assertRaises(KeyboardInterrupt):
            self.queue.wait(1.0)
        self.assertTrue(role_is_free(self.loop), "the interrupted thread kept the read role")

    def test_after_the_poll_before_woken(self) -> None:
        # Woken up by a link, then interrupted at woken()'s first line (or in
        # the queue's `finally` just before it): woken's own code never runs.
        self.loop.wake()
        with mock.patch.object(self.loop, "woken", side_effect=KeyboardInterrupt):
            with self.assertRaises(KeyboardInterrupt):
                self.queue.wait(1.0)
        self.assertTrue(role_is_free(self.loop), "the interrupted thread kept the read role")

    def test_while_reading_a_link(self) -> None:
        link = OneLink(ctrl_c)  # the Ctrl-C lands in the middle of the node's read
        self.addCleanup(link.close)
        self.watch(link)
        link.far.send(b"x")
        with self.assertRaises(KeyboardInterrupt):
            self.queue.wait(1.0)
        self.assertTrue(role_is_free(self.loop), "the interrupted thread kept the read role")

    def test_while_the_io_thread_waits_for_the_role(self) -> None:
        # The I/O thread is closing a link and waits for the role the node's
        # thread holds in its wait; the Ctrl-C lands before that thread lets go.
        closed = threading.Event()

        def close_a_link() -> None:
            with self.loop.read_role():
                closed.set()

        def poll(epoll: Any, timeout_s: float) -> Events:
            self.loop.call_soon(close_a_link)
            deadline = time.monotonic() + 2.0
            while not self.loop._role_wanted and time.monotonic() < deadline:
                time.sleep(0.001)
            raise KeyboardInterrupt

        with mock.patch(POLL, poll), self.assertRaises(KeyboardInterrupt):
            self.queue.wait(1.0)
        self.assertTrue(closed.wait(2.0), "the I/O thread never got the read role")

    def test_the_wait_after_a_ctrl_c_still_reads(self) -> None:
        # What a Ctrl-C skipped is not lost: epoll says again that it is ready.
        reads: List[int] = []
        link = OneLink(lambda: reads.append(1))
        self.addCleanup(link.close)
        self.watch(link)
        link.far.send(b"x")
        with mock.patch.object(self.loop, "woken", side_effect=KeyboardInterrupt):
            with self.assertRaises(KeyboardInterrupt):
                self.queue.wait(1.0)
        self.queue.wait(1.0)
        self.assertEqual(reads, [1])


ROUNDS = 4  # each: a server and a client per moment below, ~0.5 s (forked), ~2 s (spawned)
ROUNDS_S = 6.0  # no round starts after this long: the test stays under 10 s
FLOOD_HZ = 1000.0  # each node's ticker, in the mid-flood rounds
STOP_LIMIT_S = 1.5  # Ctrl-C to exit; the bug took 3-5 s
MOMENTS: Dict[str, Optional[float]] = {  # when the client gets its Ctrl-C, after the server's
    "before the server stops": None,
    "as the server stops": 0.0,
    "right after the server went": 0.05,
    "a little later": 0.2,
}


class TestCtrlCStopsAClientAtOnce(unittest.TestCase):
    maxDiff = None  # a failure shows every slow client

    def test_clients_whose_server_just_stopped(self) -> None:
        ctx = context()
        reports = Reports(ctx)
        self.addCleanup(reports.close)
        slow: List[str] = []
        start = time.monotonic()
        for round_ in range(ROUNDS):
            if round_ >= 2 and time.monotonic() - start > ROUNDS_S:
                break  # a slow machine: the first two rounds (idle, mid-flood) are the test
            flood = round_ % 2 == 1  # every other round, the clients are mid-flood
            slow += self.one_round(ctx, reports, flood)
        self.assertEqual(slow, [], "clients that stopped late or warned")

    def one_round(self, ctx: Any, reports: Reports, flood: bool) -> List[str]:
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        # Mid-flood: pages both ways, as fast as the ticks go, until the server stops.
        flooding: List[Any] = [TickerFactory("flood", FLOOD_HZ)] if flood else []
        server = NodeProcess(ctx, "server", [pair.server(["flood"]), *flooding])
        clients = {
            moment: NodeProcess(
                ctx,
                f"client{i}",
                [
                    pair.client(["flood"]),
                    EventReporterFactory(reports.writer, [COMMS_CONNECTED]),
                    LogForwarderFactory(reports.writer),
                    *flooding,
                ],
            )
            for i, moment in enumerate(MOMENTS)
        }
        everyone = [server, *clients.values()]
        reports.nodes = everyone
        try:
            server.start()
            for client in clients.values():
                client.start()
            connected: set[str] = set()
            while len(connected) < len(clients):
                connected.add(reports.wait_for(lambda r: r[0] == "event")[1])
            late = self.stop(server, clients, flood)
            while reports.reader.poll(0):  # what the clients logged as they stopped
                reports.get(0)
            warned = [r for r in reports.seen if r[0] == "log" and "did not stop" in r[3]]
            reports.seen.clear()
            return late + [f"warned: {r}" for r in warned]
        finally:
            for node in everyone:
                node.interrupt(timeout_s=0)  # kills what is left; keeps what it printed

    def stop(self, server: NodeProcess, clients: Dict[str, NodeProcess], flood: bool) -> List[str]:
        """Ctrl-C each client at its moment; what went wrong, one line each."""
        start = time.monotonic() + 0.1  # moments count from the server's Ctrl-C, 0.1 s from now
        # The server's Ctrl-C is the "" moment, at 0: before the other moments at 0.
        due = sorted([(-0.1 if at is None else at, m) for m, at in MOMENTS.items()] + [(0.0, "")])
        sent: Dict[str, float] = {}
        stopped: Dict[str, float] = {}
        while len(stopped) < len(clients) and time.monotonic() - start < 4.0:
            now = time.monotonic() - start
            while due and due[0][0] <= now:
                moment = due.pop(0)[1]
                (clients[moment] if moment else server).ctrl_c()
                sent[moment] = time.monotonic()
            by_sentinel = {
                c.process.sentinel: m for m, c in clients.items() if m in sent and m not in stopped
            }
            wait_s = max(0.0, min(0.01, due[0][0] - now)) if due else 0.01
            for ended in multiprocessing.connection.wait(list(by_sentinel), wait_s):
                stopped[by_sentinel[cast(int, ended)]] = time.monotonic()
        found: List[str] = []
        what = "mid-flood" if flood else "idle link"
        for moment, client in clients.items():
            took = stopped.get(moment, float("inf")) - sent.get(moment, start)
            client.join(1.0)
            printed = client.output()
            if took > STOP_LIMIT_S or "did not stop" in printed:
                found.append(f"{what}, Ctrl-C {moment}: stopped after {took:.2f} s; {printed!r}")
        return found


if __name__ == "__main__":
    unittest.main()
