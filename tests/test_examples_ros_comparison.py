"""examples/ros_comparison and the two ROS pages that quote it."""

import contextlib
import io
import logging
import os
import re
import unittest
from typing import List

import snr
from tests.examples_support import ROOT, example_path, load_module
from tests.helpers import StopWhenFactory

FILE = example_path("ros_comparison", "depth_monitor.py")


def python_blocks(markdown: str) -> List[str]:
    return re.findall(r"```python\n(.*?)```", markdown, re.DOTALL)


class TestDepthMonitor(unittest.TestCase):
    def test_runs_and_displays_filtered_depth(self) -> None:
        monitor = load_module(FILE, "ros_comparison_depth_monitor")
        factories = list(monitor.components["robot"])
        # Not the 5 s of the file: stop once two depths have been displayed.
        factories[-1] = StopWhenFactory((snr.TaskType.store_page, "depth"), count=2)
        factories.append(snr.TimeoutLoopFactory(seconds=5))  # only if the stop never comes
        runner = snr.SynchronousRunner("robot", snr.Config({"robot": factories}))
        with self.assertLogs("snr.robot.depth_display", logging.INFO) as logs:
            with contextlib.redirect_stderr(io.StringIO()):
                runner.run()
        assert runner.node is not None
        self.assertEqual(runner.node.terminate_reason, "test work done")
        shown = [record.getMessage() for record in logs.records]
        self.assertGreaterEqual(len(shown), 2)
        self.assertEqual(shown[0], "depth 5.00 m")  # the first mean is the first reading

    def test_the_pages_quote_the_file_as_it_is(self) -> None:
        with open(FILE, encoding="utf-8") as f:
            source = f.read()
        for page in ["coming-from-ros.md", "going-to-ros.md"]:
            with open(os.path.join(ROOT, "docs", page), encoding="utf-8") as f:
                markdown = f.read()
            snr_blocks = [
                b for b in python_blocks(markdown) if "AbstractNode" in b or "ComponentsByRole" in b
            ]
            self.assertTrue(snr_blocks, page)
            for block in snr_blocks:
                self.assertIn(block, source, f"{page} quotes code that is not in {FILE}")


if __name__ == "__main__":
    unittest.main()
