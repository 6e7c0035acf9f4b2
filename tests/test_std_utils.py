"""Timeout, stopwatch and printer (thesis 5.4, figure 5.4)."""

import io
import logging
import unittest
from typing import List

from snr import (
    Config,
    Mode,
    Node,
    PrinterEndpointFactory,
    SNRTestCase,
    StopwatchEndpointFactory,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)
from snr.prelude import ComponentError
from snr.std_mods.utils import format_task
from tests.helpers import StopWhenDrainedFactory


class TestTimeout(SNRTestCase):
    def test_seconds_and_ms_add_up_and_terminate_with_reason(self) -> None:
        times: List[float] = []
        node = self.run_test_node(
            [
                TimeoutLoopFactory(seconds=0.02, ms=30),
                StopwatchEndpointFactory(times, [TaskType.terminate]),
            ]
        )
        self.assertEqual(node.terminate_reason, "Timeout")
        self.assertEqual(len(times), 1)
        self.assertGreaterEqual(times[0], 0.05)

    def test_no_time_stops_the_node_once_started(self) -> None:
        node_log = logging.getLogger(f"snr.{self.role}")
        self.addCleanup(node_log.setLevel, node_log.level)
        node_log.setLevel(logging.DEBUG)  # the hint is a DEBUG line
        for factory in (TimeoutLoopFactory(), TimeoutLoopFactory(seconds=0, ms=0)):
            with self.assertLogs("snr", "DEBUG") as logs:
                node = self.run_test_node([factory], timeout_s=0.5)
            self.assertEqual(node.terminate_reason, "Timeout")
            self.assertTrue(any("stops the node as soon as it" in line for line in logs.output))

    def test_negative_time_is_refused(self) -> None:
        for seconds, ms in ((-1, 0), (0, -5), (float("nan"), 0)):
            with self.assertRaises(ComponentError) as ctx:
                TimeoutLoopFactory(seconds, ms)
            self.assertIn("negative time", str(ctx.exception))

    def test_two_timeouts_need_names(self) -> None:
        node = self.run_test_node(
            [TimeoutLoopFactory(ms=50), TimeoutLoopFactory(seconds=5, name="backstop")]
        )
        self.assertIn("backstop", node.components)


class TestPrinter(SNRTestCase):
    def test_prints_figure_5_4_lines(self) -> None:
        out = io.StringIO()
        node = self.mock_node()
        printer = PrinterEndpointFactory([(TaskType.event, "button_pressed")], out).get(node)
        printer.print_task(tasks.event("button_pressed", ["A"]), (TaskType.event, "x"))
        self.assertEqual(out.getvalue(), "(event, 'button_pressed'): ['A']\n")
        self.assertEqual(format_task(tasks.event("b", [1])), "(event, 'b'): [1]")

    def test_only_watched_tasks_are_printed_in_a_node(self) -> None:
        out = io.StringIO()
        node = Node(
            "t",
            Config(
                {"t": [PrinterEndpointFactory([(TaskType.event, "shown")], out),
                       StopWhenDrainedFactory()]},
                mode=Mode.TEST,
            ),
        )  # fmt: skip
        node.schedule([tasks.event("hidden", [1]), tasks.event("shown", [2])])
        node.loop()
        self.assertEqual(out.getvalue(), "(event, 'shown'): [2]\n")


if __name__ == "__main__":
    unittest.main()
