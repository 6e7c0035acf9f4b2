"""Lesson 2: go to a goal: your file (docs/lessons.md, "Lesson 2: go to a goal").

The robot starts at the west wall of a room and must stop at the goal, near
the east wall, going round the crate in the way. Write `GoToGoalEndpoint.steer`
(and the two helpers it calls) so that it gets there without touching
anything. As it is, the robot drives straight on, into the crate.

Run it, and grade it::

    python go_to_goal.py --seconds 25 --speed 0     # as fast as it goes
    python -m snr lesson grade 2

The room and the runner are the lesson's (``make_world`` and ``main``); your
part is the endpoint below.
"""

from __future__ import annotations

import math
import sys
from typing import Dict, Optional, Tuple

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.lessons.l02_go_to_goal.solution import main, make_world, wrap

__all__ = ["GoToGoalEndpoint", "GoToGoalFactory", "make_world", "wrap"]

CRUISE_M_S = 0.3
"""Top forward speed."""
HEADING_GAIN = 0.3
"""Steering per radian of heading error (m/s)."""
MAX_TURN_M_S = 0.15
"""The most steering: half the difference between the two wheels' speeds."""
SLOW_DOWN_M = 0.5
"""Closer than this to the goal, slow down in proportion."""
ARRIVED_M = 0.1
"""Closer than this to the goal, stop: arrived."""
BLOCKED_M = 0.45
"""Something closer than this straight ahead (and nearer than the goal) is in the way."""
EDGE_M = 0.35
"""Going round an obstacle, keep its edge this far from the robot's centre."""
EDGE_GAIN = 1.0
"""Steering per metre of error from `EDGE_M` (lesson 1's `GAIN`)."""
SPIN_M_S = 0.2
"""Wheel speed while turning on the spot."""


class GoToGoalEndpoint(Endpoint):
    """Drives to ``goal`` by odometry; goes round what is in the way; stops there.

    It reads the ``odometry`` and ``range`` pages and stores ``wheel_cmd``.

    Example (at the start, facing the goal, nothing near: straight on)::

        odometry {"x": 0.5, "y": 1.6, "theta": 0.0}
        range    {"angles_deg": [-90, -45, 0, 45, 90], "ranges_m": [1.6, 2, 2, 2, 1.4]}
        -> {"left": 0.3, "right": 0.3}
    """

    def __init__(self, factory: GoToGoalFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "go_to_goal")
        self.goal = factory.goal
        self.task_handlers = {
            (TaskType.store_page, "odometry"): self.locate,
            (TaskType.store_page, "range"): self.steer,
        }
        self.pose: Optional[Dict[str, float]] = None
        self.edge_side = 0
        """0: heading for the goal; -1: going round an obstacle on the right; +1: on the left."""

    def locate(self, task: Task, key: TaskId) -> SomeTasks:
        """Remember where odometry says the robot is."""
        self.pose = task.val_list[0].data
        return None

    def steer(self, task: Task, key: TaskId) -> SomeTasks:
        """One wheel command for one range reading, from the newest pose."""
        if self.pose is None:
            return None  # no odometry yet: wait for it
        dx, dy = self.goal[0] - self.pose["x"], self.goal[1] - self.pose["y"]
        distance = math.hypot(dx, dy)
        reading = task.val_list[0].data
        ranges = dict(zip(reading["angles_deg"], reading["ranges_m"]))
        # TODO (step 3): closer than ARRIVED_M to the goal: stop, self.wheels(0.0, 0.0).
        # TODO (step 2): the heading error, wrap(...) of the direction to the goal
        #                minus self.pose["theta"].
        # TODO (step 4): something closer than BLOCKED_M ahead (ranges[0]), and nearer
        #                than the goal: set self.edge_side; clear it when the way is free.
        heading_error = 0.0
        if self.edge_side == 0:
            return self.to_goal(heading_error, distance)
        return self.round_edge(ranges)

    def to_goal(self, heading_error: float, distance: float) -> SomeTasks:
        """Turn by the heading error; drive on when roughly facing the goal, slower near it."""
        # TODO (step 3): turn by HEADING_GAIN * heading_error (at most MAX_TURN_M_S),
        #                forward by CRUISE_M_S * cos(heading_error), slower near the goal.
        return self.wheels(CRUISE_M_S, CRUISE_M_S)  # for now: straight on

    def round_edge(self, ranges: Dict[float, float]) -> SomeTasks:
        """Lesson 1's wall follower, with the obstacle on side `edge_side`."""
        # TODO (step 4): follow the obstacle's edge, EDGE_M away, as lesson 1 does.
        return self.wheels(CRUISE_M_S, CRUISE_M_S)  # for now: straight on

    def wheels(self, left_m_s: float, right_m_s: float) -> SomeTasks:
        """The task that stores a wheel command."""
        return self.store_data_task("wheel_cmd", {"left": left_m_s, "right": right_m_s})


class GoToGoalFactory(EndpointFactory):
    """Builds a `GoToGoalEndpoint` that drives to ``goal`` (x, y in metres).

    Example::

        GoToGoalFactory((4.4, 1.6))
    """

    def __init__(self, goal: Tuple[float, float]) -> None:
        super().__init__()
        self.goal = goal

    def get(self, parent: AbstractNode) -> GoToGoalEndpoint:
        return GoToGoalEndpoint(self, parent)


if __name__ == "__main__":
    goal = make_world().goal
    assert goal is not None  # the lesson's room has one
    main(sys.argv, GoToGoalFactory(goal))
