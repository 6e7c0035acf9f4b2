"""How many steps a second the simulator runs, with and without drawing.

Four loops drive the same robot in the same world (``examples/rover/room.json``,
9 walls) with the same simple controller (drive on, turn on the spot when a
wall is near), each for the same number of 20 ms steps:

* bare physics: the robot's equations written out inline in one function
  (speed limits, acceleration limits, seeded slip, the arc, wall clearance,
  5 range rays) with no classes: the baseline;
* simulator: `DiffDriveRobot.step` and `sensor_pages`, as `SimRobotLoop`
  runs them;
* simulator + drawing each 5th step: what `SimViewLoop` at 10 Hz adds to a
  50 Hz simulation (off-screen, so no screen is needed);
* simulator + drawing every step.

The ratio to the bare loop is the price of the readable classes.

Then the whole node, as a student runs lesson 1 (docs/lessons.md) without its
view: `SimRobotLoop` at 50 Hz, the wall follower's endpoint and a
`TimeoutLoopFactory`, on a `SimClock` as fast as it goes, for 60 simulated
seconds: simulated seconds per wall second, against the target of 20x real
time, in the default DEBUG mode and in DEPLOYED mode.

Run: ``python bench/bench_sim.py`` (``--steps N`` and ``--lesson-s S`` to
change the workload).
``--picture docs/images/simulator.png`` also writes the guide's picture: the
robot after 40 s of that controller, with its path.
"""

from __future__ import annotations

import argparse
import importlib.util
import logging
import math
import os
import random
import sys
import time
from typing import Callable, List, Optional, Tuple

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

from snr import (
    Config,
    Mode,
    SimClock,
    SimRobotFactory,
    SynchronousRunner,
    TimeoutLoopFactory,
    World,
)
from snr.extras.lessons.l01_wall_follower import solution as wall_follower
from snr.extras.sim import DiffDriveRobot, Odometry, Pose, RangeSensor, RobotSpec, sensor_pages
from snr.extras.sim.draw import WorldView, import_pygame, render_scene
from snr.prelude.install import install_hint

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORLD = World.load(os.path.join(ROOT, "examples", "rover", "room.json"))
DT_S = 0.02
SEED = 1


def controller(ahead_m: float) -> Tuple[float, float]:
    """Drive on; turn on the spot when a wall is near ahead."""
    return (0.4, 0.4) if ahead_m > 0.4 else (-0.2, 0.2)


def bare_physics(steps: int) -> float:
    """The same physics inline, no classes; returns the final x (so it is not optimised away)."""
    spec = RobotSpec()
    walls = [tuple(w) for w in WORLD.walls]
    rays = [math.radians(a) for a in RangeSensor().angles_deg]
    rng = random.Random(SEED)
    x, y, theta = WORLD.start
    vl = vr = 0.0
    ahead = 2.0
    max_dv = spec.max_wheel_accel_m_s2 * DT_S

    def clearance(px: float, py: float) -> float:
        best = math.inf
        for x1, y1, x2, y2 in walls:
            ex, ey = x2 - x1, y2 - y1
            u = max(0.0, min(1.0, ((px - x1) * ex + (py - y1) * ey) / (ex * ex + ey * ey)))
            best = min(best, math.hypot(px - x1 - u * ex, py - y1 - u * ey))
        return best

    for _ in range(steps):
        tl, tr = controller(ahead)
        vl += max(-max_dv, min(max_dv, tl - vl))
        vr += max(-max_dv, min(max_dv, tr - vr))
        ml = vl * DT_S * (1 + rng.gauss(0, spec.slip))
        mr = vr * DT_S * (1 + rng.gauss(0, spec.slip))
        forward, turn = (ml + mr) / 2, (mr - ml) / spec.wheel_base_m
        nx = x + forward * math.cos(theta + turn / 2)
        ny = y + forward * math.sin(theta + turn / 2)
        if clearance(nx, ny) >= spec.radius_m:
            x, y = nx, ny
            theta += turn
        else:
            vl = vr = 0.0
        readings = []
        for angle in rays:
            dx, dy = math.cos(theta + angle), math.sin(theta + angle)
            hit = 2.0
            for x1, y1, x2, y2 in walls:
                ex, ey = x2 - x1, y2 - y1
                den = dx * ey - dy * ex
                if abs(den) > 1e-12:
                    ax, ay = x1 - x, y1 - y
                    t, u = (ax * ey - ay * ex) / den, (ax * dy - ay * dx) / den
                    if 0 <= t < hit and 0 <= u <= 1:
                        hit = t
            readings.append(hit + rng.gauss(0, 0.005))
        ahead = readings[2]
    return x


def simulator(steps: int, draw_every: int = 0) -> float:
    """`DiffDriveRobot` and `sensor_pages`; draws off-screen every ``draw_every`` steps."""
    robot = DiffDriveRobot(RobotSpec(), Pose(*WORLD.start), seed=SEED)
    odometry, sensor = Odometry(robot.spec, robot.pose), RangeSensor()
    pygame = import_pygame() if draw_every else None
    view = WorldView(WORLD)
    surface: Optional[object] = pygame.Surface(view.size_px) if pygame else None
    ahead = 2.0
    for step in range(steps):
        robot.command(*controller(ahead))
        robot.step(DT_S, WORLD)
        pages = sensor_pages(robot, WORLD, sensor, odometry)
        ahead = pages["range"]["ranges_m"][2]
        if pygame is not None and step % draw_every == 0:
            render_scene(pygame, view, WORLD, pages, surface=surface)
    return robot.pose.x


def picture(path: str, seconds: float = 40.0) -> None:
    """Drive for ``seconds`` and save a picture of the world with the robot's path."""
    from snr.extras.sim.draw import save_png

    robot = DiffDriveRobot(RobotSpec(), Pose(*WORLD.start), seed=SEED)
    odometry, sensor = Odometry(robot.spec, robot.pose), RangeSensor()
    trail: List[Tuple[float, float]] = []
    pages = sensor_pages(robot, WORLD, sensor, odometry)
    for _ in range(round(seconds / DT_S)):
        robot.command(*controller(pages["range"]["ranges_m"][2]))
        robot.step(DT_S, WORLD)
        pages = sensor_pages(robot, WORLD, sensor, odometry)
        trail.append((robot.pose.x, robot.pose.y))
    pygame = import_pygame()
    save_png(pygame, render_scene(pygame, WorldView(WORLD), WORLD, pages, trail=trail), path)
    print(f"Wrote {path}")


def lesson_in_sim_time(seconds: float, mode: Mode) -> float:
    """Lesson 1's node without its view, on a SimClock as fast as it goes; its wall seconds."""
    clock = SimClock()
    components = [
        SimRobotFactory(wall_follower.make_world(), seed=SEED),
        wall_follower.WallFollowerFactory(),
        TimeoutLoopFactory(seconds=seconds),
    ]
    started = time.perf_counter()
    SynchronousRunner("sim", Config({"sim": components}, mode=mode, clock=clock)).run()
    took = time.perf_counter() - started
    if clock() != seconds:
        raise RuntimeError(f"the node stopped at {clock()} simulated s, not {seconds}")
    return took


def rate(run: Callable[[int], float], steps: int, rounds: int) -> float:
    """Best steps per second over ``rounds`` runs (the least disturbed one)."""
    best = 0.0
    for _ in range(rounds):
        started = time.perf_counter()
        run(steps)
        best = max(best, steps / (time.perf_counter() - started))
    return best


def main(argv: List[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--picture", metavar="PNG", help="also write a picture of a run")
    parser.add_argument(
        "--lesson-s", type=float, default=60.0, help="simulated seconds of lesson 1's node"
    )
    options = parser.parse_args(argv)
    drawing = importlib.util.find_spec("pygame") is not None
    if options.picture and drawing:
        picture(options.picture)
    cases: List[Tuple[str, Callable[[int], float]]] = [
        ("bare physics (inline)", bare_physics),
        ("simulator", simulator),
    ]
    if drawing:
        cases.append(("simulator + draw every 5th", lambda n: simulator(n, draw_every=5)))
        cases.append(("simulator + draw every step", lambda n: simulator(n, draw_every=1)))
    else:
        print(f"pygame is not installed: no drawing rows ({install_hint('controller')})")
    print(
        f"Simulator speed: {options.steps} steps of {DT_S * 1000:.0f} ms, "
        f"{len(WORLD.walls)} walls, 5 range rays, best of {options.rounds}"
    )
    print(f"{'case':<30} {'steps/s':>10} {'x real time':>12} {'vs bare':>8}")
    bare = 0.0
    for name, run in cases:
        steps_per_s = rate(run, options.steps, options.rounds)
        bare = bare or steps_per_s
        print(
            f"{name:<30} {steps_per_s:>10.0f} {steps_per_s * DT_S:>11.0f}x "
            f"{steps_per_s / bare:>7.2f}x"
        )
    lesson_s = options.lesson_s
    logging.getLogger("snr.sim").setLevel(logging.WARNING)  # no "terminated" lines
    print()
    print(
        f"Lesson 1 as a node on a SimClock: robot at 50 Hz + wall follower, "
        f"{lesson_s:g} simulated s, best of {options.rounds}"
    )
    print(f"{'mode':<30} {'wall s':>10} {'x real time':>12}")
    for mode in (Mode.DEBUG, Mode.DEPLOYED):
        took = min(lesson_in_sim_time(lesson_s, mode) for _ in range(options.rounds))
        print(f"{mode.name:<30} {took:>10.3f} {lesson_s / took:>11.0f}x")
    print("target: a 60 s lesson runs >= 20x faster than real time (a node on a SimClock)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
