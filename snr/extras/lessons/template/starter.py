"""The template lesson: stop at a wall: your file (docs/teaching.md, the template lesson).

The robot starts at the west end of a corridor, facing east, 2.5 m from the
wall ahead. Write `StopAtWallEndpoint.steer` so that it stops `STOP_M` from
that wall without touching it. As it is, the robot drives on at full speed,
into the wall.

Run it, and grade it::

    python stop_at_wall.py --seconds 15
    python -m snr.extras.lessons.template.grader stop_at_wall.py

The corridor and the runner are the lesson's (``make_world`` and ``main``);
your part is the endpoint below.
"""

from __future__ import annotations

import sys

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.lessons.template.solution import main, make_world

__all__ = ["StopAtWallEndpoint", "StopAtWallFactory", "make_world"]

STOP_M = 0.5
"""Where to stop: this far from the wall ahead, measured from the robot's centre."""
GAIN = 1.0
"""Speed per metre still to go: 0.2 m from the stop, 0.2 m/s."""
MAX_SPEED_M_S = 0.3
"""The fastest the robot drives."""


class StopAtWallEndpoint(Endpoint):
    """Drives towards the wall ahead and stops `STOP_M` from it.

    It reads the ``range`` page and stores ``wheel_cmd``.

    Example (a range page in, a wheel command out)::

        {"angles_deg": [-90, -45, 0, 45, 90], "ranges_m": [0.5, 0.7, 0.7, 0.7, 0.5]}
        -> {"left": 0.2, "right": 0.2}     # 0.2 m still to go
    """

    def __init__(self, factory: StopAtWallFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stop_at_wall")
        self.task_handlers = {(TaskType.store_page, "range"): self.steer}

    def steer(self, task: Task, key: TaskId) -> SomeTasks:
        """One wheel command for one range reading."""
        reading = task.val_list[0].data
        ahead_m = dict(zip(reading["angles_deg"], reading["ranges_m"]))[0]  # noqa: F841 (not used yet)
        # TODO (step 1): the error: how far the robot still is from STOP_M.
        # TODO (step 2): a speed GAIN times the error, at most MAX_SPEED_M_S either way.
        speed = MAX_SPEED_M_S  # for now: full speed ahead
        return self.store_data_task("wheel_cmd", {"left": speed, "right": speed})


class StopAtWallFactory(EndpointFactory):
    """Builds a `StopAtWallEndpoint`.

    Example::

        StopAtWallFactory()
    """

    def get(self, parent: AbstractNode) -> StopAtWallEndpoint:
        return StopAtWallEndpoint(self, parent)


if __name__ == "__main__":
    main(sys.argv, StopAtWallFactory())
