"""The two simulator lessons (docs/lessons.md): graded in simulated time, and run as shipped.

Simulated time for a whole node is not built yet (docs/sim-time.md), so the
grading tests step the physics themselves: each step, the lesson's own
endpoint gets the sensor pages through its handler table, as a node would
hand them over, and the ``wheel_cmd`` it returns drives the robot. No node,
no threads: 60 s of robot time takes a fraction of a second, and a seed makes
every run the same. A short real-time run of each file checks that it runs
the way a student runs it.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import math
import re
import shutil
import tempfile
import unittest
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Optional, Tuple

from snr import AbstractFactory, TaskType, World
from snr.std_mods.sim import (
    DiffDriveRobot,
    Odometry,
    Pose,
    RangeSensor,
    RobotSpec,
    sensor_pages,
    wheel_command,
)
from snr.utils import MockNode, SNRTestCase
from tests.examples_support import (
    StartedScript,
    example_path,
    load_module,
    script_env,
    start_script,
)
from tests.quiet import captured_logs

wall_follower: Any = load_module(
    example_path("lessons", "wall_follower.py"), "lesson_wall_follower"
)
go_to_goal: Any = load_module(example_path("lessons", "go_to_goal.py"), "lesson_go_to_goal")

HAS_PYGAME = importlib.util.find_spec("pygame") is not None
STEP_S = 0.02
"""50 steps a second, as `SimRobotFactory` takes by default."""


@dataclass
class Drive:
    """What happened in one run: the true path and every command the brain gave."""

    robot: DiffDriveRobot
    path: List[Tuple[float, float]] = field(default_factory=list)
    bumped_steps: int = 0
    commands: int = 0

    def length_m(self) -> float:
        return sum(math.dist(a, b) for a, b in zip(self.path, self.path[1:]))


def drive(brain: AbstractFactory, world: World, seconds: float, seed: int = 1) -> Drive:
    """Run ``brain``'s endpoint against the physics for ``seconds`` of simulated time.

    Each step stores the sensor pages in a `MockNode` and hands each to the
    handlers registered for it (the node's own dispatch rule), then feeds the
    newest ``wheel_cmd`` the endpoint returned to the robot's motors.
    """
    node = MockNode("sim")
    endpoint = brain.get(node)
    assert endpoint is not None
    node.components[endpoint.name] = endpoint
    robot = DiffDriveRobot(RobotSpec(), Pose(*world.start), seed=seed)
    odometry, sensor = Odometry(robot.spec, robot.pose), RangeSensor()
    run = Drive(robot)
    for _ in range(round(seconds / STEP_S)):
        for key, data in sensor_pages(robot, world, sensor, odometry).items():
            task = node.store_data_task(key, data)
            node.datastore[key] = task.val_list[0]  # stored before handlers run, as in a node
            node.execute_task(task)
        for task in node.scheduled:
            if task.type is TaskType.store_page and task.name == "wheel_cmd":
                command = wheel_command(task.val_list[0].data)
                assert command is not None, task
                robot.command(*command)
                run.commands += 1
        node.scheduled.clear()
        robot.step(STEP_S, world)
        run.path.append((robot.pose.x, robot.pose.y))
        run.bumped_steps += robot.bumped
    return run


class TestWallFollower(unittest.TestCase):
    def test_a_minute_along_the_walls_without_a_bump(self) -> None:
        world = wall_follower.make_world()
        run = drive(wall_follower.WallFollowerFactory(), world, seconds=60.0)
        self.assertEqual(run.bumped_steps, 0, "it touched a wall")
        self.assertGreater(run.commands, 2900, "the brain steered every step")
        # Round the room: about 14 m, past the divider (x = 2.6) and back west.
        self.assertGreater(run.length_m(), 12.0)
        self.assertGreater(max(x for x, _ in run.path), 3.4, "it never got round the divider")
        # Along a wall all the time (after the first second): never in open floor.
        clearances = [world.clearance_m(x, y) for x, y in run.path[50:]]
        self.assertGreater(min(clearances), 0.18, "too close to a wall")
        self.assertLess(max(clearances), 0.5, "it left the wall")

    def test_the_demo_runs_this_file(self) -> None:
        """``python -m snr demo --sim`` and the lesson run the one controller."""
        import snr.demo.wall_follower as shipped

        self.assertIs(wall_follower.WallFollowerEndpoint, shipped.WallFollowerEndpoint)
        self.assertIs(wall_follower.main, shipped.main)


class TestGoToGoal(unittest.TestCase):
    def test_it_goes_round_the_crate_and_stops_at_the_goal(self) -> None:
        world = go_to_goal.make_world()
        goal = world.goal
        assert goal is not None
        start_x, start_y, _ = world.start
        # The crate is in the way: the straight line to the goal is blocked.
        to_goal = math.atan2(goal[1] - start_y, goal[0] - start_x)
        self.assertLess(
            world.ray_hit_m(start_x, start_y, to_goal, 10.0),
            math.dist((start_x, start_y), goal) - 1.0,
        )
        run = drive(go_to_goal.GoToGoalFactory(goal), world, seconds=25.0)
        self.assertEqual(run.bumped_steps, 0, "it touched the crate or a wall")
        # Odometry drifts a few centimetres over the 5 m it drives: hence 0.25 m.
        self.assertLess(math.dist(run.path[-1], goal), 0.25)
        self.assertEqual(run.robot.wheel_speeds_m_s, (0.0, 0.0), "it did not stop there")
        reached_s = STEP_S * next(i for i, p in enumerate(run.path) if math.dist(p, goal) < 0.25)
        self.assertLess(reached_s, 20.0)


class TestRunAsAStudentDoes(SNRTestCase):
    """Each lesson's ``main`` in a real node, in real time, briefly (frames, no window)."""

    def run_main(self, lesson: Any, seconds: float) -> Tuple[str, Path]:
        frames = Path(self.temp_file("frames"))
        out = io.StringIO()
        with captured_logs("snr.sim") as lines, contextlib.redirect_stdout(out):
            lesson.main(["lesson.py", "--seconds", str(seconds), "--frames", str(frames)])
        problems = [line for line in lines if not line.startswith("INFO")]
        if HAS_PYGAME:
            self.assertEqual(problems, [], lines)
        else:  # the simulator drives unseen, and says how to see it
            self.assertEqual(len(problems), 1, lines)
            self.assertIn("pip install 'snr[controller]'", problems[0])
        return out.getvalue(), frames

    def test_the_wall_follower_sets_off(self) -> None:
        text, frames = self.run_main(wall_follower, 0.4)
        self.assertIn(f"Pictures: PNG frames in {frames.resolve()}", text)
        simulated_s, x = summary(r"After ([\d.]+) s the robot is at \(([\d.]+), ", text)
        if simulated_s >= 0.2:  # 2 cm by then (a busy machine may take fewer steps)
            self.assertGreater(x, 0.5, text)  # it set off east from x = 0.5
        if HAS_PYGAME:
            self.assertTrue(list(frames.glob("frame_*.png")), "no frames were written")

    def test_go_to_goal_sets_off(self) -> None:
        text, _ = self.run_main(go_to_goal, 0.4)
        simulated_s, left_m = summary(r"After ([\d.]+) s the robot is ([\d.]+) m from", text)
        if simulated_s >= 0.2:
            self.assertLess(left_m, 3.9, text)  # it started 3.90 m away


def summary(pattern: str, text: str) -> Tuple[float, float]:
    """The simulated seconds and the position a lesson's last line gives.

    The node runs in real time, so how many steps it took in its time
    depends on the machine; at least one, or nothing ran.
    """
    match = re.search(pattern, text)
    if match is None:
        raise AssertionError(f"no summary line in {text!r}")
    simulated_s, where = float(match.group(1)), float(match.group(2))
    if not simulated_s > 0:
        raise AssertionError(f"the simulator took no step: {text!r}")
    return simulated_s, where


def _start_sim_demo() -> Tuple[Path, Optional[StartedScript]]:
    """``python -m snr demo --sim`` for 1.5 s in a temp folder, headless."""
    folder = Path(tempfile.mkdtemp(prefix="snr-sim-demo-"))
    if not HAS_PYGAME:
        return folder, None
    env = script_env({"SDL_VIDEODRIVER": "dummy", "PYGAME_HIDE_SUPPORT_PROMPT": "1"})
    # 1.5 s, not the default 15: enough to set off and draw frames even when
    # the machine is busy (it runs beside other tests, so it costs no wall time).
    command = ["-m", "snr", "demo", "--sim", "--seconds", "1.5"]
    return folder, start_script(command, cwd=str(folder), env=env)


# Started when this module is imported; it runs while other tests do.
SIM_DEMO_FOLDER, SIM_DEMO = _start_sim_demo()


@unittest.skipUnless(HAS_PYGAME, "pygame is not installed: the demo would draw nothing")
class TestSimDemo(SNRTestCase):
    def test_python_m_snr_demo_sim_drives_the_rover_and_says_where_the_frames_are(self) -> None:
        assert SIM_DEMO is not None
        folder = SIM_DEMO_FOLDER
        result = SIM_DEMO.result()
        self.addCleanup(shutil.rmtree, folder, True)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        self.assertTrue(lines[0].startswith("SNR demo --sim: "), result.stdout)
        frames = (folder / "sim_frames").resolve()
        self.assertIn(f"Pictures: PNG frames in {frames}", lines)
        simulated_s, x = summary(r"After ([\d.]+) s the robot is at \(([\d.]+), ", lines[-1])
        # On a machine too busy to simulate that much, it may not have got that far.
        if simulated_s >= 0.2:
            self.assertGreater(x, 0.5, result.stdout)  # it set off from x = 0.5
        if simulated_s >= 0.5:
            self.assertTrue(list(frames.glob("frame_*.png")), result.stdout)
        self.assertEqual(result.stderr, "", "quiet unless --verbose")


if __name__ == "__main__":
    unittest.main()
