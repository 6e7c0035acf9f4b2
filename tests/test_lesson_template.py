"""The lesson template (snr/extras/lessons/template/) still works: it cannot rot.

docs/teaching.md tells a teacher to copy the template to write a new lesson;
here its grader passes its solution, fails its starter with checks that say
what, why and where, grades it as ``python -m snr lesson grade`` would once
it is registered, and the template stays out of ``lesson list``. Every ``$``
line of docs/teaching.md prints what the page shows.
"""

from __future__ import annotations

import contextlib
import glob
import io
import os
import shutil
import tempfile
import time
import unittest
from pathlib import Path

from snr.__main__ import main
from snr.extras.lessons import LESSONS, Lesson, lesson
from snr.extras.lessons.command import grade_file
from snr.extras.lessons.template import grader
from tests.examples_support import ROOT as CHECKOUT
from tests.tutorial_transcripts import compare, transcripts

TEACHING_PAGE = Path(CHECKOUT, "docs", "teaching.md")

CLEO = '''"""Cleo's wall follower: the range handler divides by zero."""

from snr import Endpoint, TaskType


class WallFollower(Endpoint):
    def __init__(self, factory, parent):
        super().__init__(factory, parent, "wall_follower")
        self.task_handlers = {(TaskType.store_page, "range"): self.steer}

    def steer(self, task, key):
        ranges = task.val_list[0].data["ranges_m"]
        return self.store_data_task("wheel_cmd", {"left": 1 / 0, "right": ranges[0]})
'''
"""The page's third student: the handler divides by zero on line 13."""

TEMPLATE = Lesson(0, "stop at a wall", "template", "stop_at_wall.py", "")
"""The template as a registered lesson would be: what `lesson grade` loads."""


def line_of(path: Path, text: str) -> int:
    """The number of the first line of ``path`` that contains ``text``."""
    for number, line in enumerate(path.read_text("utf-8").splitlines(), start=1):
        if text in line:
            return number
    raise AssertionError(f"{text!r} is not in {path}")


class TestTemplate(unittest.TestCase):
    def test_the_solution_passes_and_the_starter_fails_with_reasons(self) -> None:
        started = time.monotonic()
        checks = grade_file(TEMPLATE, TEMPLATE.folder / "solution.py")
        self.assertLess(time.monotonic() - started, 5.0, "a grade takes under 5 s")
        self.assertEqual(len(checks), 5, checks)
        self.assertTrue(all(check.passed for check in checks), checks)
        starter = TEMPLATE.folder / "starter.py"
        checks = grade_file(TEMPLATE, starter)
        self.assertTrue(checks[0].passed, "the starter's endpoint is found")
        failed = [check.name for check in checks if not check.passed]
        self.assertEqual(
            failed, ["never touches the wall", "stops 0.5 m from the wall", "ends stopped"]
        )
        steer = line_of(starter, "def steer(")
        for check in checks[2:]:
            self.assertTrue(check.expected and check.happened and check.hint, check)
            self.assertEqual(check.line, steer, check)
        self.assertIn("TODO", starter.read_text("utf-8"))

    def test_the_graders_own_command_prints_each_check_and_its_status(self) -> None:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            passed = grader.main(["grader.py", str(TEMPLATE.folder / "solution.py")])
            failed = grader.main(["grader.py", str(TEMPLATE.folder / "starter.py")])
        self.assertEqual((passed, failed), (0, 1), out.getvalue())
        self.assertIn("passed  stops 0.5 m from the wall: 0.50 m", out.getvalue())
        self.assertIn("FAILED  never touches the wall (line ", out.getvalue())

    def test_the_template_is_not_a_listed_lesson(self) -> None:
        self.assertNotIn("template", [one.package for one in LESSONS])


class TestTheTeachingPage(unittest.TestCase):
    """Each ``$`` line of docs/teaching.md, run in a folder of the page's submissions."""

    def test_every_command_on_the_page_prints_what_the_page_shows(self) -> None:
        page = transcripts(TEACHING_PAGE.read_text("utf-8"))
        self.assertIn("$ python -m snr lesson grade 1 submissions/*.py", page)
        self.assertEqual(len(page), 2, list(page))  # and the template grader's own
        one = lesson(1)
        folder = Path(tempfile.mkdtemp(prefix="snr-teaching-"))
        before = os.getcwd()
        os.chdir(folder)
        try:
            (folder / "submissions").mkdir()
            shutil.copyfile(one.folder / "solution.py", folder / "submissions" / "ana.py")
            shutil.copyfile(one.folder / "starter.py", folder / "submissions" / "ben.py")
            (folder / "submissions" / "cleo.py").write_text(CLEO, "utf-8")
            for command, shown in page.items():
                with self.subTest(command=command):
                    words = command.split()[1:]  # after "$"
                    argv = [name for word in words for name in sorted(glob.glob(word)) or [word]]
                    out = io.StringIO()
                    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
                        if argv[:3] == ["python", "-m", "snr"]:
                            main(argv[3:])
                        elif argv[:3] == ["python", "-m", "snr.extras.lessons.template.grader"]:
                            grader.main(["grader.py", str(Path(CHECKOUT, argv[3]))])
                        else:
                            self.fail(f"the test does not know how to run {command!r}")
                    self.assertIsNone(compare(shown, out.getvalue()), command)
        finally:
            os.chdir(before)
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
