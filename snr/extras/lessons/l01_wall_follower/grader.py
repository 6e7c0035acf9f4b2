"""Lesson 1's grader: does the robot follow the wall, all round the room, untouched?

It runs the student's endpoint with the simulated robot for 60 s of simulated
time (seed 1, a second or so of computer time) and checks the robot's true
path, never the code's names:

* it runs without an exception, and answers (nearly) every ``range`` page;
* the bumper is never pressed;
* from the first second on, the wall is `TARGET_M` away, within `MARGIN_M`;
* it drives round the room: more than 12 m, and round the divider's end.

Example::

    for check in grade(Path("wall_follower.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

from pathlib import Path
from typing import Dict, List, Optional

from snr.extras.lessons.grading import (
    STEP_HZ,
    Check,
    Drive,
    drive,
    find_endpoint,
    first_checks,
    handler_line,
    load_submission,
    touch_check,
)
from snr.extras.lessons.l01_wall_follower.solution import make_world
from snr.extras.sim import World

__all__ = ["HINTS", "KEYS", "MARGIN_M", "SECONDS", "TARGET_M", "course_checks", "grade"]

KEYS = ["range", "bump"]
"""The sensor pages the endpoint handles."""
SECONDS = 60.0
"""Simulated seconds a grade runs: once round the room."""
TARGET_M = 0.35
"""Where the wall should be, from the robot's centre."""
MARGIN_M = 0.16
"""How far from `TARGET_M` the wall may be, after the first second (0.19 m to 0.51 m)."""
HINTS = {
    "touch": "turn left on the spot when the wall ahead is closer than FRONT_CLEAR_M (step 4)",
    "wall": "steer by GAIN * (TARGET_M - wall distance), the distance from the rays "
    "at -90 and -45 degrees (steps 2 and 3)",
    "round": "where the wall ends the side ray sees far: the turn is the limit, right",
}
"""Lesson 1's hints for `course_checks`, by check."""


def grade(path: Path) -> List[Check]:
    """The checks of lesson 1 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no endpoint.

    Example::

        all(check.passed for check in grade(Path("wall_follower.py")))
    """
    cls = find_endpoint(load_submission(path), KEYS)
    world = make_world()
    run, endpoint = drive(cls, world, SECONDS, path)
    steer = handler_line(endpoint, "range")
    checks = first_checks(cls, endpoint, "range", run.error)
    if run.error is not None:
        return checks
    steps = len(run.path)
    checks.append(
        Check(
            "steers every step",
            run.commands >= 0.95 * steps,
            expected=f"a wheel_cmd for each of the {steps} range pages",
            happened=f"{run.commands} wheel commands",
            hint="return self.wheels(left, right) from the range handler, every time",
            line=steer,
        )
    )
    return checks + course_checks(world, run, steer, HINTS)


def course_checks(
    world: World, run: Drive, line: Optional[int], hints: Dict[str, str]
) -> List[Check]:
    """The checks of the course itself: never touches, keeps the wall, goes round the room.

    Lesson 3's perception-based follower is graded on the same course by
    these same checks; ``hints`` (keys ``touch``, ``wall``, ``round``) point
    at the steps of the lesson at hand, ``line`` at the student's handler.

    Example::

        checks += course_checks(world, run, steer_line, HINTS)
    """
    checks = [touch_check(run, "never touches a wall", hints["touch"], line)]
    clearances = [world.clearance_m(x, y) for x, y in run.path[STEP_HZ:]]  # after 1 s
    low, high = TARGET_M - MARGIN_M, TARGET_M + MARGIN_M
    if clearances:
        nearest, farthest = min(clearances), max(clearances)
        worst = max(clearances, key=lambda c: abs(c - TARGET_M))
        at = run.path[STEP_HZ + clearances.index(worst)]
        happened = (
            f"from {nearest:.2f} m to {farthest:.2f} m; the worst, {worst:.2f} m, "
            f"at ({at[0]:.2f}, {at[1]:.2f})"
        )
    else:
        nearest, farthest, happened = 0.0, 0.0, "the robot never moved"
    checks.append(
        Check(
            f"keeps the wall {TARGET_M} m away",
            bool(clearances) and low <= nearest and farthest <= high,
            expected=f"the nearest wall {low:.2f} m to {high:.2f} m from the robot, after 1 s",
            happened=happened,
            hint=hints["wall"],
            line=line,
        )
    )
    length = run.length_m()
    east = max((x for x, _ in run.path), default=0.0)
    checks.append(
        Check(
            "goes round the room",
            length > 12.0 and east > 3.4,
            expected="more than 12 m, round the divider's end (x beyond 3.4 m)",
            happened=f"{length:.1f} m, as far east as x = {east:.2f} m",
            hint=hints["round"],
            line=line,
        )
    )
    return checks
