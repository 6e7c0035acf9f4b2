"""Lesson 3: the lidar (`ScanSensor`) and the perception-based drop-in for lesson 1.

The scan: its rays, its 0.0 for no echo, its seed, its rate in a node, and
that adding it changes nothing else in a run. The lesson: the solution
passes, the starter fails with checks that say why, a copy of lesson 1's
solution fails with the drop-in check, and ``nearest_echo`` reads a scan as
its docstring says. (tests/test_lesson_command.py runs lesson 3 with the
others: the renamed copy, the page's ``$`` lines.)
"""

from __future__ import annotations

import contextlib
import io
import math
import random
import tempfile
import time
import unittest
from pathlib import Path
from typing import Any, Dict, List

from snr import Config, Mode, SimClock, SimRobotFactory, TimeoutLoopFactory, World
from snr.core import TestRunner
from snr.extras.lessons import lesson
from snr.extras.lessons.command import grade_file
from snr.extras.lessons.l03_scan_follower import solution
from snr.extras.lessons.l03_scan_follower.solution import nearest_echo
from snr.extras.sim import Pose, ScanSensor, SimViewFactory
from snr.extras.sim.draw import Scene
from snr.prelude import ComponentError
from tests.examples_support import example_path, load_module
from tests.optional import needs
from tests.page_collector import PageCollectorFactory
from tests.quiet import captured_logs

PERFECT = ScanSensor(noise_m=0.0, dropout=0.0)


def node_pages(seconds: float, **robot: Any) -> Dict[str, List[Any]]:
    """The ``scan``, ``range`` and ``true_pose`` pages of a robot driving ``seconds`` in a box."""
    world = World.box(4.0, 3.0)
    world.start = (1.0, 1.0, 0.0)
    pages = PageCollectorFactory(["scan", "range", "true_pose"])
    components = [
        SimRobotFactory(world, seed=3, **robot),
        TimeoutLoopFactory(seconds=seconds),
        pages,
    ]
    config = Config({"sim": components}, mode=Mode.TEST, clock=SimClock())
    TestRunner("sim", config, timeout_s=30.0).run()
    kept: Dict[str, List[Any]] = {"scan": [], "range": [], "true_pose": []}
    for page in pages.pages:
        kept[page.key].append(page.data)
    return kept


class TestScanSensor(unittest.TestCase):
    def test_72_rays_all_round_none_straight_ahead_or_to_the_side(self) -> None:
        angles = ScanSensor().angles_deg()
        self.assertEqual(len(angles), 72)
        self.assertEqual((angles[0], angles[-1]), (-177.5, 177.5))
        self.assertNotIn(-90.0, angles)
        self.assertNotIn(0.0, angles)

    def test_each_ray_sees_the_nearest_wall_and_no_echo_reads_zero(self) -> None:
        box = World.box(4.0, 3.0)
        scan = ScanSensor(rays=4, noise_m=0.0, dropout=0.0).read(
            box, Pose(1.0, 1.0, 0.0), random.Random(0)
        )
        self.assertEqual(scan["angles_deg"], [-135.0, -45.0, 45.0, 135.0])
        self.assertEqual(scan["ranges_m"], [1.414, 1.414, 2.828, 1.414])
        short = ScanSensor(rays=4, max_range_m=2.0, noise_m=0.0, dropout=0.0)
        far = short.read(box, Pose(1.0, 1.0, 0.0), random.Random(0))["ranges_m"]
        self.assertEqual(far[2], 0.0, "nothing within 2 m that way: no echo")

    def test_noise_and_lost_echoes_are_seeded(self) -> None:
        box, pose = World.box(4.0, 3.0), Pose(1.0, 1.0, 0.3)
        first = ScanSensor().read(box, pose, random.Random(5))
        self.assertEqual(first, ScanSensor().read(box, pose, random.Random(5)))
        self.assertNotEqual(first, ScanSensor().read(box, pose, random.Random(6)))
        exact = PERFECT.read(box, pose, random.Random(5))["ranges_m"]
        errors = [abs(a - b) for a, b in zip(first["ranges_m"], exact) if a > 0]
        self.assertLess(max(errors), 0.05)  # 1 cm noise, and never a wrong wall
        lost = 0
        for seed in range(20):
            lost += ScanSensor().read(box, pose, random.Random(seed))["ranges_m"].count(0.0)
        self.assertTrue(20 <= lost <= 80, f"{lost} of 1440 rays lost: about 3 %")

    def test_a_bad_setting_is_refused_with_what_to_give(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            ScanSensor(rays=0)
        self.assertIn("give at least one ray", str(caught.exception))
        with self.assertRaises(ComponentError):
            ScanSensor(dropout=1.0)

    def test_in_a_node_10_scans_a_second_and_no_range_page_when_it_has_none(self) -> None:
        pages = node_pages(1.0, range_sensor=False, scan_sensor=ScanSensor())
        self.assertEqual(pages["range"], [])
        steps = len(pages["true_pose"])
        self.assertGreaterEqual(steps, 50)
        self.assertEqual(len(pages["scan"]), math.ceil(steps / 5))  # the first step, then 1 in 5
        self.assertEqual(len(pages["scan"][0]["ranges_m"]), 72)
        plain = node_pages(1.0)
        self.assertEqual(plain["scan"], [], "no lidar unless one is given")
        self.assertEqual(len(plain["range"]), steps)

    def test_a_lidar_changes_nothing_else_in_a_run(self) -> None:
        plain = node_pages(0.5)
        with_scan = node_pages(0.5, scan_sensor=ScanSensor())
        self.assertEqual(plain["range"], with_scan["range"])  # its own random numbers
        self.assertEqual(plain["true_pose"], with_scan["true_pose"])
        self.assertEqual(with_scan["scan"], node_pages(0.5, scan_sensor=ScanSensor())["scan"])


class TestTheView(unittest.TestCase):
    def test_it_reads_the_distance_pages_the_robot_stores_and_no_other(self) -> None:
        world = World.box(4.0, 3.0)
        world.start = (1.0, 1.0, 0.0)
        lidar_only = SimRobotFactory(world, range_sensor=False, scan_sensor=ScanSensor())
        self.assertEqual(lidar_only.sensor_keys, ["scan"])
        self.assertEqual(SimRobotFactory(world).sensor_keys, ["range"])
        view = SimViewFactory(world, sensor_keys=lidar_only.sensor_keys)
        scene = Scene(None, world, sensor_keys=view.sensor_keys)
        self.assertEqual(scene.keys, ("true_pose", "odometry", "scan", "bump"))
        self.assertEqual(Scene(None, world).keys, ("true_pose", "odometry", "range", "bump"))

    @needs("pygame")
    def test_the_lesson_drawn_for_6_s_hints_at_no_missing_key(self) -> None:
        # A view reading 'range' from a robot with none would log, after 5 s in
        # DEBUG mode, that nothing stores it: noise in a student's terminal.
        frames = Path(tempfile.mkdtemp(prefix="snr-lesson3-"))
        argv = ["scan_follower.py", "--seconds", "6", "--speed", "0", "--frames", str(frames)]
        with captured_logs("snr") as lines, contextlib.redirect_stdout(io.StringIO()) as out:
            solution.main(argv)
        self.assertIn("After 6.0 s the robot is at", out.getvalue())
        self.assertEqual([line for line in lines if "has been read" in line], [])
        self.assertGreater(len(list(frames.glob("frame_*.png"))), 50, "it drew the scan")
        for frame in frames.iterdir():
            frame.unlink()
        frames.rmdir()


class TestLesson3(unittest.TestCase):
    def test_the_solution_passes_on_lesson_1s_course_in_under_5_s(self) -> None:
        started = time.monotonic()
        checks = grade_file(lesson(3), lesson(3).folder / "solution.py")
        self.assertLess(time.monotonic() - started, 5.0)
        self.assertTrue(all(check.passed for check in checks), checks)
        names = [check.name for check in checks]
        for name in ("never touches a wall", "keeps the wall 0.35 m away", "goes round the room"):
            self.assertIn(name, names)  # lesson 1's own checks
        first = grade_file(lesson(1), lesson(1).folder / "solution.py")
        self.assertEqual(names[-3:], [check.name for check in first][-3:])

    def test_the_starter_fails_and_says_where(self) -> None:
        checks = grade_file(lesson(3), lesson(3).folder / "starter.py")
        failed = [check for check in checks if not check.passed]
        self.assertEqual(
            [check.name for check in failed],
            ["never touches a wall", "keeps the wall 0.35 m away", "goes round the room"],
        )
        self.assertIn("nearest echo", failed[1].hint)

    def test_lesson_1s_solution_is_no_drop_in_and_is_told_so(self) -> None:
        checks = grade_file(lesson(3), lesson(1).folder / "solution.py")
        self.assertEqual(
            [(check.name, check.passed) for check in checks],
            [
                ("the endpoint", False),
                ("runs without an exception", True),
                ("a drop-in: sees by the scan, not lesson 1's range rays", False),
            ],
        )
        drop_in = checks[-1]
        self.assertEqual(
            drop_in.happened,
            "WallFollowerEndpoint handles 'range' pages, lesson 1's ready-made rays; this "
            "robot has a lidar and no range sensor, so that handler never ran",
        )
        self.assertIn("handle 'scan' instead of 'range'", drop_in.hint)
        source = (lesson(1).folder / "solution.py").read_text("utf-8").splitlines()
        self.assertIn("def steer(", source[(drop_in.line or 0) - 1])

    def test_the_example_runs_the_shipped_solution(self) -> None:
        example = load_module(example_path("lessons", "scan_follower.py"), "lesson_scan_follower")
        self.assertIs(example.main, solution.main)

    def test_nearest_echo_skips_no_echo_and_other_angles(self) -> None:
        scan = {"angles_deg": [-97.5, -92.5, -87.5, 2.5], "ranges_m": [0.36, 0.0, 0.351, 0.2]}
        self.assertEqual(nearest_echo(scan, -135, -45), (0.351, -87.5))
        distance, angle = nearest_echo(scan, 100, 170)
        self.assertTrue(math.isinf(distance) and math.isnan(angle))


if __name__ == "__main__":
    unittest.main()
