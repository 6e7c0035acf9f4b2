"""`RepeatFilter` and `LossReport`: repeated lines in brief, and drops always said."""

from __future__ import annotations

import logging
import unittest
from typing import List

from snr.core.logs import LossReport, RepeatFilter


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


class TestRepeatFilter(LogTest):
    def test_a_flood_is_summarised_and_a_quiet_group_starts_afresh(self) -> None:
        news = RepeatFilter(self.log, first=2, every_s=5.0, clock=self.clock, fresh_after_s=30.0)
        for n in range(10):  # a flood: two in full, the rest counted
            news.report("connect", "Clients connected", logging.INFO, "client %d", n)
            self.clock.now += 0.1
        self.assertEqual(self.lines.lines[0], "client 0")
        self.assertTrue(self.lines.lines[1].startswith("client 1\n(More of these"))
        self.assertEqual(len(self.lines.lines), 2)
        self.clock.now += 60  # quiet: the next one is news again, after the count
        news.report("connect", "Clients connected", logging.INFO, "client %d", 10)
        self.assertRegex(self.lines.lines[2], r"^Clients connected: 8 more times .* \(10 in all\)")
        self.assertEqual(self.lines.lines[3], "client 10")
        self.assertEqual(news.count("connect"), 11)

    def test_without_fresh_after_s_the_count_goes_on_for_ever(self) -> None:
        repeats = RepeatFilter(self.log, first=1, every_s=5.0, clock=self.clock)
        for _ in range(3):
            repeats.report("bad", "Bad readings", logging.WARNING, "bad reading")
            self.clock.now += 60
        self.assertTrue(self.lines.lines[0].startswith("bad reading\n"))  # in full once
        self.assertEqual(len(self.lines.lines), 3)
        for line in self.lines.lines[1:]:
            self.assertRegex(line, r"^Bad readings: 1 more times")


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
            "Dropped 5 pages for 'urov' over 0.4 s before the link ended (5 in all).",
        )
        self.assertFalse(loss.dropping)
        self.assertFalse(loss.ended("the link ended"), "nothing more to say")


if __name__ == "__main__":
    unittest.main()
