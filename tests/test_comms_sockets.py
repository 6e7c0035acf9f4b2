"""Sockets comms between real nodes in separate processes (thesis 5.1, 5.4.1)."""

from __future__ import annotations

import time
import unittest
from typing import Any, List

from snr import COMMS_CONNECTED, COMMS_DISCONNECTED, SocketsPair
from tests.comms_helpers import (
    CpuMeterFactory,
    EchoFactory,
    EventReporterFactory,
    LogForwarderFactory,
    NodeProcess,
    OrderCheckerFactory,
    ReporterFactory,
    Reports,
    SendOnConnectFactory,
    TickerFactory,
    context,
    pages_of,
)
from tests.helpers import free_port, settle_the_heap


class SocketsProcessTest(unittest.TestCase):
    def setUp(self) -> None:
        self.ctx = context()
        self.reports = Reports(self.ctx)
        self.addCleanup(self.reports.close)
        self.pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        self.nodes: List[NodeProcess] = []
        self.addCleanup(self.stop_all)

    def node(self, role: str, *factories: Any) -> NodeProcess:
        node = NodeProcess(self.ctx, role, factories).start()
        self.nodes.append(node)
        self.reports.nodes.append(node)  # a failure shows what it printed
        return node

    def stop_all(self) -> None:
        for node in self.nodes:  # all at once: each stops in its own time, not one after another
            node.ctrl_c()
        for node in self.nodes:
            node.interrupt()

    def collect(self, role: str, key: str, count: int, timeout_s: float = 8.0) -> List[Any]:
        """Wait until ``role`` reported ``count`` pages under ``key``."""
        if len(pages_of(self.reports.seen, role, key)) < count:
            self.reports.wait_for(
                lambda _: len(pages_of(self.reports.seen, role, key)) >= count, timeout_s
            )
        return pages_of(self.reports.seen, role, key)

    def settle(self, seconds: float = 0.1) -> None:
        """Take any late (unwanted) reports, e.g. duplicates or echoes.

        Pages between processes on 127.0.0.1 take well under a millisecond, so
        0.1 s is ample for a page that should not come.
        """
        deadline = time.monotonic() + seconds
        while (remaining := deadline - time.monotonic()) > 0:
            if self.reports.reader.poll(remaining):
                self.reports.get(0)


class TestForwarding(SocketsProcessTest):
    def test_client_forwards_only_its_keys_with_origin_and_time(self) -> None:
        writer = self.reports.writer
        self.node("receiver", self.pair.server(), ReporterFactory(writer, ["a", "b"]))
        self.node(
            "sender",
            self.pair.client(["a"]),
            SendOnConnectFactory("a", 5),
            SendOnConnectFactory("b", 3, name="send_b"),
        )
        self.assertEqual(self.collect("receiver", "a", 5), [0, 1, 2, 3, 4])
        self.settle()
        pages = [r for r in self.reports.seen if r[0] == "receiver"]
        self.assertEqual(
            pages, [("receiver", "a", i, "sender", 1000.0 + i) for i in range(5)], "no 'b'"
        )

    def test_both_directions_over_one_connection(self) -> None:
        writer = self.reports.writer
        self.node(
            "robot",
            self.pair.server(["pong"]),
            EchoFactory("ping", "pong"),
            ReporterFactory(writer, ["ping"]),
        )
        self.node(
            "topside",
            self.pair.client("ping"),
            SendOnConnectFactory("ping", 50),
            ReporterFactory(writer, ["pong"]),
        )
        self.assertEqual(self.collect("topside", "pong", 50), list(range(50)))
        self.assertEqual(self.collect("robot", "ping", 50), list(range(50)))
        pongs = [r for r in self.reports.seen if r[:2] == ("topside", "pong")]
        self.assertTrue(all(r[3] == "robot" for r in pongs), pongs[:3])

    def test_server_accepts_several_clients_and_never_echoes(self) -> None:
        # All three forward the same key: the hub passes pages between the
        # clients, but no page goes back to where it came from.
        writer = self.reports.writer
        self.node("hub", self.pair.server(["shared"]), ReporterFactory(writer, ["shared"]))
        self.node(
            "one",
            self.pair.client(["shared"]),
            SendOnConnectFactory("shared", 5),
            ReporterFactory(writer, ["shared"]),
        )
        self.assertEqual(self.collect("hub", "shared", 5), [0, 1, 2, 3, 4])
        self.node(
            "two",
            self.pair.client(["shared"]),
            SendOnConnectFactory("shared", 5, first=100),
            ReporterFactory(writer, ["shared"]),
        )
        self.collect("hub", "shared", 10)
        self.collect("one", "shared", 10)
        self.settle()
        seen = self.reports.seen
        self.assertEqual(pages_of(seen, "hub", "shared"), [0, 1, 2, 3, 4, *range(100, 105)])
        self.assertEqual(pages_of(seen, "one", "shared"), [0, 1, 2, 3, 4, *range(100, 105)])
        # "two" connected after "one" sent: pages are live, so it has only its own.
        self.assertEqual(pages_of(seen, "two", "shared"), list(range(100, 105)))
        from_two_at_one = [r[3] for r in seen if r[0] == "one" and r[2] >= 100]
        self.assertEqual(set(from_two_at_one), {"two"})


class TestFaults(SocketsProcessTest):
    def test_client_started_first_connects_when_the_server_appears(self) -> None:
        writer = self.reports.writer
        self.node(
            "sender",
            self.pair.client(["a"]),
            SendOnConnectFactory("a", 3),
            EventReporterFactory(writer, [COMMS_CONNECTED]),
        )
        time.sleep(0.1)  # the client is retrying meanwhile (first retries at 0.05 and 0.15 s)
        self.assertEqual(self.reports.seen, [])
        self.node("receiver", self.pair.server(), ReporterFactory(writer, ["a"]))
        self.assertEqual(self.collect("receiver", "a", 3), [0, 1, 2])

    def test_reconnects_after_the_server_is_killed_mid_stream(self) -> None:
        writer = self.reports.writer
        sender = self.node(
            "sender",
            self.pair.client(["tick"]),
            TickerFactory("tick", hz=50),
            LogForwarderFactory(writer),
        )
        first = self.node("receiver", self.pair.server(), ReporterFactory(writer, ["tick"]))
        self.collect("receiver", "tick", 5)
        first.kill()  # SIGKILL: no goodbye on the wire
        # The sender notices after the receiver died, so every report of the
        # first receiver is ahead of its warning in the pipe: `before` is exact.
        self.reports.wait_for(lambda r: r[0] == "log" and "Lost the link" in r[3])
        before = len(pages_of(self.reports.seen, "receiver", "tick"))
        self.node("receiver", self.pair.server(), ReporterFactory(writer, ["tick"]))
        ticks = self.collect("receiver", "tick", before + 5)
        self.assertTrue(sender.process.is_alive(), "the sender survived its peer's death")
        old, new = ticks[:before], ticks[before:]
        self.assertEqual(old, list(range(old[0], old[0] + len(old))))
        self.assertEqual(new, list(range(new[0], new[0] + len(new))), "in order, no repeats")
        self.assertGreater(new[0], old[-1])
        lost = [r for r in self.reports.seen if r[0] == "log" and "Lost the link" in r[3]]
        self.assertEqual(len(lost), 1, lost)
        self.assertIn("Reconnecting", lost[0][3])

    def test_server_survives_a_killed_client_and_takes_the_next(self) -> None:
        writer = self.reports.writer
        server = self.node(
            "receiver",
            self.pair.server(),
            ReporterFactory(writer, ["tick"]),
            EventReporterFactory(writer, [COMMS_DISCONNECTED]),
        )
        first = self.node("sender", self.pair.client(["tick"]), TickerFactory("tick", hz=50))
        self.collect("receiver", "tick", 3)
        first.kill()
        # The link's end is handled after the pages read before it: once it is
        # reported, every page of the first sender has been too.
        self.reports.wait_for(lambda r: r[0] == "event" and r[2] == COMMS_DISCONNECTED)
        before = len(pages_of(self.reports.seen, "receiver", "tick"))
        self.node("sender", self.pair.client(["tick"]), TickerFactory("tick", hz=50))
        ticks = self.collect("receiver", "tick", before + 3)
        self.assertTrue(server.process.is_alive())
        new = ticks[before:]  # a new sender counts from 0 (the first ticks may precede the link)
        self.assertEqual(new, list(range(new[0], new[0] + len(new))))
        self.assertLess(new[0], 10)

    def test_20000_pages_all_arrive_in_order_at_a_slow_receiver(self) -> None:
        count = 20000
        writer = self.reports.writer
        self.node(
            "receiver",
            self.pair.server(),
            OrderCheckerFactory(writer, "n", count, slow_every=1000),
        )
        self.node("sender", self.pair.client("n"), SendOnConnectFactory("n", count))
        done = self.reports.wait_for(lambda r: r[0] == "done", timeout_s=12)
        self.assertEqual(done[1:3], (count, []), "all pages, in order, no duplicates")

    def test_idle_connected_pair_uses_under_2_percent_cpu(self) -> None:
        settle_the_heap(self)  # no collection of earlier tests' objects in the window
        # CPU time of each node process over 0.3 s once connected (robust to a
        # busy machine: it counts only this process's own work).
        writer = self.reports.writer
        window_s = 0.3
        self.node("receiver", self.pair.server(["b"]), CpuMeterFactory(writer, window_s))
        self.node("sender", self.pair.client(["a"]), CpuMeterFactory(writer, window_s))
        first = self.reports.wait_for(lambda r: r[0] == "cpu", timeout_s=8)
        second = self.reports.wait_for(lambda r: r[0] == "cpu", timeout_s=8)
        for _, role, used_s, wall_s in (first, second):
            # A spinning pair would use a whole core; the idle figure itself (0.1 %) is
            # bench_comms.py's to measure. 10 % leaves room for a long serial run's threads.
            self.assertLess(used_s / wall_s, 0.10, f"{role} used {used_s:.3f} s of CPU")


if __name__ == "__main__":
    unittest.main()
