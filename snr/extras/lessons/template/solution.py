"""The template lesson: stop at a wall (docs/teaching.md), the reference solution.

The robot starts at the west end of a corridor, facing east. Its brain,
`StopAtWallEndpoint`, reads one ray of the ``range`` page, the one straight
ahead, and drives at a speed proportional to how far it still is from
`STOP_M` before the wall: fast when far, slower and slower as it comes
closer, stopped there.

Run it (no view: it prints where the robot stopped)::

    python -m snr.extras.lessons.template.solution --seconds 15

A new lesson's solution keeps this shape: the world (`make_world`), the
endpoint and its factory, and a `main` that the starter file imports, so
that the student's file is only the endpoint.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Dict, List, Optional

import snr
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType

__all__ = ["StopAtWallEndpoint", "StopAtWallFactory", "main", "make_world"]

STOP_M = 0.5
"""Where to stop: this far from the wall ahead, measured from the robot's centre."""
GAIN = 1.0
"""Speed per metre still to go: 0.2 m from the stop, 0.2 m/s."""
MAX_SPEED_M_S = 0.3
"""The fastest the robot drives."""

CORRIDOR: Dict[str, Any] = {
    "name": "stop at a wall",
    # A corridor 3 m long and 1 m wide; the robot starts at its west end.
    "walls": [[0, 0, 3, 0], [3, 0, 3, 1], [3, 1, 0, 1], [0, 1, 0, 0]],
    "start": [0.5, 0.5, 0.0],
}
"""The world, in the same form as a world file (docs/simulator.md)."""


def make_world() -> snr.World:
    """The lesson's corridor; the robot starts 2.5 m from the wall ahead.

    Example::

        make_world().start    # (0.5, 0.5, 0.0): facing east
    """
    return snr.World.from_dict(CORRIDOR, where="template CORRIDOR")


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
        ahead_m = dict(zip(reading["angles_deg"], reading["ranges_m"]))[0]
        error = ahead_m - STOP_M  # > 0: still to go; < 0: too close
        speed = max(-MAX_SPEED_M_S, min(MAX_SPEED_M_S, GAIN * error))
        return self.store_data_task("wheel_cmd", {"left": speed, "right": speed})


class StopAtWallFactory(EndpointFactory):
    """Builds a `StopAtWallEndpoint`.

    Example::

        StopAtWallFactory()
    """

    def get(self, parent: AbstractNode) -> StopAtWallEndpoint:
        return StopAtWallEndpoint(self, parent)


def main(argv: List[str], brain: Optional[snr.AbstractFactory] = None) -> snr.SimRobotFactory:
    """``python solution.py [--seconds S] [--seed N]``: run the lesson, say where it stopped.

    ``brain`` drives the robot: this file's `StopAtWallFactory` unless given
    (the starter file passes its own). The node runs on a `SimClock` as fast
    as it goes, so ``--seconds`` is simulated time.

    Example::

        main(["solution.py", "--seconds", "15"]).robot.pose.x    # about 2.5
    """
    parser = argparse.ArgumentParser(prog=argv[0], description="The template lesson.")
    parser.add_argument("--seconds", type=float, default=15.0, help="simulated seconds to run")
    parser.add_argument("--seed", type=int, default=1, help="the simulator's random seed")
    options = parser.parse_args(argv[1:])
    world = make_world()
    sim = snr.SimRobotFactory(world, seed=options.seed)
    components = [
        sim,
        brain or StopAtWallFactory(),
        snr.TimeoutLoopFactory(seconds=options.seconds),
    ]
    config = snr.Config({"sim": components}, clock=snr.SimClock(speed=None))
    snr.SynchronousRunner("sim", config).run()
    pose = sim.robot.pose
    ahead = world.ray_hit_m(pose.x, pose.y, pose.theta, 5.0)
    print(
        f"After {sim.steps / sim.rate_hz:.1f} s the robot is at ({pose.x:.2f}, {pose.y:.2f}), "
        f"{ahead:.2f} m from the wall ahead{', touching it' if sim.robot.bumped else ''}."
    )
    return sim


if __name__ == "__main__":
    main(sys.argv)
