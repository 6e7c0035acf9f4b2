"""Lesson 1: a wall follower (docs/lessons.md), the reference solution.

The robot keeps a wall on its right, a fixed distance away, and drives along
it all the way round the room. Its brain, `WallFollowerEndpoint`, is a
proportional controller: it steers by an amount proportional to how far it
is from where it wants to be.

Run it (a window if you have a screen, else PNG frames in ``sim_frames/``;
without pygame it runs undrawn, and says so)::

    python examples/lessons/wall_follower.py --seconds 30
    python examples/lessons/wall_follower.py --seconds 5 --frames my_frames
    python examples/lessons/wall_follower.py --seconds 60 --speed 0   # as fast as it goes

This file ships inside the package, so ``python -m snr demo --sim`` runs it
from an installed SNR too; ``examples/lessons/wall_follower.py`` runs it from
the lessons' folder. To write the controller yourself, ``python -m snr lesson
start 1`` writes the lesson's starter file into your folder, and ``python -m
snr lesson grade 1`` grades it; a copy of this file passes too, renamed or not.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional

import snr
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.sim import run_in_window
from snr.extras.sim.draw import NO_PICTURES, pygame_installed

__all__ = ["WallFollowerEndpoint", "WallFollowerFactory", "main", "make_world", "run"]

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

ROOM: Dict[str, Any] = {
    "name": "wall follower room",
    # A 4 m x 3 m room with a divider sticking out of the south wall.
    "walls": [[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0], [2.6, 0, 2.6, 1.2]],
    "boxes": [[1.2, 1.6, 0.6, 0.5]],
    "start": [0.5, 0.35, 0.0],
}
"""The world, in the same form as a world file (docs/simulator.md)."""


def make_world() -> snr.World:
    """The lesson's room: walls, a divider and a crate; the robot starts by the south wall.

    Example::

        make_world().start    # (0.5, 0.35, 0.0): facing east, the wall 0.35 m to its right
    """
    return snr.World.from_dict(ROOM, where="wall_follower.py ROOM")


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
        ranges = dict(zip(reading["angles_deg"], reading["ranges_m"]))
        if self.bumped:
            # Touching a wall: back away, turning left (away from the right wall).
            return self.wheels(-0.1, 0.0)
        if ranges[0] < FRONT_CLEAR_M:
            # A wall ahead: turn left on the spot until the way is clear.
            return self.wheels(-SPIN_M_S, SPIN_M_S)
        # The wall's distance: the right ray, or the front-right ray if it
        # sees the wall closer (a wall 0.35 m away is 0.35 / sin 45° along
        # that ray). The diagonal sees a bend in the wall before the side does.
        wall_m = min(ranges[-90], ranges[-45] * math.sin(math.radians(45)))
        error = TARGET_M - wall_m  # > 0: too close to the wall
        turn = max(-MAX_TURN_M_S, min(MAX_TURN_M_S, GAIN * error))  # > 0: turn left
        return self.wheels(CRUISE_M_S - turn, CRUISE_M_S + turn)

    def wheels(self, left_m_s: float, right_m_s: float) -> SomeTasks:
        """The task that stores a wheel command."""
        return self.store_data_task("wheel_cmd", {"left": left_m_s, "right": right_m_s})


class WallFollowerFactory(EndpointFactory):
    """Builds a `WallFollowerEndpoint`.

    Example::

        WallFollowerFactory()
    """

    def __init__(self, name: Optional[str] = None) -> None:
        super().__init__()
        self.name = name or "wall_follower"

    def get(self, parent: AbstractNode) -> WallFollowerEndpoint:
        return WallFollowerEndpoint(self, parent)


def run(
    seconds: float,
    frames_dir: Optional[str] = None,
    seed: int = 1,
    speed: Optional[float] = 1.0,
    brain: Optional[snr.AbstractFactory] = None,
    robot: Optional[Dict[str, Any]] = None,
) -> snr.SimRobotFactory:
    """Run the lesson in one node for ``seconds``; returns the simulated robot.

    With ``frames_dir`` the view writes PNG frames there; without it, a
    window if there is a screen (drawn on this thread, which must be the
    main one on macOS, while the node runs on another), else frames in
    ``sim_frames/``. Without pygame nothing is drawn: it says so, and how to
    get pictures, and makes no folder.

    The node runs on a `SimClock`, ``speed`` simulated seconds per real
    second (1.0: real time; None: as fast as the computer can), so ``seconds``
    is simulated time and the same ``seed`` gives the same run. ``brain``
    drives the robot: this file's `WallFollowerFactory` unless given (the
    starter file passes its own); ``robot``, more arguments for its
    `SimRobotFactory` (lesson 3 gives it a lidar instead of its range sensor).

    Example::

        sim = run(5.0, frames_dir="frames")
        sim.robot.pose        # where the robot got to
    """
    world = make_world()
    sim = snr.SimRobotFactory(world, seed=seed, **(robot or {}))
    if frames_dir is None:
        view = snr.SimViewFactory(world, sensor_keys=sim.sensor_keys)
    else:
        view = snr.SimViewFactory(
            world, frames_dir=frames_dir, window=False, sensor_keys=sim.sensor_keys
        )
    brain_and_timer = [brain or WallFollowerFactory(), snr.TimeoutLoopFactory(seconds=seconds)]
    clock = snr.SimClock(speed=speed)
    if not pygame_installed():  # said once, here; no view, so no folder and no warning
        print(NO_PICTURES, flush=True)
        snr.SynchronousRunner(
            "sim", snr.Config({"sim": [sim, *brain_and_timer]}, clock=clock)
        ).run()
    elif view.window:
        # The window on this (the main) thread, as macOS requires; the node beside it.
        run_in_window("sim", snr.Config({"sim": [sim, *brain_and_timer]}, clock=clock), view)
    else:
        print(f"Pictures: PNG frames in {Path(view.frames_dir).resolve()}", flush=True)
        snr.SynchronousRunner(
            "sim", snr.Config({"sim": [sim, view, *brain_and_timer]}, clock=clock)
        ).run()
    pose = sim.robot.pose
    print(
        f"After {sim.steps / sim.rate_hz:.1f} s the robot is at ({pose.x:.2f}, {pose.y:.2f})"
        f"{', touching a wall' if sim.robot.bumped else ''}."
    )
    return sim


def main(
    argv: List[str],
    brain: Optional[snr.AbstractFactory] = None,
    robot: Optional[Dict[str, Any]] = None,
    title: str = "Lesson 1: a wall follower.",
) -> None:
    """``python wall_follower.py [--seconds S] [--frames DIR] [--seed N] [--speed X]``.

    ``brain``: the endpoint's factory that drives the robot (this file's by
    default); ``robot`` and ``title``: lesson 3's lidar and name, for its file.
    """
    parser = argparse.ArgumentParser(prog=argv[0], description=title)
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
    run(options.seconds, options.frames, options.seed, options.speed or None, brain, robot)


if __name__ == "__main__":
    main(sys.argv)
