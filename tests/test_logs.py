"""SNR's logging: each line once, however the program set logging up; repeats in brief.

`RateLimitedLog` and `LossReport` keep repeated lines short and always say drops.
"""

from __future__ import annotations

import logging
import subprocess
import sys
import unittest
from typing import List

from snr.core.logs import LossReport
from snr.std_mods.comms.rate_limited_log import RateLimitedLog
from tests.examples_support import ROOT, script_env


class Lines(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.lines: List[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(record.getMessage())


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class LogTest(unittest.TestCase):
    def setUp(self) -> None:
        self.log = logging.getLogger(f"snr.test_logs.{self.id()}")
        self.log.propagate = False
        self.log.setLevel(logging.DEBUG)
        self.lines = Lines()
        self.log.addHandler(self.lines)
        self.addCleanup(self.log.removeHandler, self.lines)
        self.clock = Clock()


class TestRateLimitedLog(LogTest):
    def test_news_is_logged_one_by_one_until_it_floods(self) -> None:
        news = RateLimitedLog(self.log, burst=3, window_s=10.0, clock=self.clock)
        for n in range(10):  # a flood: three in full, the rest counted
            news.report("Clients connected", logging.INFO, "client %d", n)
            self.clock.now += 0.1
        self.assertEqual(self.lines.lines, ["client 0", "client 1", "client 2"])
        news.tick()  # the window has not passed: nothing yet
        self.assertEqual(len(self.lines.lines), 3)
        self.clock.now += 10
        news.tick()
        self.assertRegex(
            self.lines.lines[3],
            r"^Clients connected: 7 more in the last 10\.\d s, not logged one by one "
            r"\(over 3 in 10 s\)\.$",
        )
        news.report("Clients connected", logging.INFO, "client %d", 10)  # calm again
        self.assertEqual(self.lines.lines[4], "client 10")

    def test_every_kind_has_its_own_budget_and_flush_says_the_rest(self) -> None:
        news = RateLimitedLog(self.log, burst=1, window_s=10.0, clock=self.clock)
        for kind in ("Clients connected", "Clients disconnected"):
            for _ in range(3):
                news.report(kind, logging.INFO, "%s", kind.lower())
        self.assertEqual(self.lines.lines, ["clients connected", "clients disconnected"])
        news.flush()
        self.assertEqual(len(self.lines.lines), 4)
        self.assertTrue(all("2 more in the last" in line for line in self.lines.lines[2:]))


class TestLossReport(LogTest):
    def test_drops_not_yet_said_are_said_when_the_source_ends(self) -> None:
        loss = LossReport(self.log, "pages for 'urov'", "it is slow", clock=self.clock)
        loss.dropped()  # said at once
        self.clock.now += 0.2
        loss.dropped(4)  # within the second: counted, not yet said
        self.assertEqual(len(self.lines.lines), 1)
        self.clock.now += 0.2
        self.assertTrue(loss.ended("the link ended"))
        self.assertEqual(
            self.lines.lines[-1],
            "Dropped 4 more pages for 'urov' before the link ended (5 over 0.4 s, 5 in all).",
        )
        self.assertFalse(loss.dropping)
        self.assertFalse(loss.ended("the link ended"), "nothing more to say")

    def test_an_episode_all_said_ends_in_silence(self) -> None:
        loss = LossReport(self.log, "pages for 'urov'", "it is slow", clock=self.clock)
        loss.dropped()
        self.assertFalse(loss.ended("the link ended"), "the one drop is in the log already")
        self.assertEqual(len(self.lines.lines), 1)
        self.assertFalse(loss.dropping)


# A program as a student writes it; argv[1] says when, if ever, it configures logging.
PROGRAM = """
import logging, sys
from snr import Config, Mode, Node, TimeoutLoopFactory
app_format = "app %(name)s %(levelname)s: %(message)s"
if sys.argv[1] == "before":
    logging.basicConfig(format=app_format)
node = Node("robot", Config({"robot": [TimeoutLoopFactory(seconds=1)]}, mode=Mode.DEBUG))
if sys.argv[1] == "after":
    logging.basicConfig(format=app_format)
node.log.info("Depth %d m", 3)
node.log.warning("Sonar silent")

class Listener(logging.Handler):  # as the console's, quoting a failed reload to its user
    snr_only_listens = True
    def emit(self, record):
        pass

node.log.addHandler(Listener(logging.ERROR))
node.log.error("Reload failed")
"""


class TestEachLineOnce(unittest.TestCase):
    """Whoever prints SNR's lines, each is printed once (issue: twice after basicConfig)."""

    def stderr_lines(self, when: str) -> List[str]:
        done = subprocess.run(
            [sys.executable, "-c", PROGRAM, when],
            cwd=ROOT,
            env=script_env(),
            capture_output=True,
            text=True,
            timeout=60,
        )
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertEqual(done.stdout, "")
        return done.stderr.splitlines()

    def test_basic_config_before_the_first_node(self) -> None:
        self.assertEqual(
            self.stderr_lines("before"),
            [
                "app snr.robot INFO: Depth 3 m",
                "app snr.robot WARNING: Sonar silent",
                "app snr.robot ERROR: Reload failed",
            ],
        )

    def test_basic_config_after_the_first_node(self) -> None:
        self.assertEqual(
            self.stderr_lines("after"),
            [
                "app snr.robot INFO: Depth 3 m",
                "app snr.robot WARNING: Sonar silent",
                "app snr.robot ERROR: Reload failed",
            ],
        )

    def test_never_configured_snr_prints_its_own_lines(self) -> None:
        lines = self.stderr_lines("never")
        self.assertEqual(len(lines), 3, lines)
        self.assertRegex(lines[0], r"^\d\d:\d\d:\d\d snr\.robot INFO: Depth 3 m$")
        self.assertRegex(lines[1], r"^\d\d:\d\d:\d\d snr\.robot WARNING: Sonar silent$")
        # A handler that only listens (the console's) leaves the line to SNR's.
        self.assertRegex(lines[2], r"^\d\d:\d\d:\d\d snr\.robot ERROR: Reload failed$")


if __name__ == "__main__":
    unittest.main()
