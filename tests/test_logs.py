"""`RepeatFilter` and `LossReport`: repeated lines in brief, and drops always said."""

from __future__ import annotations

import logging
import unittest
from typing import List

from snr.core.logs import LossReport, RateLimitedLog


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


if __name__ == "__main__":
    unittest.main()
