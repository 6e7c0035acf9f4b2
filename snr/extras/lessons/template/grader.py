"""The template lesson's grader: does the robot stop `STOP_M` from the wall, untouched?

It runs the student's endpoint with the simulated robot for `SECONDS` of
simulated time (seed 1, a fraction of a second of computer time) and checks
the robot's true path, never the code's names:

* the endpoint handles ``range`` pages, and runs without an exception;
* the bumper is never pressed;
* it ends `STOP_M` from the wall ahead, within `MARGIN_M`;
* it ends stopped: its last wheel command is (nearly) zero.

A lesson in `snr.extras.lessons.LESSONS` is graded by ``python -m snr lesson
grade N``; this one is not listed, so this module grades a file itself::

    python -m snr.extras.lessons.template.grader stop_at_wall.py

Example::

    for check in grade(Path("stop_at_wall.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import List

from snr.extras.lessons.grading import (
    Check,
    SubmissionError,
    drive,
    find_endpoint,
    first_checks,
    handler_line,
    load_submission,
    touch_check,
)
from snr.extras.lessons.template.solution import STOP_M, make_world

__all__ = ["KEYS", "MARGIN_M", "SECONDS", "STILL_M_S", "grade", "main"]

KEYS = ["range"]
"""The sensor pages the endpoint handles."""
SECONDS = 15.0
"""Simulated seconds a grade runs: time to get there, and to settle."""
MARGIN_M = 0.05
"""How far from `STOP_M` the robot may stop (0.45 m to 0.55 m from the wall)."""
STILL_M_S = 0.02
"""A wheel command slower than this, both wheels, is stopped."""


def grade(path: Path) -> List[Check]:
    """The template lesson's checks for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no endpoint.

    Example::

        all(check.passed for check in grade(Path("stop_at_wall.py")))
    """
    # 1. Load the file by its path, find its endpoint by what it handles.
    cls = find_endpoint(load_submission(path), KEYS)
    # 2. Run it with the simulated robot, in simulated time, seed 1.
    world = make_world()
    run, endpoint = drive(cls, world, SECONDS, path)
    steer = handler_line(endpoint, "range")  # the line every failed check points at
    checks = first_checks(cls, endpoint, "range", run.error)
    if run.error is not None:
        return checks
    # 3. Turn what happened into checks: expected, happened, a hint, a line.
    checks.append(
        touch_check(
            run,
            "never touches the wall",
            "slow down as the wall comes closer: speed GAIN * (ahead - STOP_M) (step 2)",
            steer,
        )
    )
    x, y = run.path[-1] if run.path else world.start[:2]
    ahead = world.ray_hit_m(x, y, 0.0, 5.0)  # the robot faces east all the way
    checks.append(
        Check(
            f"stops {STOP_M} m from the wall",
            abs(ahead - STOP_M) <= MARGIN_M,
            expected=f"the wall ahead {STOP_M - MARGIN_M:.2f} m to {STOP_M + MARGIN_M:.2f} m "
            f"away after {SECONDS:g} s",
            happened=f"{ahead:.2f} m, at ({x:.2f}, {y:.2f})",
            hint="the error is the ray straight ahead minus STOP_M (step 1)",
            line=steer,
        )
    )
    last = run.last_command or {}
    speeds = [abs(float(last.get(wheel, 0.0))) for wheel in ("left", "right")]
    checks.append(
        Check(
            "ends stopped",
            bool(last) and max(speeds) < STILL_M_S,
            expected=f"a last wheel command under {STILL_M_S} m/s, both wheels",
            happened=(
                f"the last wheel command: left {speeds[0]:.3f} m/s, right {speeds[1]:.3f} m/s"
                if last
                else "no wheel command at all"
            ),
            hint="at STOP_M the error is zero, and so is the speed (step 2)",
            line=steer,
        )
    )
    return checks


def main(argv: List[str]) -> int:
    """``python -m snr.extras.lessons.template.grader FILE``: each check; 0 if all passed.

    Example::

        main(["grader.py", "stop_at_wall.py"])
    """
    if len(argv) != 2:
        print(f"usage: python -m snr.extras.lessons.template.grader FILE (not {argv[1:]})")
        return 2
    try:
        checks = grade(Path(argv[1]))
    except SubmissionError as error:
        print(f"FAILED  loads, with an endpoint: {error}")
        return 1
    for check in checks:
        line = f" (line {check.line})" if check.line and not check.passed else ""
        said = f": {check.happened}" if check.happened else ""
        print(f"{'passed' if check.passed else 'FAILED'}  {check.name}{line}{said}")
        if not check.passed:
            print(f"        expected: {check.expected}; hint: {check.hint}")
    return 0 if all(check.passed for check in checks) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
