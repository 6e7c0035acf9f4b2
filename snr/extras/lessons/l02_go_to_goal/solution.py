"""Lesson 2: go to a goal (docs/lessons.md), the reference solution.

The robot drives to a point in the room, going round a crate in the way. Its
brain, `GoToGoalEndpoint`, knows where it is only from its ``odometry`` page
(dead reckoning from the wheel encoders) and sees the crate only with its
range sensors, as a real rover would.

Run it (a window if you have a screen, else PNG frames in ``sim_frames/``;
without pygame it runs undrawn, and says so)::

    python examples/lessons/go_to_goal.py --seconds 30
    python examples/lessons/go_to_goal.py --seconds 5 --frames my_frames
    python examples/lessons/go_to_goal.py --seconds 60 --speed 0   # as fast as it goes

To write the controller yourself, ``python -m snr lesson start 2`` writes the
lesson's starter file into your folder, and ``python -m snr lesson grade 2``
grades it.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import snr
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.sim.draw import NO_PICTURES, pygame_installed

__all__ = ["GoToGoalEndpoint", "GoToGoalFactory", "main", "make_world", "run", "wrap"]

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

ROOM: Dict[str, Any] = {
    "name": "go to goal room",
    # A 5 m x 3 m room with a crate between the start and the goal.
    "walls": [[0, 0, 5, 0], [5, 0, 5, 3], [5, 3, 0, 3], [0, 3, 0, 0]],
    "boxes": [[2.2, 1.1, 0.6, 0.8]],
    "start": [0.5, 1.5, 0.0],
    "goal": [4.4, 1.6],
}
"""The world, in the same form as a world file (docs/simulator.md)."""


def make_world() -> snr.World:
    """The lesson's room: the robot starts at the west wall, the goal is past the crate.

    Example::

        make_world().goal    # (4.4, 1.6)
    """
    return snr.World.from_dict(ROOM, where="go_to_goal.py ROOM")


def wrap(angle: float) -> float:
    """``angle`` in (-pi, pi]: the shorter way round.

    Example::

        wrap(math.radians(270))    # -pi / 2: a quarter turn right, not three left
    """
    return math.atan2(math.sin(angle), math.cos(angle))


class GoToGoalEndpoint(Endpoint):
    """Drives to ``goal`` by odometry; goes round what is in the way; stops there.

    It reads the ``odometry`` and ``range`` pages and stores ``wheel_cmd``.
    It is in one of two modes: *to goal* (steer by the heading error), or
    *round* an obstacle (follow its edge, as lesson 1 follows a wall, until
    the goal is no longer behind it).

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
        self.arrived = False

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
        if distance < ARRIVED_M:
            if not self.arrived:
                self.arrived = True
                self.info("Arrived within %.2f m of the goal", distance)
            return self.wheels(0.0, 0.0)
        # The heading error: how far to turn to face the goal (> 0: to the left).
        heading_error = wrap(math.atan2(dy, dx) - self.pose["theta"])
        reading = task.val_list[0].data
        ranges = dict(zip(reading["angles_deg"], reading["ranges_m"]))
        ahead = ranges[0]
        if self.edge_side == 0 and ahead < min(BLOCKED_M, distance):
            # In the way: go round it on the goal's side, the obstacle on the other.
            self.edge_side = -1 if heading_error >= 0 else 1
        elif self.edge_side != 0 and ahead > BLOCKED_M and self.edge_side * heading_error <= 0:
            # The way ahead is clear and the goal is no longer on the obstacle's
            # side: it is not behind the obstacle any more. Head for it.
            self.edge_side = 0
        if self.edge_side == 0:
            return self.to_goal(heading_error, distance)
        return self.round_edge(ranges)

    def to_goal(self, heading_error: float, distance: float) -> SomeTasks:
        """Turn by the heading error; drive on when roughly facing the goal, slower near it."""
        turn = max(-MAX_TURN_M_S, min(MAX_TURN_M_S, HEADING_GAIN * heading_error))
        facing = max(0.0, math.cos(heading_error))  # 1 facing the goal, 0 side-on or away
        forward = CRUISE_M_S * facing * min(1.0, distance / SLOW_DOWN_M)
        return self.wheels(forward - turn, forward + turn)

    def round_edge(self, ranges: Dict[float, float]) -> SomeTasks:
        """Lesson 1's wall follower, with the obstacle on side `edge_side`."""
        side = self.edge_side
        if ranges[0] < BLOCKED_M:
            # A face ahead: turn on the spot, away from the obstacle's side.
            return self.wheels(side * SPIN_M_S, -side * SPIN_M_S)
        edge_m = min(ranges[90 * side], ranges[45 * side] * math.sin(math.radians(45)))
        error = EDGE_M - edge_m  # > 0: too close to the edge
        turn = max(-MAX_TURN_M_S, min(MAX_TURN_M_S, -side * EDGE_GAIN * error))
        return self.wheels(CRUISE_M_S - turn, CRUISE_M_S + turn)

    def wheels(self, left_m_s: float, right_m_s: float) -> SomeTasks:
        """The task that stores a wheel command."""
        return self.store_data_task("wheel_cmd", {"left": left_m_s, "right": right_m_s})


class GoToGoalFactory(EndpointFactory):
    """Builds a `GoToGoalEndpoint` that drives to ``goal`` (x, y in metres).

    Example::

        GoToGoalFactory((4.4, 1.6))
    """

    def __init__(self, goal: Tuple[float, float], name: Optional[str] = None) -> None:
        super().__init__()
        self.goal = goal
        self.name = name or "go_to_goal"

    def get(self, parent: AbstractNode) -> GoToGoalEndpoint:
        return GoToGoalEndpoint(self, parent)


def run(
    seconds: float,
    frames_dir: Optional[str] = None,
    seed: int = 1,
    speed: Optional[float] = 1.0,
    brain: Optional[snr.AbstractFactory] = None,
) -> snr.SimRobotFactory:
    """Run the lesson in one node for ``seconds``; returns the simulated robot.

    The node runs on a `SimClock`, ``speed`` simulated seconds per real
    second (1.0: real time; None: as fast as the computer can), so ``seconds``
    is simulated time and the same ``seed`` gives the same run. ``brain``
    drives the robot: this file's `GoToGoalFactory` unless given (the starter
    file passes its own).

    Example::

        sim = run(5.0, frames_dir="frames")
    """
    world = make_world()
    assert world.goal is not None
    sim = snr.SimRobotFactory(world, seed=seed)
    if frames_dir is None:
        view = snr.SimViewFactory(world)
    else:
        view = snr.SimViewFactory(world, frames_dir=frames_dir, window=False)
    components = [
        sim,
        brain or GoToGoalFactory(world.goal),
        snr.TimeoutLoopFactory(seconds=seconds),
    ]
    if not pygame_installed():  # said once, here; no view, so no folder and no warning
        print(NO_PICTURES, flush=True)
    else:
        components.append(view)
        if not view.window:
            print(f"Pictures: PNG frames in {Path(view.frames_dir).resolve()}", flush=True)
    clock = snr.SimClock(speed=speed)
    snr.SynchronousRunner("sim", snr.Config({"sim": components}, clock=clock)).run()
    pose = sim.robot.pose
    left = math.hypot(world.goal[0] - pose.x, world.goal[1] - pose.y)
    print(f"After {sim.steps / sim.rate_hz:.1f} s the robot is {left:.2f} m from the goal.")
    return sim


def main(argv: List[str], brain: Optional[snr.AbstractFactory] = None) -> None:
    """``python go_to_goal.py [--seconds S] [--frames DIR] [--seed N] [--speed X]``.

    ``brain``: the endpoint's factory that drives the robot (this file's by default).
    """
    parser = argparse.ArgumentParser(prog=argv[0], description="Lesson 2: go to a goal.")
    parser.add_argument("--seconds", type=float, default=30.0, help="how long to run")
    parser.add_argument("--frames", default=None, help="write PNG frames to this folder")
    parser.add_argument("--seed", type=int, default=1, help="the simulator's random seed")
    parser.add_argument(
        "--speed",
        type=float,
        default=1.0,
        help="simulated seconds per real second: 1 is real time, 0.5 half speed, "
        "0 as fast as the computer can",
    )
    options = parser.parse_args(argv[1:])
    if options.speed < 0:
        parser.error(f"--speed {options.speed:g}: use 0 (as fast as possible) or more")
    run(options.seconds, options.frames, options.seed, options.speed or None, brain)


if __name__ == "__main__":
    main(sys.argv)
