"""Lesson 3: a perception-based controller (docs/lessons.md), the reference solution.

Lesson 1's robot and room, with one change: the five ready-made range rays
are gone, and a lidar (`ScanSensor`) is there instead. Its ``scan`` page is
raw, 72 noisy rays all round, 10 a second, some with no echo; no ray points
exactly to the side. `ScanFollowerEndpoint` finds the wall in it
(*perception*: `nearest_echo`), and hands the distance to lesson 1's
proportional controller, unchanged. It stores the same ``wheel_cmd`` pages
as lesson 1's endpoint, so it drops in where that one was: the thesis's
"perception based controller as a drop-in replacement" (8.3.1).

Run it (a window if you have a screen, else PNG frames; as lesson 1)::

    python -m snr.extras.lessons.l03_scan_follower.solution --seconds 30
    python -m snr.extras.lessons.l03_scan_follower.solution --seconds 60 --speed 0

``python -m snr lesson start 3`` writes the lesson's starter file into your
folder, and ``python -m snr lesson grade 3`` grades it.
"""

from __future__ import annotations

import math
import sys
from typing import Any, Dict, List, Optional, Tuple

import snr
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.lessons.l01_wall_follower import solution as lesson_1
from snr.extras.lessons.l01_wall_follower.solution import make_world
from snr.extras.sim import ScanSensor

__all__ = [
    "ROBOT",
    "ScanFollowerEndpoint",
    "ScanFollowerFactory",
    "main",
    "make_world",
    "nearest_echo",
]

ROBOT: Dict[str, Any] = {"range_sensor": False, "scan_sensor": ScanSensor()}
"""Lesson 3's robot: no range rays, a lidar instead (the arguments of its `SimRobotFactory`)."""

TARGET_M = 0.35
"""How far from the robot's centre the wall on its right should be."""
CRUISE_M_S = 0.25
"""Forward speed along the wall."""
GAIN = 1.0
"""Steering per metre of error: 0.1 m too far from the wall turns by 0.1 m/s."""
MAX_TURN_M_S = 0.15
"""The most steering: half the difference between the two wheels' speeds."""
FRONT_CLEAR_M = 0.45
"""A wall closer than this ahead is a corner: turn left on the spot."""
SPIN_M_S = 0.2
"""Wheel speed while turning on the spot."""
RIGHT_DEG = (-180.0, -45.0)
"""Where to look for the wall on the right: the rays between these angles (behind it too,
so that going round the end of a wall the robot keeps the end in sight)."""
LOOK_AHEAD_M = 0.3
"""Steer by the wall's distance this far ahead, as its angle says it will be."""
AHEAD_DEG = (-25.0, 25.0)
"""Where to look for a wall ahead: the rays between these angles."""


def nearest_echo(scan: Dict[str, Any], from_deg: float, to_deg: float) -> Tuple[float, float]:
    """The nearest thing the scan saw between two angles: (distance in m, its angle in degrees).

    Rays that got no echo read 0.0 and are skipped. The nearest point of a
    straight wall is where a line at right angles from the robot meets it:
    its distance is the wall's distance, and its angle says which way the
    wall runs (-90: parallel to the robot, on its right; more than -90: the
    robot heads into it). Nothing seen: ``(math.inf, nan)``.

    Example::

        scan = {"angles_deg": [-97.5, -92.5, -87.5], "ranges_m": [0.36, 0.0, 0.351]}
        nearest_echo(scan, -135, -45)    # (0.351, -87.5): the 0.0 was no echo
    """
    best = (math.inf, math.nan)
    for angle, distance in zip(scan["angles_deg"], scan["ranges_m"]):
        if from_deg <= angle <= to_deg and 0.0 < distance < best[0]:
            best = (distance, angle)
    return best


class ScanFollowerEndpoint(Endpoint):
    """Keeps a wall on the robot's right, `TARGET_M` away, seen by a lidar; turns left at corners.

    It reads the ``scan`` and ``bump`` pages and stores ``wheel_cmd``, as
    lesson 1's endpoint does from ``range`` pages.

    Example (a scan page in, a wheel command out)::

        {"angles_deg": [-177.5, ..., 177.5], "ranges_m": [..., 0.45, 0.0, 0.46, ...]}
        -> {"left": 0.35, "right": 0.15}     # the wall 0.45 m away: 0.1 m too far
    """

    def __init__(self, factory: ScanFollowerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "scan_follower")
        self.task_handlers = {
            (TaskType.store_page, "scan"): self.steer,
            (TaskType.store_page, "bump"): self.feel,
        }
        self.bumped = False

    def feel(self, task: Task, key: TaskId) -> SomeTasks:
        """Remember whether the bumper is pressed; `steer` backs away if so."""
        self.bumped = bool(task.val_list[0].data)
        return None

    def steer(self, task: Task, key: TaskId) -> SomeTasks:
        """One wheel command for one scan."""
        scan = task.val_list[0].data
        # Perception: the scan -> where the wall is (and whether one is ahead).
        wall_m, angle_deg = nearest_echo(scan, *RIGHT_DEG)
        if wall_m < math.inf:
            # The nearest echo at -90 degrees: the robot runs along the wall. At
            # -80 it heads 10 degrees into it, and LOOK_AHEAD_M further on the wall
            # will be LOOK_AHEAD_M * sin(10 degrees) closer: steer by that distance.
            wall_m -= LOOK_AHEAD_M * math.sin(math.radians(angle_deg + 90.0))
        ahead_m, _ = nearest_echo(scan, *AHEAD_DEG)
        # Control: lesson 1's proportional controller, as it was.
        if self.bumped:
            return self.wheels(-0.1, 0.0)
        if ahead_m < FRONT_CLEAR_M:
            return self.wheels(-SPIN_M_S, SPIN_M_S)
        error = TARGET_M - wall_m  # > 0: too close to the wall
        turn = max(-MAX_TURN_M_S, min(MAX_TURN_M_S, GAIN * error))  # > 0: turn left
        return self.wheels(CRUISE_M_S - turn, CRUISE_M_S + turn)

    def wheels(self, left_m_s: float, right_m_s: float) -> SomeTasks:
        """The task that stores a wheel command."""
        return self.store_data_task("wheel_cmd", {"left": left_m_s, "right": right_m_s})


class ScanFollowerFactory(EndpointFactory):
    """Builds a `ScanFollowerEndpoint`.

    Example::

        ScanFollowerFactory()
    """

    def __init__(self, name: Optional[str] = None) -> None:
        super().__init__()
        self.name = name or "scan_follower"

    def get(self, parent: AbstractNode) -> ScanFollowerEndpoint:
        return ScanFollowerEndpoint(self, parent)


def main(argv: List[str], brain: Optional[snr.AbstractFactory] = None) -> None:
    """``python scan_follower.py [--seconds S] [--frames DIR] [--seed N] [--speed X]``.

    Lesson 1's runner (its room, its view, its options), with `ROBOT`, the
    robot with a lidar. ``brain``: the endpoint's factory that drives it
    (this file's by default; the starter file passes its own).

    Example::

        main(["scan_follower.py", "--seconds", "60", "--speed", "0"])
    """
    title = "Lesson 3: lesson 1's wall follower, seeing by lidar."
    lesson_1.main(argv, brain or ScanFollowerFactory(), ROBOT, title)


if __name__ == "__main__":
    main(sys.argv)
