"""``python -m snr lesson``: starter files, graders by behaviour, a class's table, the page.

Each lesson's grader runs a student's file in the simulator (simulated time,
seed 1) and checks what the robot did. Here: the starter fails its grader
with checks that say why, the solution passes, a copied and renamed solution
passes too (a grade never depends on a class's name or module), several files
make one row each, ``start`` never overwrites, ``--png`` draws the graded
run's path (and says how to get pygame when it is missing), and every ``$``
line of docs/lessons.md prints what the page shows.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import tempfile
import time
import unittest
from pathlib import Path
from typing import Iterator, List, Tuple

from snr.__main__ import main
from snr.extras.lessons import LESSONS, lesson
from snr.extras.lessons.command import grade_file
from snr.prelude.install import install_hint
from tests.examples_support import ROOT as CHECKOUT
from tests.helpers import no_pygame
from tests.optional import needs
from tests.tutorial_transcripts import compare, transcripts

LESSONS_PAGE = Path(CHECKOUT, "docs", "lessons.md")
ENDPOINT_LESSONS = [one for one in LESSONS if one.number not in (5, 6, 7)]
"""The lessons whose file is an endpoint (5 to 7: tests/test_lesson_assignments.py)."""

BROKEN = '''"""A submission that raises in its handler."""
from snr import Endpoint, TaskType


class Crash(Endpoint):
    def __init__(self, factory, parent):
        super().__init__(factory, parent, "crash")
        self.task_handlers = {(TaskType.store_page, "range"): self.steer}

    def steer(self, task, key):
        return 1 / 0
'''
"""A student's file whose range handler divides by zero (line 11)."""


def snr(*argv: str) -> Tuple[int, str]:
    """Run ``python -m snr ARGV`` in this process: its exit status and what it printed."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        code = main(list(argv))
    return code, out.getvalue()


@contextlib.contextmanager
def in_temp_folder() -> Iterator[Path]:
    """A fresh folder, made the current one for the block, then removed."""
    folder = Path(tempfile.mkdtemp(prefix="snr-lesson-"))
    before = os.getcwd()
    os.chdir(folder)
    try:
        yield folder
    finally:
        os.chdir(before)
        shutil.rmtree(folder, ignore_errors=True)


def line_of(path: Path, text: str) -> int:
    """The number of the first line of ``path`` that contains ``text``."""
    for number, line in enumerate(path.read_text("utf-8").splitlines(), start=1):
        if text in line:
            return number
    raise AssertionError(f"{text!r} is not in {path}")


class TestStarterAndSolution(unittest.TestCase):
    def test_each_starter_fails_with_readable_checks_and_each_solution_passes(self) -> None:
        for one in (lesson(1), lesson(2), lesson(3)):  # the robot's; test_lesson_filter.py: 4
            with self.subTest(lesson=one.number):
                started = time.monotonic()
                checks = grade_file(one, one.folder / "solution.py")
                self.assertLess(time.monotonic() - started, 5.0, "a grade takes under 5 s")
                self.assertTrue(all(check.passed for check in checks), checks)
                checks = grade_file(one, one.folder / "starter.py")
                failed = [check for check in checks if not check.passed]
                self.assertTrue(failed, "the starter passed: it holds the answer")
                self.assertTrue(checks[0].passed, "the starter's endpoint is found")
                steer = line_of(one.folder / "starter.py", "def steer(")
                for check in failed:  # each says what, why, and where to look
                    self.assertTrue(check.expected and check.happened and check.hint, check)
                    self.assertEqual(check.line, steer, check)
                self.assertIn("touches", failed[0].name)
                self.assertIn("the bumper was pressed at", failed[0].happened)

    def test_the_starter_runs_as_the_student_runs_it(self) -> None:
        code, out = snr("lesson", "list")  # (the module imports cleanly too)
        self.assertEqual(code, 0)
        for one in LESSONS:
            text = (one.folder / "starter.py").read_text("utf-8")
            self.assertIn("TODO", text)
            self.assertIn(f"python -m snr lesson grade {one.number}", text)
            self.assertIn(f"{one.number}  {one.title}", out.splitlines())


class TestGradedByBehaviour(unittest.TestCase):
    def test_a_copied_and_renamed_solution_passes(self) -> None:
        with in_temp_folder() as folder:
            for one in ENDPOINT_LESSONS:
                with self.subTest(lesson=one.number):
                    text = (one.folder / "solution.py").read_text("utf-8")
                    for old in ("WallFollower", "GoToGoal", "ScanFollower", "DepthFilter"):
                        text = text.replace(old, "MyRobot")
                    copy = folder / f"lesson{one.number}_my_robot.py"
                    copy.write_text(text, "utf-8")
                    code, out = snr("lesson", "grade", str(one.number), copy.name)
                    self.assertEqual(code, 0, out)
                    self.assertIn("MyRobotEndpoint handles", out)
                    self.assertTrue(out.splitlines()[-1].startswith("All "), out)

    def test_a_file_without_an_endpoint_is_told_what_to_write(self) -> None:
        with in_temp_folder() as folder:
            (folder / "empty.py").write_text("SPEED = 1\n", "utf-8")
            code, out = snr("lesson", "grade", "1", "empty.py")
        self.assertEqual(code, 1)
        self.assertIn("FAILED  loads, with an endpoint", out)
        self.assertIn("empty.py: no endpoint found", out)
        self.assertIn("extends snr.Endpoint and handles the 'range', 'bump' pages", out)

    def test_a_syntax_error_names_the_line(self) -> None:
        with in_temp_folder() as folder:
            (folder / "typo.py").write_text("x = 1\ndef f(:\n", "utf-8")
            code, out = snr("lesson", "grade", "2", "typo.py")
        self.assertEqual(code, 1)
        self.assertIn("typo.py, line 2: ", out)


class TestAClassTable(unittest.TestCase):
    def test_good_starter_and_broken_files_make_one_row_each(self) -> None:
        one = lesson(1)
        with in_temp_folder() as folder:
            shutil.copyfile(one.folder / "solution.py", folder / "good.py")
            shutil.copyfile(one.folder / "starter.py", folder / "starter.py")
            (folder / "broken.py").write_text(BROKEN, "utf-8")
            started = time.monotonic()
            code, out = snr("lesson", "grade", "1", "good.py", "starter.py", "broken.py")
            took = time.monotonic() - started
        steer = line_of(one.folder / "starter.py", "def steer(")
        self.assertEqual(code, 1, "not every file passed")
        self.assertEqual(
            out.splitlines(),
            [
                f"Lesson 1, {one.title}: 3 files",
                "file        checks  result",
                "good.py     6/6     passed",
                f"starter.py  3/6     FAILED: never touches a wall (line {steer}); keeps the "
                f"wall 0.35 m away (line {steer}); goes round the room (line {steer})",
                "broken.py   1/2     FAILED: runs without an exception (line 11: "
                "ZeroDivisionError: division by zero)",
            ],
        )
        self.assertLess(took, 15.0, "three grades of 60 simulated seconds")

    def test_the_class_passes_only_when_every_file_does(self) -> None:
        one = lesson(2)
        with in_temp_folder() as folder:
            shutil.copyfile(one.folder / "solution.py", folder / "a.py")
            shutil.copyfile(one.folder / "solution.py", folder / "b.py")
            code, out = snr("lesson", "grade", "2", "a.py", "b.py")
        self.assertEqual(code, 0, out)
        self.assertEqual(out.count("5/5     passed"), 2, out)


def count_pixels(path: Path, color: Tuple[int, int, int]) -> int:
    """How many pixels of the PNG picture at ``path`` are ``color``."""
    from snr.extras.sim.draw import import_pygame  # quietly: no banner

    image = import_pygame().image.load(str(path))
    width, height = image.get_size()
    return sum(
        tuple(image.get_at((x, y)))[:3] == color for x in range(width) for y in range(height)
    )


class TestPathPicture(unittest.TestCase):
    @needs("pygame")
    def test_png_draws_the_room_and_the_graded_path(self) -> None:
        from snr.extras.sim import draw

        one = lesson(2)
        with in_temp_folder() as folder:
            code, out = snr("lesson", "grade", "2", "--solution", "--png", "pics/path.png")
            picture = folder / "pics" / "path.png"
            self.assertEqual(code, 0, out)
            self.assertIn("All 5 checks passed.", out)
            self.assertIn(f"Wrote {Path('pics', 'path.png')}: the room and the robot's path", out)
            data = picture.read_bytes()
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n")
            self.assertGreater(len(data), 1000)
            path_pixels = count_pixels(picture, draw.TRAIL)
            goal_pixels = count_pixels(picture, draw.GOAL)
            pygame = draw.import_pygame()
            world = one.module("solution").make_world()
            empty = draw.render_scene(pygame, draw.WorldView(world), world, {})
            draw.save_png(pygame, empty, folder / "empty.png")
            empty_path_pixels = count_pixels(folder / "empty.png", draw.TRAIL)
        # The path is several metres long: hundreds of pixels drawn 2 wide.
        self.assertGreater(path_pixels, 500)
        self.assertEqual(empty_path_pixels, 0)
        self.assertGreater(goal_pixels, 0)

    def test_without_pygame_png_says_how_to_install_it_and_grading_still_works(self) -> None:
        with in_temp_folder() as folder, no_pygame():
            code, out = snr("lesson", "grade", "2", "--solution", "--png", "path.png")
            self.assertEqual(code, 1, out)
            self.assertIn("--png draws with pygame, which is not installed", out)
            self.assertIn(install_hint("controller"), out)
            self.assertIn("Grading works without it: leave out --png.", out)
            self.assertFalse((folder / "path.png").exists())
            code, out = snr("lesson", "grade", "2", "--solution")
        self.assertEqual(code, 0, out)
        self.assertIn("All 5 checks passed.", out)

    def test_png_with_several_files_is_refused_with_the_command_for_one(self) -> None:
        with in_temp_folder() as folder:
            code, out = snr("lesson", "grade", "1", "a.py", "b.py", "--png", "path.png")
            self.assertFalse((folder / "path.png").exists())
        self.assertEqual(code, 2)
        self.assertEqual(
            out.strip(),
            "snr lesson grade: --png draws one run, and 2 files were given. Grade one "
            "file with --png: `python -m snr lesson grade 1 a.py --png path.png`.",
        )

    @needs("pygame")
    def test_no_picture_when_no_robot_was_driven(self) -> None:
        with in_temp_folder() as folder:
            code, out = snr("lesson", "grade", "4", "--solution", "--png", "path.png")
            self.assertFalse((folder / "path.png").exists())
        self.assertEqual(code, 1, "asked for a picture, got none")
        self.assertIn("All 5 checks passed.", out)
        self.assertIn("No picture: lesson 4's grade drives no robot in the simulator", out)


class TestStart(unittest.TestCase):
    def test_start_writes_the_starter_and_refuses_to_overwrite(self) -> None:
        with in_temp_folder() as folder:
            code, out = snr("lesson", "start", "2")
            self.assertEqual(code, 0, out)
            written = folder / "go_to_goal.py"
            self.assertEqual(
                written.read_text("utf-8"), (lesson(2).folder / "starter.py").read_text("utf-8")
            )
            self.assertIn("python -m snr lesson grade 2", out)
            written.write_text("# my work\n", "utf-8")
            code, out = snr("lesson", "start", "2")
            self.assertEqual(code, 1)
            self.assertIn("exists already; it is left as it is", out)
            self.assertEqual(written.read_text("utf-8"), "# my work\n")

    def test_grade_without_a_file_says_how_to_start(self) -> None:
        with in_temp_folder():
            code, out = snr("lesson", "grade", "1")
        self.assertEqual(code, 2)
        self.assertIn("there is no wall_follower.py here", out)
        self.assertIn("python -m snr lesson start 1", out)

    def test_an_unknown_lesson_lists_the_lessons(self) -> None:
        code, out = snr("lesson", "start", "9")
        self.assertEqual(code, 2)
        numbers = ", ".join(str(one.number) for one in LESSONS)
        self.assertIn(f"there is no lesson 9; the lessons are {numbers}", out)


class TestThePage(unittest.TestCase):
    """Each ``$`` line of docs/lessons.md, run in order in one folder, prints what is shown."""

    def test_every_command_on_the_page_prints_what_the_page_shows(self) -> None:
        page = transcripts(LESSONS_PAGE.read_text("utf-8"))
        commands: List[str] = [line for line in page if line.startswith("$ python -m snr lesson")]
        self.assertGreaterEqual(len(commands), 3, list(page))
        with in_temp_folder():
            for command in commands:
                with self.subTest(command=command):
                    argv = command.split()[4:]  # after "$ python -m snr"
                    _, out = snr(*argv)
                    self.assertIsNone(compare(page[command], out), command)

    def test_the_page_shows_list_start_and_grade(self) -> None:
        text = LESSONS_PAGE.read_text("utf-8")
        for command in ("lesson list", "lesson start 1", "lesson grade 1"):
            self.assertTrue(re.search(rf"^\$ python -m snr {command}$", text, re.M), command)


if __name__ == "__main__":
    unittest.main()
