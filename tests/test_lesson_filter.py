"""Lesson 4, a filter: graded on replayed readings, by what the filter stores.

The grader replays 400 noisy depth readings into the student's endpoint in
simulated time and checks the ``depth`` pages: one per reading, the noise
removed, and not lagging behind. Here: the starter fails the noise check and
says why, on its ``smooth`` line; the solution passes; a moving average of 100
readings smooths, but fails the lag check; SNR's own `MovingAvgFilter`, in a
student's file, passes; an exception names its line.
"""

from __future__ import annotations

import contextlib
import io
import shutil
import tempfile
import time
import unittest
from pathlib import Path
from typing import Dict, List

from snr.extras.lessons import lesson
from snr.extras.lessons.command import grade_file
from snr.extras.lessons.grading import Check
from snr.extras.lessons.l04_depth_filter import solution

WRAPPED = '''"""A student's filter: SNR's own moving average, wrapped."""
import collections

from snr import Endpoint, TaskType
from snr.std_mods.filters import MovingAvgFilter


class Wrapped(Endpoint):
    def __init__(self, factory, parent):
        super().__init__(factory, parent, "wrapped")
        self.filter = MovingAvgFilter(collections.deque(maxlen=8))
        self.task_handlers = {(TaskType.store_page, "depth_raw"): self.smooth}

    def smooth(self, task, key):
        self.filter.update(task.val_list[0].data)
        return self.store_data_task("depth", self.filter.avg())
'''
"""SNR's `MovingAvgFilter` of 8 readings, as a student may use it."""

CRASH = '''"""A filter that raises on its 31st reading."""
from snr import Endpoint, TaskType


class Crash(Endpoint):
    def __init__(self, factory, parent):
        super().__init__(factory, parent, "crash")
        self.seen = 0
        self.task_handlers = {(TaskType.store_page, "depth_raw"): self.smooth}

    def smooth(self, task, key):
        self.seen += 1
        return self.store_data_task("depth", 1 / (30 - self.seen))
'''
"""Divides by zero on line 13, at the 30th reading."""

LESSON = lesson(4)


class TestLessonFilter(unittest.TestCase):
    def setUp(self) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="snr-lesson-4-"))
        self.addCleanup(shutil.rmtree, self.folder, True)

    def grade(self, name: str, text: str) -> Dict[str, Check]:
        path = self.folder / name
        path.write_text(text, "utf-8")
        return {check.name: check for check in grade_file(LESSON, path)}

    def test_the_solution_passes_in_well_under_two_seconds(self) -> None:
        started = time.monotonic()
        checks = grade_file(LESSON, LESSON.folder / "solution.py")
        self.assertLess(time.monotonic() - started, 2.0, "a grade takes under 2 s")
        self.assertTrue(all(check.passed for check in checks), checks)
        self.assertEqual(len(checks), 5)

    def test_the_starter_fails_the_noise_check_on_its_smooth_line(self) -> None:
        checks = grade_file(LESSON, LESSON.folder / "starter.py")
        failed = [check for check in checks if not check.passed]
        self.assertEqual([check.name for check in failed], ["removes the noise"])
        smooth = _line_of(LESSON.folder / "starter.py", "def smooth(")
        self.assertEqual(failed[0].line, smooth)
        self.assertIn("1.00 x the readings'", failed[0].happened)
        self.assertTrue(failed[0].expected and failed[0].hint)

    def test_a_window_of_100_readings_lags_behind(self) -> None:
        text = (LESSON.folder / "solution.py").read_text("utf-8")
        checks = self.grade("wide.py", text.replace("WINDOW = 8\n", "WINDOW = 100\n"))
        lag = checks["keeps up with the depth"]
        self.assertFalse(lag.passed, lag)
        self.assertEqual(lag.happened, "20 samples or more (0.4 s) behind")
        self.assertTrue(checks["stores a depth page for each reading"].passed)

    def test_snrs_own_moving_average_wrapped_passes(self) -> None:
        checks = self.grade("wrapped.py", WRAPPED)
        self.assertTrue(all(check.passed for check in checks.values()), checks)
        self.assertEqual(checks["the endpoint"].happened, "Wrapped handles 'depth_raw'", checks)

    def test_an_exception_names_its_line_and_stops_the_grade(self) -> None:
        checks = list(self.grade("crash.py", CRASH).values())
        self.assertEqual(len(checks), 2)
        self.assertFalse(checks[1].passed)
        self.assertEqual(checks[1].line, 13)
        self.assertIn("ZeroDivisionError", checks[1].happened)
        self.assertIn("handling a 'depth_raw' page", checks[1].happened)

    def test_too_few_pages_is_said_in_numbers(self) -> None:
        text = (LESSON.folder / "solution.py").read_text("utf-8")
        sparse = text.replace(
            '        return self.store_data_task("depth", sum',
            "        if self.recent[-1] > 2.0:  # half the readings\n"
            "            return None\n"
            '        return self.store_data_task("depth", sum',
        )
        self.assertNotEqual(sparse, text)
        check = self.grade("sparse.py", sparse)["stores a depth page for each reading"]
        self.assertFalse(check.passed)
        self.assertIn("'depth' pages for 400 'depth_raw' pages", check.happened)


class TestTheSignalAndTheRun(unittest.TestCase):
    def test_the_signal_is_the_same_every_time(self) -> None:
        first = solution.make_signal(400)
        self.assertEqual(first, solution.make_signal(400))
        clean, raw = first
        self.assertAlmostEqual(clean[50], 3.0)
        self.assertAlmostEqual(solution.rms_error(raw, clean), 0.5, delta=0.05)

    def test_lag_samples_finds_a_known_delay(self) -> None:
        clean, _ = solution.make_signal(400)
        self.assertEqual(solution.lag_samples([0.0] * 3 + clean, clean), 3)
        self.assertEqual(solution.lag_samples(clean, clean), 0)

    def test_the_lesson_runs_as_the_student_runs_it(self) -> None:
        out = io.StringIO()
        with contextlib.redirect_stdout(out), self.assertLogs("snr", "INFO") as logs:
            solution.main(["depth_filter.py", "--seconds", "2"])
        self.assertIn("stored every value", "\n".join(logs.output))
        lines: List[str] = out.getvalue().splitlines()
        self.assertEqual(lines[0].split(), ["sample", "true", "depth", "reading", "filtered"])
        self.assertTrue(lines[-1].startswith("100 readings, 100 depth pages."), lines)


def _line_of(path: Path, text: str) -> int:
    for number, line in enumerate(path.read_text("utf-8").splitlines(), start=1):
        if text in line:
            return number
    raise AssertionError(f"{text!r} is not in {path}")


if __name__ == "__main__":
    unittest.main()
