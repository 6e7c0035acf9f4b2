"""Lesson 1: a wall follower: your file (docs/lessons.md, "Lesson 1: a wall follower").

The robot starts by the south wall of a room, facing east, the wall 0.35 m to
its right. Write `WallFollowerEndpoint.steer` so that it keeps the wall there,
all the way round the room, without touching anything. As it is, the robot
drives straight on, into the divider.

Run it, and grade it::

    python wall_follower.py --seconds 30 --speed 0     # as fast as it goes
    python -m snr lesson grade 1

The room and the runner are the lesson's (``make_world`` and ``main``); your
part is the endpoint below.
"""

from __future__ import annotations

import sys

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.lessons.l01_wall_follower.solution import main, make_world

__all__ = ["WallFollowerEndpoint", "WallFollowerFactory", "make_world"]

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


class WallFollowerEndpoint(Endpoint):
    """Keeps a wall on the robot's right, `TARGET_M` away; turns left at corners.

    It reads the ``range`` and ``bump`` pages and stores ``wheel_cmd``.

    Example (a range page in, a wheel command out)::

        {"angles_deg": [-90, -45, 0, 45, 90], "ranges_m": [0.45, 0.64, 2.0, 2.0, 2.0]}
        -> {"left": 0.35, "right": 0.15}     # 0.1 m too far from the wall: turn right
    """

    def __init__(self, factory: WallFollowerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "wall_follower")
        self.task_handlers = {
            (TaskType.store_page, "range"): self.steer,
            (TaskType.store_page, "bump"): self.feel,
        }
        self.bumped = False

    def feel(self, task: Task, key: TaskId) -> SomeTasks:
        """Remember whether the bumper is pressed; `steer` backs away if so."""
        self.bumped = bool(task.val_list[0].data)
        return None

    def steer(self, task: Task, key: TaskId) -> SomeTasks:
        """One wheel command for one range reading."""
        reading = task.val_list[0].data
        ranges = dict(zip(reading["angles_deg"], reading["ranges_m"]))  # noqa: F841 (not used yet)
        # ranges[-90] is the ray to the right, ranges[0] straight ahead (metres).
        # TODO (step 4): if self.bumped, back away: self.wheels(-0.1, 0.0).
        # TODO (step 4): a wall closer than FRONT_CLEAR_M ahead: turn left on the spot.
        # TODO (step 2): the wall's distance, from the rays at -90 and -45 degrees
        #                (import math, for math.sin).
        # TODO (step 3): the error from TARGET_M, and a turn GAIN times it, at most
        #                MAX_TURN_M_S either way; the right wheel faster turns left.
        return self.wheels(CRUISE_M_S, CRUISE_M_S)  # for now: straight on

    def wheels(self, left_m_s: float, right_m_s: float) -> SomeTasks:
        """The task that stores a wheel command."""
        return self.store_data_task("wheel_cmd", {"left": left_m_s, "right": right_m_s})


class WallFollowerFactory(EndpointFactory):
    """Builds a `WallFollowerEndpoint`.

    Example::

        WallFollowerFactory()
    """

    def get(self, parent: AbstractNode) -> WallFollowerEndpoint:
        return WallFollowerEndpoint(self, parent)


if __name__ == "__main__":
    main(sys.argv, WallFollowerFactory())
