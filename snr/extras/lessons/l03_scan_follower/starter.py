"""Lesson 3: a perception-based controller: your file (docs/lessons.md, "Lesson 3").

Lesson 1's room and robot, with one change: the five range rays are gone, and
a lidar is there instead. Each ``scan`` page holds 72 rays all round, 10 a
second, each a little noisy, some reading 0.0 (no echo), none pointing
exactly to the side. Find the wall in the scan (`nearest_echo`, and the
TODOs in `steer`); lesson 1's proportional controller, below them, does the
rest. As it is, the robot sees nothing and drives straight on, into the
divider.

Run it, and grade it::

    python scan_follower.py --seconds 30 --speed 0     # as fast as it goes
    python -m snr lesson grade 3

The room, the robot and the runner are the lesson's (``make_world`` and
``main``); your part is the perception below.
"""

from __future__ import annotations

import math
import sys
from typing import Any, Dict, Tuple

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.lessons.l03_scan_follower.solution import main, make_world

__all__ = ["ScanFollowerEndpoint", "ScanFollowerFactory", "make_world", "nearest_echo"]

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
"""Where to look for the wall on the right: the rays between these angles (behind it too)."""
LOOK_AHEAD_M = 0.3
"""Steer by the wall's distance this far ahead, as its angle says it will be."""
AHEAD_DEG = (-25.0, 25.0)
"""Where to look for a wall ahead: the rays between these angles."""


def nearest_echo(scan: Dict[str, Any], from_deg: float, to_deg: float) -> Tuple[float, float]:
    """The nearest thing the scan saw between two angles: (distance in m, its angle in degrees).

    Example::

        scan = {"angles_deg": [-97.5, -92.5, -87.5], "ranges_m": [0.36, 0.0, 0.351]}
        nearest_echo(scan, -135, -45)    # (0.351, -87.5): the 0.0 was no echo
    """
    # TODO (step 2): go through zip(scan["angles_deg"], scan["ranges_m"]) and keep
    #                the shortest distance, and its angle, of the rays between
    #                from_deg and to_deg; skip 0.0, which means "no echo".
    return math.inf, math.nan  # for now: nothing seen


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
        scan = task.val_list[0].data  # noqa: F841 (not used yet)
        # Perception: the scan -> where the wall is (and whether one is ahead).
        # TODO (step 3): the wall's distance and angle, nearest_echo(scan, *RIGHT_DEG);
        #                then the distance LOOK_AHEAD_M ahead: less
        #                LOOK_AHEAD_M * math.sin(math.radians(angle + 90)).
        wall_m = TARGET_M  # for now: the wall is always where it should be
        # TODO (step 4): the nearest echo ahead, in AHEAD_DEG.
        ahead_m = math.inf  # for now: nothing ahead
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

    def get(self, parent: AbstractNode) -> ScanFollowerEndpoint:
        return ScanFollowerEndpoint(self, parent)


if __name__ == "__main__":
    main(sys.argv, ScanFollowerFactory())
