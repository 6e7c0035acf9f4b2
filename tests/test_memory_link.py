"""The in-memory connection pair (snr.utils.memory_link): two nodes of one process, linked."""

from __future__ import annotations

import logging
import unittest
from typing import List

from snr import Config, Mode, Page, tasks
from snr.prelude import ConfigError
from snr.std_mods.comms.comms_loop import CommsLoop
from snr.utils import MemoryLinkPair, memory_transport_pair
from tests.helpers import wait_until
from tests.quiet import capture_test_logs
from tests.test_comms_liveness import CounterFactory
from tests.test_comms_local import LocalNodes, StoreOnConnectFactory

PAGE = Page("pose", {"x": 1.5, "tags": ["a", "b"]}, "robot", 1234.5, process=False)


class TestTransportPair(unittest.TestCase):
    def test_bytes_sent_on_one_end_arrive_on_the_other_then_the_end(self) -> None:
        here, there = memory_transport_pair()
        self.addCleanup(here.close)
        self.addCleanup(there.close)
        self.assertEqual((here.peer, there.peer), ("memory-b", "memory-a"))
        with self.assertRaises(BlockingIOError):  # nothing sent yet: non-blocking
            there.recv_into(bytearray(8))
        self.assertEqual(here.send(b"abc"), 3)
        here.end_writing()
        buffer = bytearray(8)
        self.assertEqual(there.recv_into(buffer), 3)
        self.assertEqual(bytes(buffer[:3]), b"abc")
        self.assertEqual(there.recv_into(buffer), 0, "then the end of the stream")


class TestTwoNodesInMemory(unittest.TestCase):
    def setUp(self) -> None:
        capture_test_logs(self)  # the lost-link warnings of these tests stay out of the output

    def run_nodes(self, config: Config, pair: MemoryLinkPair) -> LocalNodes:
        self.addCleanup(pair.close)  # cleanups run last first: after the nodes stop
        nodes = LocalNodes(config, ["receiver", "sender"])
        self.addCleanup(nodes.stop)
        return nodes

    def test_a_stored_page_arrives_exactly_with_its_fields(self) -> None:
        pair = MemoryLinkPair()
        counter = CounterFactory("pose")
        config = Config(
            {
                "receiver": [pair.first(), counter],
                "sender": [pair.second("pose"), StoreOnConnectFactory([tasks.store_page(PAGE)])],
            },
            mode=Mode.TEST,
        )
        nodes = self.run_nodes(config, pair)
        self.assertTrue(wait_until(lambda: bool(counter.seen), 5.0), "the page arrives")
        self.assertEqual(nodes.nodes[0].get_page("pose"), PAGE)

    def test_a_cut_is_seen_on_both_sides_and_the_nodes_keep_running(self) -> None:
        pair = MemoryLinkPair()
        counter = CounterFactory("pose")
        config = Config(
            {"receiver": [pair.first(), counter], "sender": [pair.second("pose")]},
            mode=Mode.TEST,
        )
        nodes = self.run_nodes(config, pair)
        receiver, sender = nodes.nodes
        loops: List[CommsLoop] = []
        for node, name in ((receiver, "memory_link_a"), (sender, "memory_link_b")):
            loop = node.components[name]
            assert isinstance(loop, CommsLoop)
            loops.append(loop)
        self.assertTrue(wait_until(lambda: all(loop.links for loop in loops), 5.0))
        with self.assertLogs("snr", logging.WARNING) as logs:
            pair.cut()
            self.assertTrue(
                wait_until(lambda: sum("Lost the link" in line for line in logs.output) >= 2, 5.0),
                logs.output,
            )
        self.assertTrue(wait_until(lambda: all(loop.is_terminated() for loop in loops), 5.0))
        self.assertTrue(all(thread.is_alive() for thread in nodes.threads), "nodes keep running")

    def test_an_end_serves_one_node_once(self) -> None:
        pair = MemoryLinkPair()
        self.addCleanup(pair.close)
        factory = pair.first("pose")
        factory.take_transport()
        with self.assertRaises(ConfigError) as ctx:
            factory.take_transport()
        self.assertIn("Make a new MemoryLinkPair()", str(ctx.exception))


if __name__ == "__main__":
    unittest.main()
