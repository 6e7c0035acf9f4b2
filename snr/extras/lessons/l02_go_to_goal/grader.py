"""Lesson 2's grader: does the robot reach the goal, round the crate, untouched, and stop?

It runs the student's endpoint with the simulated robot for 25 s of simulated
time (seed 1) and checks the robot's true path, never the code's names:

* it runs without an exception;
* the bumper is never pressed (neither the crate nor a wall);
* it is within `REACHED_M` of the goal in under `IN_TIME_S`;
* it ends there, stopped.

Example::

    for check in grade(Path("go_to_goal.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import List

from snr.extras.lessons.grading import (
    STEP_HZ,
    Check,
    drive,
    find_endpoint,
    first_checks,
    handler_line,
    load_submission,
    touch_check,
)
from snr.extras.lessons.l02_go_to_goal.solution import make_world

__all__ = ["IN_TIME_S", "KEYS", "REACHED_M", "SECONDS", "grade"]

KEYS = ["odometry", "range"]
"""The sensor pages the endpoint handles."""
SECONDS = 25.0
"""Simulated seconds a grade runs."""
IN_TIME_S = 20.0
"""The goal must be reached in less than this."""
REACHED_M = 0.25
"""Closer than this to the goal (by the true pose) is there: odometry drifts a few cm."""


def grade(path: Path) -> List[Check]:
    """The checks of lesson 2 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no endpoint.

    Example::

        all(check.passed for check in grade(Path("go_to_goal.py")))
    """
    cls = find_endpoint(load_submission(path), KEYS)
    world = make_world()
    goal = world.goal
    assert goal is not None  # the lesson's room has one
    run, endpoint = drive(cls, world, SECONDS, path, {"goal": goal})
    steer = handler_line(endpoint, "range")
    checks = first_checks(cls, endpoint, "range", run.error)
    if run.error is not None:
        return checks
    checks.append(
        touch_check(
            run,
            "never touches the crate or a wall",
            "when something is closer than BLOCKED_M ahead, go round its edge (step 4)",
            steer,
        )
    )
    distances = [math.dist(p, goal) for p in run.path]
    reached = next((i for i, d in enumerate(distances) if d < REACHED_M), None)
    nearest = min(distances, default=math.inf)
    checks.append(
        Check(
            "reaches the goal in time",
            reached is not None and reached / STEP_HZ < IN_TIME_S,
            expected=f"within {REACHED_M} m of the goal {goal} in under {IN_TIME_S:g} s",
            happened=f"there at {reached / STEP_HZ:.1f} s"
            if reached is not None
            else f"never; {nearest:.2f} m at the nearest",
            hint="steer by HEADING_GAIN * the heading error, wrapped (steps 2 and 3)",
            line=steer,
        )
    )
    final = distances[-1] if distances else math.inf
    wheels = run.last_command or {}
    stopped = wheels.get("left") == 0.0 and wheels.get("right") == 0.0
    checks.append(
        Check(
            "stops at the goal",
            final < REACHED_M and stopped,
            expected=f"at the end, within {REACHED_M} m of the goal, wheels at 0",
            happened=f"{final:.2f} m from it, last command {wheels or 'none'}",
            hint="closer than ARRIVED_M, return self.wheels(0.0, 0.0) (step 3)",
            line=steer,
        )
    )
    return checks
