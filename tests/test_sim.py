"""The simulator's physics, driven directly (no node): world, robot, sensors."""

from __future__ import annotations

import json
import math
import random
import unittest
from typing import Any, Dict, List

from snr import SimRobotFactory, SNRTestCase, World
from snr.extras.sim import (
    DiffDriveRobot,
    Odometry,
    Pose,
    RangeSensor,
    RobotSpec,
    sensor_pages,
    wheel_command,
)
from snr.extras.sim.world import Segment, distance_to_segment_m, ray_segment_hit_m
from snr.prelude import ComponentError

DT_S = 0.02
PERFECT = RobotSpec(slip=0.0)


def room() -> World:
    world = World.box(4.0, 3.0)
    world.add_box(1.5, 1.0, 0.5, 0.5)
    return world


class TestGeometry(unittest.TestCase):
    def test_a_ray_meets_a_wall_ahead_not_behind_or_beside(self) -> None:
        wall = Segment(2.0, -1.0, 2.0, 1.0)
        self.assertAlmostEqual(ray_segment_hit_m(0, 0, 1, 0, wall) or 0, 2.0)
        self.assertIsNone(ray_segment_hit_m(0, 0, -1, 0, wall))  # behind the ray
        self.assertIsNone(ray_segment_hit_m(0, 2, 1, 0, wall))  # passes the wall's end
        self.assertIsNone(ray_segment_hit_m(0, 0, 0, 1, Segment(1, 0, 1, 0.5)))  # parallel

    def test_distance_to_a_wall_clamps_to_its_ends(self) -> None:
        wall = Segment(-1.0, 0.0, 1.0, 0.0)
        self.assertAlmostEqual(distance_to_segment_m(0, 1, wall), 1.0)
        self.assertAlmostEqual(distance_to_segment_m(3, 0, wall), 2.0)
        self.assertAlmostEqual(distance_to_segment_m(4, 4, Segment(1, 1, 1, 1)), math.hypot(3, 3))

    def test_the_world_answers_rays_and_clearance(self) -> None:
        world = room()
        self.assertAlmostEqual(world.ray_hit_m(1.0, 1.25, 0.0, 10.0), 0.5)  # the crate
        self.assertAlmostEqual(world.ray_hit_m(1.0, 0.5, 0.0, 10.0), 3.0)  # the east wall
        self.assertEqual(world.ray_hit_m(1.0, 0.5, 0.0, 2.0), 2.0)  # out of range
        self.assertAlmostEqual(world.clearance_m(1.0, 0.5), 0.5)
        self.assertEqual(world.bounds(), (0.0, 0.0, 4.0, 3.0))


class TestWorldFile(SNRTestCase):
    def write(self, data: Any) -> str:
        path = self.temp_file("world.json")
        with open(path, "w", encoding="utf-8") as f:
            f.write(data if isinstance(data, str) else json.dumps(data))
        return path

    def test_walls_boxes_start_and_goal_are_read(self) -> None:
        world = World.load(
            self.write(
                {
                    "name": "lab",
                    "walls": [[0, 0, 4, 0]],
                    "boxes": [[1, 1, 0.5, 0.5]],
                    "start": [0.5, 0.5, 1.5],
                    "goal": [3, 2],
                }
            )
        )
        self.assertEqual(world.name, "lab")
        self.assertEqual(len(world.walls), 5)  # one wall, and a box's four
        self.assertEqual(world.walls[0], Segment(0.0, 0.0, 4.0, 0.0))
        self.assertEqual(world.start, (0.5, 0.5, 1.5))
        self.assertEqual(world.goal, (3.0, 2.0))

    def test_mistakes_name_the_file_the_wall_and_the_fix(self) -> None:
        cases = [
            ('{"walls": [[0, 0, 4]]}', "wall 0 is [0, 0, 4]; write it as 4 numbers"),
            ('{"walls": [[0, 0, 4, 0]], "start": [1, "a", 0]}', "start is"),
            ('{"walls": [[0, 0, 4, 0]], "wals": []}', "unknown field(s) ['wals']"),
            ('{"boxes": []}', "the world has no walls"),
            ('{"walls": [[0, 0, 4, 0]],\n]', "is not valid JSON"),
            ("[1, 2]", "a world is a JSON object"),
        ]
        for text, expected in cases:
            path = self.write(text)
            with self.subTest(text=text), self.assertRaises(ComponentError) as caught:
                World.load(path)
            self.assertIn(expected, str(caught.exception))
            self.assertIn("world.json", str(caught.exception))
        with self.assertRaisesRegex(ComponentError, "Cannot read the world file"):
            World.load(self.write("{}") + ".missing")


def drive(robot: DiffDriveRobot, world: World, seconds: float) -> None:
    for _ in range(round(seconds / DT_S)):
        robot.step(DT_S, world)


class TestRobot(unittest.TestCase):
    def test_it_speeds_up_within_the_limits_then_cruises(self) -> None:
        robot = DiffDriveRobot(PERFECT, Pose(0.5, 1.5, 0.0))
        robot.command(9.0, 9.0)  # clipped to 0.5 m/s
        robot.step(DT_S, World.box(4, 3))
        self.assertAlmostEqual(robot.wheel_speeds_m_s[0], 0.02)  # 1 m/s² for 20 ms
        drive(robot, World.box(4, 3), 0.98)
        self.assertEqual(robot.wheel_speeds_m_s, (0.5, 0.5))
        # 25 steps speeding up (0.02 .. 0.5 m/s), then 25 at 0.5 m/s: 0.13 + 0.25 m
        self.assertAlmostEqual(robot.pose.x, 0.5 + 0.38)
        self.assertAlmostEqual(robot.pose.y, 1.5)

    def test_opposite_wheels_spin_it_on_the_spot(self) -> None:
        robot = DiffDriveRobot(PERFECT, Pose(1.0, 1.0, 0.0))
        robot.command(-0.1, 0.1)
        drive(robot, World.box(4, 3), 1.0)
        self.assertAlmostEqual(robot.pose.x, 1.0)
        self.assertAlmostEqual(robot.pose.y, 1.0)
        self.assertGreater(robot.pose.theta, 0.3)  # anticlockwise: to its left
        left, right = robot.encoder_ticks
        self.assertLess(left, 0)
        self.assertGreater(right, 0)

    def test_a_wall_stops_it_and_presses_the_bumper(self) -> None:
        world = World.box(4, 3)
        robot = DiffDriveRobot(RobotSpec(), Pose(3.0, 1.0, 0.2), seed=3)
        robot.command(0.5, 0.5)
        closest = math.inf
        for _ in range(200):  # 4 s: long enough to reach the wall 1 m ahead
            robot.step(DT_S, world)
            closest = min(closest, world.clearance_m(robot.pose.x, robot.pose.y))
        self.assertGreaterEqual(closest, robot.spec.radius_m)  # never in the wall
        self.assertTrue(robot.bumped)
        self.assertAlmostEqual(robot.pose.x, 4.0 - robot.spec.radius_m, places=2)
        robot.command(-0.3, -0.3)  # backing off frees it
        drive(robot, world, 0.5)
        self.assertFalse(robot.bumped)

    def test_too_long_a_step_is_refused(self) -> None:
        robot = DiffDriveRobot(RobotSpec(), Pose(1.0, 1.0, 0.0))
        with self.assertRaisesRegex(ComponentError, "could pass through a wall"):
            robot.step(0.5, World.box(4, 3))
        with self.assertRaisesRegex(ComponentError, "higher rate_hz"):
            SimRobotFactory(World.box(4, 3), rate_hz=5)
        with self.assertRaisesRegex(ComponentError, "from a wall"):
            SimRobotFactory(World(walls=[Segment(0, 0, 4, 0)], start=(1.0, 0.05, 0.0)))
        with self.assertRaisesRegex(ComponentError, "must be > 0"):
            RobotSpec(radius_m=0)


class TestSensors(unittest.TestCase):
    def test_rays_see_the_nearest_wall_in_each_direction(self) -> None:
        sensor = RangeSensor(angles_deg=(-90.0, 0.0, 90.0, 180.0), max_range_m=2.5, noise_m=0.0)
        ranges = sensor.read(World.box(4, 3), Pose(1.0, 1.0, 0.0), random.Random(0))
        self.assertEqual([round(r, 6) for r in ranges], [1.0, 2.5, 2.0, 1.0])

    def test_odometry_follows_the_truth_without_slip_and_drifts_with_it(self) -> None:
        for slip, expect_close in ((0.0, True), (0.1, False)):
            robot = DiffDriveRobot(RobotSpec(slip=slip), Pose(1.0, 1.0, 0.0), seed=2)
            odometry = Odometry(robot.spec, robot.pose)
            robot.command(0.3, 0.25)
            for _ in range(150):
                robot.step(DT_S, World.box(4, 3))
                odometry.update(*robot.encoder_ticks)
            error = math.hypot(odometry.pose.x - robot.pose.x, odometry.pose.y - robot.pose.y)
            with self.subTest(slip=slip):
                if expect_close:
                    self.assertLess(error, 0.002)  # one tick is 0.5 mm
                else:
                    self.assertGreater(error, 0.004)  # 8 ticks: slip, not rounding

    def test_a_wheel_command_is_a_dict_or_a_pair_of_numbers(self) -> None:
        self.assertEqual(wheel_command({"left": 0.2, "right": -0.2}), (0.2, -0.2))
        self.assertEqual(wheel_command([1, 2]), (1.0, 2.0))
        for bad in (None, "go", {"left": 1}, [True, 1], [math.nan, 0], [1, 2, 3]):
            self.assertIsNone(wheel_command(bad), bad)


def run(seed: int, steps: int = 300) -> List[Dict[str, Any]]:
    """A wall-following run of ``steps`` steps; the pages of every step."""
    world = room()
    robot = DiffDriveRobot(RobotSpec(), Pose(*world.start), seed=seed)
    odometry = Odometry(robot.spec, robot.pose)
    sensor = RangeSensor()
    recorded = []
    for _ in range(steps):
        pages = sensor_pages(robot, world, sensor, odometry)
        recorded.append(pages)
        ahead = pages["range"]["ranges_m"][2]
        robot.command(*((0.4, 0.4) if ahead > 0.4 else (0.2, -0.2)))
        robot.step(DT_S, world)
    return recorded


class TestDeterminism(unittest.TestCase):
    def test_the_same_seed_gives_the_same_pages(self) -> None:
        first, second = run(seed=7), run(seed=7)
        self.assertEqual(first, second)
        self.assertNotEqual(first, run(seed=8))  # the noise is really there
        # and the run went somewhere
        self.assertGreater(first[-1]["true_pose"]["x"], first[0]["true_pose"]["x"] + 0.5)


if __name__ == "__main__":
    unittest.main()
