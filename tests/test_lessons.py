"""The two simulator lessons (docs/lessons.md): graded in simulated time, and run as shipped.

The grading tests run each lesson's own endpoint and the simulated robot as a
node, as a student's program runs them, on a `SimClock` as fast as it goes:
60 simulated seconds take about a second, with the same pages every run
(seed 1). A page collector keeps the robot's true pose and bumper for the
grade. A short run of each file checks that it runs the way a student runs it.
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

from snr import (
    AbstractFactory,
    Config,
    Mode,
    RecorderEndpointFactory,
    SimClock,
    SimRobotFactory,
    TimeoutLoopFactory,
    World,
)
from snr.core import TestRunner
from snr.extras.sim import (
    BUMP,
    ODOMETRY,
    RANGE,
    TRUE_POSE,
    WHEEL_CMD,
    WHEEL_ENCODERS,
    DiffDriveRobot,
)
from snr.extras.sim.draw import NO_PICTURES
from snr.utils import SNRTestCase
from tests.examples_support import (
    StartedScript,
    early,
    example_path,
    load_module,
    script_env,
    start_script,
)
from tests.helpers import no_pygame
from tests.optional import reason
from tests.page_collector import PageCollectorFactory
from tests.quiet import SlowHandlerLimitFactory, captured_logs

wall_follower: Any = load_module(
    example_path("lessons", "wall_follower.py"), "lesson_wall_follower"
)
go_to_goal: Any = load_module(example_path("lessons", "go_to_goal.py"), "lesson_go_to_goal")

HAS_PYGAME = importlib.util.find_spec("pygame") is not None
STEP_S = 0.02
"""50 steps a second, as `SimRobotFactory` takes by default."""


@dataclass
class Drive:
    """What happened in one run: the true path, the bumps and every command the brain gave."""

    robot: DiffDriveRobot
    clock: SimClock
    path: List[Tuple[float, float]] = field(default_factory=list)
    bumped_steps: int = 0
    commands: int = 0

    def length_m(self) -> float:
        return sum(math.dist(a, b) for a, b in zip(self.path, self.path[1:]))


def drive(brain: AbstractFactory, world: World, seconds: float, seed: int = 1) -> Drive:
    """Run ``brain`` and the simulated robot as one node for ``seconds`` of simulated time.

    The node is what a lesson's ``run()`` builds, without the view: the robot
    (`SimRobotFactory`), the lesson's endpoint and a `TimeoutLoopFactory`, on a
    `SimClock` as fast as it goes. Each physics step stores a ``true_pose`` and
    a ``bump`` page, which a collector keeps for grading.
    """
    clock = SimClock()
    robot = SimRobotFactory(world, seed=seed)
    pages = PageCollectorFactory([TRUE_POSE, BUMP, WHEEL_CMD])
    # The brains' handlers are quick, but may wait for a busy machine's CPU.
    components = [
        robot,
        brain,
        TimeoutLoopFactory(seconds=seconds),
        pages,
        SlowHandlerLimitFactory(),
    ]
    runner = TestRunner("sim", Config({"sim": components}, mode=Mode.TEST, clock=clock), 30.0)
    runner.run()
    if runner.timed_out:
        raise AssertionError(f"the node did not stop by itself: {clock!r}")
    if clock() != seconds:
        raise AssertionError(f"the node stopped at {clock()} simulated s, not {seconds}")
    run = Drive(robot.robot, clock)
    run.path = [(pose["x"], pose["y"]) for pose in pages.data(TRUE_POSE)]  # type: ignore[index]
    run.bumped_steps = sum(1 for pressed in pages.data(BUMP) if pressed)
    run.commands = len(pages.data(WHEEL_CMD))
    return run


class TestWallFollower(unittest.TestCase):
    def test_a_minute_along_the_walls_without_a_bump(self) -> None:
        world = wall_follower.make_world()
        run = drive(wall_follower.WallFollowerFactory(), world, seconds=60.0)
        self.assertEqual(len(run.path), 3001, "a step every 20 simulated ms, 0 s to 60 s")
        self.assertEqual(run.bumped_steps, 0, "it touched a wall")
        self.assertGreater(run.commands, 2900, "the brain steered every step")
        # Round the room: about 14 m, past the divider (x = 2.6) and back west.
        self.assertGreater(run.length_m(), 12.0)
        self.assertGreater(max(x for x, _ in run.path), 3.4, "it never got round the divider")
        # Along a wall all the time (after the first second): never in open floor.
        clearances = [world.clearance_m(x, y) for x, y in run.path[50:]]
        self.assertGreater(min(clearances), 0.18, "too close to a wall")
        self.assertLess(max(clearances), 0.5, "it left the wall")
        # What makes it fast: simulated time jumped from tick to tick and never
        # waited on the wall clock (the speed is measured by bench/bench_sim.py).
        self.assertEqual(run.clock.jumps, 3000)
        self.assertEqual((run.clock.wall_waits, run.clock.paced_waits), (0, 0))

    def test_the_example_runs_the_shipped_solution(self) -> None:
        """``examples/lessons/`` runs the lessons' solutions, as ``demo --sim`` does lesson 1's."""
        from snr.extras.lessons.l01_wall_follower import solution as first
        from snr.extras.lessons.l02_go_to_goal import solution as second

        self.assertIs(wall_follower.main, first.main)
        self.assertIs(go_to_goal.main, second.main)


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


class TestSameSeedSamePages(unittest.TestCase):
    """Two runs with the same seed record the same pages, byte for byte."""

    def record(self, folder: Path, name: str, seed: int) -> bytes:
        path = folder / f"{name}.jsonl"
        keys = [RANGE, BUMP, WHEEL_ENCODERS, ODOMETRY, TRUE_POSE, WHEEL_CMD]
        components = [
            SimRobotFactory(wall_follower.make_world(), seed=seed),
            wall_follower.WallFollowerFactory(),
            RecorderEndpointFactory(path, keys),
            TimeoutLoopFactory(seconds=5),
        ]
        config = Config({"sim": components}, mode=Mode.TEST, clock=SimClock())
        runner = TestRunner("sim", config, 30.0)
        runner.run()
        self.assertFalse(runner.timed_out)
        return path.read_bytes()

    def test_two_runs_with_one_seed_record_identical_pages(self) -> None:
        folder = Path(tempfile.mkdtemp(prefix="snr-sim-time-"))
        self.addCleanup(shutil.rmtree, folder, True)
        first = self.record(folder, "first", seed=1)
        second = self.record(folder, "second", seed=1)
        other_seed = self.record(folder, "other_seed", seed=2)
        lines = first.splitlines()
        # The header, then 6 pages a step (5 sensor pages and the brain's
        # command) for each of the 251 steps from 0 s to 5 s.
        self.assertEqual(len(lines), 1 + 6 * 251)
        self.assertIn(b'"created_at_s":5.0,', lines[-1])  # simulated time, epoch 0
        self.assertEqual(first, second, "the same seed recorded different pages")
        self.assertNotEqual(first, other_seed, "the seed changed nothing")


class TestRunAsAStudentDoes(SNRTestCase):
    """Each lesson's ``main`` in a real node, briefly (frames, no window)."""

    def run_main(self, lesson: Any, seconds: float, *options: str) -> Tuple[str, Path]:
        frames = Path(self.temp_file("frames"))
        out = io.StringIO()
        argv = ["lesson.py", "--seconds", str(seconds), "--frames", str(frames), *options]
        with captured_logs("snr.sim") as lines, contextlib.redirect_stdout(out):
            lesson.main(argv)
        # No warning, with pygame or without: without, the lesson says so on stdout.
        problems = [line for line in lines if not line.startswith("INFO")]
        self.assertEqual(problems, [], lines)
        return out.getvalue(), frames

    def test_the_wall_follower_sets_off_in_real_time(self) -> None:
        text, frames = self.run_main(wall_follower, 0.4)  # the default: --speed 1
        simulated_s, x = summary(r"After ([\d.]+) s the robot is at \(([\d.]+), ", text)
        self.assertEqual(simulated_s, 0.4, text)  # simulated time: however busy the machine
        self.assertGreater(x, 0.5, text)  # it set off east from x = 0.5
        if HAS_PYGAME:  # a frame at 0.0, 0.1, ... 0.4 simulated s, where it said
            self.assertIn(f"Pictures: PNG frames in {frames.resolve()}", text)
            self.assertEqual(len(list(frames.glob("frame_*.png"))), 5, "frames written")
        else:
            self.assertIn(NO_PICTURES, text)

    def test_without_pygame_a_lesson_says_so_once_and_promises_no_frames(self) -> None:
        for lesson in (wall_follower, go_to_goal):
            with self.subTest(lesson=lesson.__name__):
                with no_pygame():
                    text, frames = self.run_main(lesson, 0.2, "--speed", "0")
                self.assertEqual(text.count(NO_PICTURES), 1, text)
                self.assertNotIn("Pictures:", text)
                self.assertNotIn("frames", text)
                self.assertFalse(frames.exists(), f"{frames} was made, but nothing is drawn")

    def test_go_to_goal_sets_off_as_fast_as_it_can(self) -> None:
        text, _ = self.run_main(go_to_goal, 0.4, "--speed", "0")
        simulated_s, left_m = summary(r"After ([\d.]+) s the robot is ([\d.]+) m from", text)
        self.assertEqual(simulated_s, 0.4, text)
        self.assertLess(left_m, 3.9, text)  # it started 3.90 m away


def summary(pattern: str, text: str) -> Tuple[float, float]:
    """The simulated seconds and the position a lesson's last line gives."""
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
    # 1.5 simulated s at real speed, not the default 15: enough to set off and
    # draw frames (it runs beside other tests, so it costs no wall time).
    command = ["-m", "snr", "demo", "--sim", "--seconds", "1.5"]
    return folder, start_script(command, cwd=str(folder), env=env)


# `python -m snr demo --sim` where ``import pygame`` fails, as in a plain install.
RUN_SIM_DEMO_WITHOUT_PYGAME = (
    "import runpy, sys\n"
    "sys.modules['pygame'] = None  # import pygame: ImportError\n"
    "sys.argv = ['snr', 'demo', '--sim', *sys.argv[1:]]\n"
    "runpy.run_module('snr', run_name='__main__', alter_sys=True)\n"
)


def _start_sim_demo_without_pygame() -> Tuple[Path, StartedScript]:
    """``python -m snr demo --sim`` for 0.5 s in a temp folder, as if pygame were missing."""
    folder = Path(tempfile.mkdtemp(prefix="snr-sim-demo-no-pygame-"))
    command = ["-c", RUN_SIM_DEMO_WITHOUT_PYGAME, "--seconds", "0.5"]
    return folder, start_script(command, cwd=str(folder))


# Started when this module is imported (`early`); they run while other tests do.
SIM_DEMO = early(_start_sim_demo)
SIM_DEMO_WITHOUT_PYGAME = early(_start_sim_demo_without_pygame)


def setUpModule() -> None:
    SIM_DEMO()  # (started already, unless in a pytest-xdist worker)
    SIM_DEMO_WITHOUT_PYGAME()


@unittest.skipUnless(HAS_PYGAME, reason("pygame"))
class TestSimDemo(SNRTestCase):
    def test_python_m_snr_demo_sim_drives_the_rover_and_says_where_the_frames_are(self) -> None:
        folder, demo = SIM_DEMO()
        assert demo is not None
        result = demo.result()
        self.addCleanup(shutil.rmtree, folder, True)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        self.assertTrue(lines[0].startswith("SNR demo --sim: "), result.stdout)
        frames = (folder / "sim_frames").resolve()
        self.assertIn(f"Pictures: PNG frames in {frames}", lines)
        simulated_s, x = summary(r"After ([\d.]+) s the robot is at \(([\d.]+), ", lines[-1])
        self.assertEqual(simulated_s, 1.5, result.stdout)  # simulated time, at real speed
        self.assertGreater(x, 0.5, result.stdout)  # it set off from x = 0.5
        self.assertTrue(list(frames.glob("frame_*.png")), result.stdout)
        self.assertEqual(result.stderr, "", "quiet unless --verbose")
        self.assertNotIn("draws nothing", result.stdout)


class TestSimDemoWithoutPygame(unittest.TestCase):
    def test_it_drives_unseen_says_so_once_and_makes_no_frames_folder(self) -> None:
        folder, demo = SIM_DEMO_WITHOUT_PYGAME()
        result = demo.result()
        self.addCleanup(shutil.rmtree, folder, True)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        self.assertTrue(lines[0].startswith("SNR demo --sim: "), result.stdout)
        # One true thing: it runs without drawing, and how to get pictures.
        self.assertEqual(lines[1], NO_PICTURES, result.stdout)
        self.assertIn("Install pygame to see it", NO_PICTURES)
        self.assertEqual(result.stdout.count("draws nothing"), 1, result.stdout)
        self.assertNotIn("frames", result.stdout)
        self.assertEqual(result.stderr, "", "said once, on stdout; the log adds nothing")
        self.assertEqual(list(folder.iterdir()), [], "no sim_frames folder: nothing is drawn")
        simulated_s, x = summary(r"After ([\d.]+) s the robot is at \(([\d.]+), ", lines[-1])
        self.assertEqual(simulated_s, 0.5, result.stdout)
        self.assertGreater(x, 0.5, result.stdout)  # it drove all the same


if __name__ == "__main__":
    unittest.main()
