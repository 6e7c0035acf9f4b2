"""``python -m snr lesson``: list the lessons, start one, grade your file.

Found by the kernel's ``snr.commands`` entry point; ``snr/__main__.py`` makes
the ``lesson`` parser and this module adds its options and runs it::

    python -m snr lesson list              # each lesson's number and title
    python -m snr lesson start 1           # writes wall_follower.py here
    python -m snr lesson grade 1           # grades it: each check, in words
    python -m snr lesson grade 1 a.py b.py # a class's files: one row each
    python -m snr lesson grade 1 --solution
    python -m snr lesson grade 1 --png path.png  # and a picture of the robot's path

A grade runs the file's endpoint in the simulator, in simulated time with a
fixed seed, and checks what the robot did (``grading``); the exit status is 0
only when every check of every file passed.

Example::

    run(argparse.Namespace(action="list"))
"""

from __future__ import annotations

import argparse
import math
import shutil
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from snr import World
from snr.extras.lessons import LESSONS, Lesson, lesson
from snr.extras.lessons.grading import Check, Drive, SubmissionError, kept_drives

__all__ = ["add_arguments", "grade_file", "run", "save_path_png"]

DESCRIPTION = (
    "The course's lessons, each a robot to program in the simulator: 'list' shows them, "
    "'start N' writes lesson N's starter file into this folder, 'grade N' runs your file "
    "in the simulator and says, check by check, what the robot did and what it should."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``lesson``'s actions and options to its parser (``snr/__main__.py`` made it).

    Example::

        add_arguments(argparse.ArgumentParser(prog="snr lesson"))
    """
    parser.description = DESCRIPTION
    actions = parser.add_subparsers(dest="action", metavar="ACTION", title="actions")
    actions.required = True
    actions.add_parser(
        "list", help="each lesson's number and title", description="List the lessons."
    )
    start = actions.add_parser(
        "start",
        help="write lesson N's starter file into this folder",
        description="Write lesson N's starter file into the current folder (never over "
        "a file that is there) and say how to run and grade it.",
    )
    start.add_argument("number", metavar="N", type=int, help="the lesson's number")
    grade = actions.add_parser(
        "grade",
        help="grade your file (or several) for lesson N, in the simulator",
        description="Run each FILE's endpoint in the simulator (simulated time, seed 1) "
        "and check what the robot did. One file: each check, passed or failed, with "
        "what was expected, what happened and a hint. Several: one row per file.",
    )
    grade.add_argument("number", metavar="N", type=int, help="the lesson's number")
    grade.add_argument(
        "files",
        metavar="FILE",
        nargs="*",
        help="the files to grade (default: the one 'lesson start N' wrote)",
    )
    grade.add_argument(
        "--solution", action="store_true", help="grade the lesson's reference solution"
    )
    grade.add_argument(
        "--png",
        metavar="PATH",
        help="also draw the room and the robot's path in the graded run into PATH "
        "(one file only; needs pygame)",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``python -m snr lesson ACTION ...``; the exit status.

    Example::

        run(argparse.Namespace(action="start", number=1))
    """
    if args.action == "list":
        for one in LESSONS:
            print(f"{one.number}  {one.title}")
        return 0
    try:
        chosen = lesson(args.number)
    except KeyError as error:
        print(f"snr lesson: {error.args[0]} (`python -m snr lesson list` shows them).")
        return 2
    if args.action == "start":
        return _start(chosen, Path.cwd())
    return _grade(chosen, args.files, args.solution, getattr(args, "png", None))


def grade_file(chosen: Lesson, path: Path) -> List[Check]:
    """The checks of ``chosen``'s grader for the file at ``path``; never raises for the file.

    A file that cannot be loaded, or has no endpoint, gets one failed check
    that says why.

    Example::

        grade_file(lesson(1), Path("wall_follower.py"))
    """
    try:
        checks: List[Check] = chosen.module("grader").grade(path)
    except SubmissionError as error:
        return [Check("loads, with an endpoint", False, happened=str(error))]
    return checks


def _start(chosen: Lesson, folder: Path) -> int:
    target = folder / chosen.file_name
    if target.exists():
        print(
            f"snr lesson start: {target} exists already; it is left as it is. Grade it "
            f"with `python -m snr lesson grade {chosen.number}`, or move it away to start "
            "afresh."
        )
        return 1
    shutil.copyfile(chosen.folder / "starter.py", target)
    print(f"Wrote {chosen.file_name}: lesson {chosen.number}, {chosen.title}.")
    print(f"Read the lesson: docs/lessons.md#{chosen.anchor} (or `python -m snr docs`).")
    print("Write the TODOs in it; run it with:")
    print(f"    python {chosen.file_name} --seconds 30")
    print("and grade it with:")
    print(f"    python -m snr lesson grade {chosen.number}")
    return 0


def save_path_png(world: World, run: Drive, target: Path) -> Path:
    """Draw ``world`` and the path of ``run`` into the PNG file ``target``; returns it.

    Walls in black, the goal (if any) as a green ring, the path in blue, a red
    dot wherever the bumper was pressed, and the robot where the run ended
    (red if pressed there).
    Drawn off-screen: no window, no display needed.

    Raises:
        snr.ComponentError: pygame is not installed (the message says how to get it).

    Example::

        with kept_drives() as drives:
            grade_file(lesson(1), Path("wall_follower.py"))
        save_path_png(*drives[-1], Path("path.png"))
    """
    from snr.extras.sim import draw  # pygame, only when a picture is asked for
    from snr.extras.sim.sensors import BUMP, TRUE_POSE

    pygame = draw.import_pygame()
    view = draw.WorldView(world)
    pages: Dict[str, Any] = {}
    if run.path:
        (x0, y0), (x, y) = run.path[max(0, len(run.path) - 5)], run.path[-1]
        pages[TRUE_POSE] = {"x": x, "y": y, "theta": math.atan2(y - y0, x - x0)}
        # Red, as in the simulator's window, if it ended pressed against something.
        pages[BUMP] = bool(run.bumps) and run.bumps[-1] >= len(run.path) - 1
    surface = draw.render_scene(pygame, view, world, pages, trail=run.path, trail_px=2)
    for step in run.bumps:
        pressed_at = view.to_px(*run.path[max(0, step - 1)])
        pygame.draw.circle(surface, draw.BUMPED, pressed_at, 3)
    return draw.save_png(pygame, surface, target)


def _grade(chosen: Lesson, files: Sequence[str], solution: bool, png: Optional[str]) -> int:
    paths = [Path(name) for name in files]
    if solution:
        paths.append(chosen.folder / "solution.py")
    if not paths:
        default = Path(chosen.file_name)
        if not default.exists():
            print(
                f"snr lesson grade: there is no {chosen.file_name} here. "
                f"`python -m snr lesson start {chosen.number}` writes it; or name your "
                f"file: `python -m snr lesson grade {chosen.number} FILE`."
            )
            return 2
        paths = [default]
    if png is not None and len(paths) > 1:
        print(
            f"snr lesson grade: --png draws one run, and {len(paths)} files were given. "
            f"Grade one file with --png: `python -m snr lesson grade {chosen.number} "
            f"{paths[0]} --png {png}`."
        )
        return 2
    if png is not None:
        from snr.extras.sim.draw import INSTALL_HINT, pygame_installed

        if not pygame_installed():
            print(
                f"snr lesson grade: --png draws with pygame, which is not installed. "
                f"{INSTALL_HINT}. Grading works without it: leave out --png."
            )
            return 1
    with kept_drives() as drives:
        results = [(path, grade_file(chosen, path)) for path in paths]
    if len(results) == 1:
        _print_checks(chosen, *results[0])
    else:
        _print_table(chosen, results)
    passed = all(check.passed for _, checks in results for check in checks)
    if png is not None:
        drew = _save_png(chosen, results[0][1], drives, Path(png))
        return 0 if passed and drew else 1
    return 0 if passed else 1


def _save_png(
    chosen: Lesson, checks: List[Check], drives: List[Tuple[World, Drive]], target: Path
) -> bool:
    """Draw the graded run's path into ``target``, saying where; False if there was no run."""
    if not drives:
        if checks and checks[0].name == "loads, with an endpoint":
            why = "the file did not run (see the check above)"
        else:
            why = f"lesson {chosen.number}'s grade drives no robot in the simulator"
        print(f"No picture: {why}, so there is no path to draw; {target} was not written.")
        return False
    world, run = drives[-1]
    written = save_path_png(world, run, target)
    print(
        f"Wrote {written}: the room and the robot's path over the graded run "
        "(blue; red dots where the bumper was pressed)."
    )
    return True


def _print_checks(chosen: Lesson, path: Path, checks: List[Check]) -> None:
    print(f"Lesson {chosen.number}, {chosen.title}: grading {path}")
    for check in checks:
        where = f" (line {check.line})" if check.line and not check.passed else ""
        if check.passed:
            said = f": {check.happened}" if check.happened else ""
            print(f"  passed  {check.name}{said}")
            continue
        print(f"  FAILED  {check.name}{where}")
        for label, words in (
            ("expected", check.expected),
            ("happened", check.happened),
            ("hint", check.hint),
        ):
            if words:
                print(f"          {label + ':':9} {words}")
    passed = sum(check.passed for check in checks)
    if passed == len(checks):
        print(f"All {len(checks)} checks passed.")
    else:
        print(f"{passed} of {len(checks)} checks passed: fix the first FAILED one, grade again.")


def _print_table(chosen: Lesson, results: List[Tuple[Path, List[Check]]]) -> None:
    print(f"Lesson {chosen.number}, {chosen.title}: {len(results)} files")
    width = max(len("file"), *(len(str(path)) for path, _ in results))
    print(f"{'file':{width}}  checks  result")
    for path, checks in results:
        passed = sum(check.passed for check in checks)
        failed = [_short(check) for check in checks if not check.passed]
        result = "passed" if not failed else "FAILED: " + "; ".join(failed)
        print(f"{path!s:{width}}  {passed}/{len(checks):<5} {result}")


def _short(check: Check) -> str:
    """A failed check in a few words, with the line, for a table's row."""
    where = f"line {check.line}: " if check.line else ""
    if check.name in ("runs without an exception", "loads, with an endpoint"):
        return f"{check.name} ({where}{check.happened.split(', ')[0]})"
    return check.name + (f" (line {check.line})" if check.line else "")
