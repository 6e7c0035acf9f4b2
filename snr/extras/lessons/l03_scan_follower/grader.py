"""Lesson 3's grader: lesson 1's course and checks, the wall seen in a lidar's scan.

It runs the student's endpoint with lesson 1's room and robot, but the robot
has a lidar (``ScanSensor``, ``scan`` pages) and no range sensor: no
``range`` page is ever stored. 60 s of simulated time, seed 1, and checks of
the robot's true path, never the code's names:

* it runs without an exception;
* it is a drop-in: it handles no ``range`` page (lesson 1's ready-made
  rays), so a copy of lesson 1's solution fails here, and says why;
* it answers (nearly) every ``scan`` page with a wheel command;
* lesson 1's checks (`course_checks`), the same: the bumper is never
  pressed, the wall stays `TARGET_M` away within `MARGIN_M` after the first
  second, and it drives round the room, round the divider's end.

Example::

    for check in grade(Path("scan_follower.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional, Type

from snr import Endpoint
from snr.extras.lessons.grading import (
    STEP_HZ,
    Check,
    drive,
    find_endpoint,
    first_checks,
    handler_line,
    load_submission,
)
from snr.extras.lessons.l01_wall_follower.grader import MARGIN_M, SECONDS, TARGET_M, course_checks
from snr.extras.lessons.l03_scan_follower.solution import ROBOT, make_world

__all__ = ["HINTS", "KEYS", "MARGIN_M", "SECONDS", "TARGET_M", "drop_in_check", "grade"]

KEYS = ["scan", "bump"]
"""The sensor pages the endpoint handles."""
HINTS = {
    "touch": "turn left on the spot when the nearest echo ahead (AHEAD_DEG) is closer "
    "than FRONT_CLEAR_M (step 4)",
    "wall": "the wall's distance is the nearest echo in RIGHT_DEG, skipping 0.0 (no echo), "
    "less LOOK_AHEAD_M * sin(its angle + 90 degrees) (steps 2 and 3)",
    "round": "look for the wall behind the robot too (RIGHT_DEG from -180): round the "
    "divider's end, the end stays the nearest echo (step 3)",
}
"""Lesson 3's hints for lesson 1's `course_checks`, by check."""


def grade(path: Path) -> List[Check]:
    """The checks of lesson 3 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no endpoint.

    Example::

        all(check.passed for check in grade(Path("scan_follower.py")))
    """
    cls = find_endpoint(load_submission(path), KEYS)
    world = make_world()
    run, endpoint = drive(cls, world, SECONDS, path, robot=ROBOT)
    steer = handler_line(endpoint, "scan")
    checks = first_checks(cls, endpoint, "scan", run.error)
    if run.error is not None:
        return checks
    checks.append(drop_in_check(cls, endpoint))
    if not checks[-1].passed:
        return checks  # lesson 1's endpoint: nothing else is worth reading until this is fixed
    steps_per_scan = round(STEP_HZ / ROBOT["scan_sensor"].rate_hz)
    scans = (len(run.path) + steps_per_scan - 1) // steps_per_scan
    checks.append(
        Check(
            "steers every scan",
            run.commands >= 0.95 * scans,
            expected=f"a wheel_cmd for each of the {scans} scan pages",
            happened=f"{run.commands} wheel commands",
            hint="return self.wheels(left, right) from the scan handler, every time",
            line=steer,
        )
    )
    return checks + course_checks(world, run, steer, HINTS)


def drop_in_check(cls: Type[Endpoint], endpoint: Optional[Endpoint]) -> Check:
    """The check that the endpoint is a drop-in for lesson 1's: it handles no ``range`` page.

    Example::

        drop_in_check(ScanFollowerEndpoint, endpoint).passed    # True
    """
    handlers = endpoint.task_handlers if endpoint is not None else {}
    reads_range = any(isinstance(task_id, tuple) and task_id[1] == "range" for task_id in handlers)
    if reads_range:
        happened = (
            f"{cls.__name__} handles 'range' pages, lesson 1's ready-made rays; this robot "
            "has a lidar and no range sensor, so that handler never ran"
        )
    else:
        happened = f"{cls.__name__} handles no 'range' page"
    return Check(
        "a drop-in: sees by the scan, not lesson 1's range rays",
        not reads_range,
        expected="the wall found in the 'scan' pages, the robot's only sensor of walls",
        happened=happened,
        hint="a copy of lesson 1's endpoint will not do: handle 'scan' instead of 'range', "
        "and find the wall in its rays with nearest_echo (steps 1 and 2)",
        line=handler_line(endpoint, "range"),
    )
