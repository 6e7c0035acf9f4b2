"""Drawing the simulator (pygame, headless), and the simulator running in a node.

pygame draws on off-screen surfaces here: no screen is needed, and SDL's
dummy video driver is set in case anything asks for a window.
"""

from __future__ import annotations

import importlib
import os
import re
import unittest
from pathlib import Path
from typing import Any, Callable

os.environ["SDL_VIDEODRIVER"] = "dummy"  # before pygame is imported
os.environ["PYGAME_HIDE_SUPPORT_PROMPT"] = "1"

from snr import SimRobotFactory, SimViewFactory, SNRTestCase, TaskType, World
from snr.extras.sim import DiffDriveRobot, Odometry, Pose, RangeSensor, RobotSpec, sensor_pages
from snr.extras.sim.draw import WALL, WorldView, import_pygame, render_scene, save_png
from snr.prelude import ComponentError
from snr.prelude.install import install_hint
from tests.examples_support import example_path, load_module
from tests.helpers import StopWhenFactory, no_pygame
from tests.optional import needs, reason

try:
    pygame: Any = importlib.import_module("pygame")
except ImportError:
    pygame = None

rover: Any = load_module(example_path("rover", "main.py"), "rover_example_under_test")


def pixels_of(surface: Any, color: Any) -> int:
    """How many pixels of ``surface`` are (within 10 of) ``color``."""
    return int(pygame.mask.from_threshold(surface, color, (10, 10, 10, 255)).count())


@unittest.skipIf(pygame is None, reason("pygame"))
class TestPicture(SNRTestCase):
    def test_a_png_of_the_world_is_written_and_is_not_blank(self) -> None:
        world = World.load(example_path("rover", "room.json"))
        robot = DiffDriveRobot(RobotSpec(), Pose(*world.start), seed=1)
        pages = sensor_pages(robot, world, RangeSensor(), Odometry(robot.spec, robot.pose))
        path = Path(self.temp_file("world.png"))
        save_png(pygame, render_scene(pygame, WorldView(world), world, pages), path)

        picture = pygame.image.load(str(path))
        self.assertEqual(picture.get_size(), WorldView(world).size_px)
        robot_blue = (40, 90, 200)
        self.assertGreater(pixels_of(picture, WALL), 3000)  # the walls' outlines
        self.assertGreater(pixels_of(picture, robot_blue), 300)  # a 10 cm robot
        # The robot is drawn where it is: just behind its centre (facing +x,
        # a line marks its heading ahead of the centre) is robot blue.
        behind = WorldView(world).to_px(robot.pose.x - 0.05, robot.pose.y)
        self.assertEqual(tuple(picture.get_at(behind))[:3], robot_blue)


class TestInANode(SNRTestCase):
    def run_rover(
        self, view: SimViewFactory, drawn: Callable[[], bool] = lambda: True
    ) -> SimRobotFactory:
        """The rover example's brain drives the simulated robot for 40 steps.

        The node stops once 40 steps were taken and two frames written (or
        ``drawn()`` holds, in window mode).
        """
        sim = SimRobotFactory(World.load(example_path("rover", "room.json")), rate_hz=250)
        self.run_test_node(
            [
                sim,
                rover.WandererFactory(),
                view,
                StopWhenFactory(
                    (TaskType.store_page, "true_pose"),
                    when=lambda task: sim.steps >= 40 and view.frames_written >= 2 and drawn(),
                ),
            ],
            timeout_s=10,  # a bound for a busy machine: the node stops once the work is done
        )
        return sim

    @unittest.skipIf(pygame is None, reason("pygame"))
    def test_the_wanderer_drives_and_frames_are_written(self) -> None:
        frames = Path(self.temp_file("frames"))
        view = SimViewFactory(World.box(4, 3), frames_dir=frames, window=False, rate_hz=100)
        sim = self.run_rover(view)
        self.assertGreater(sim.robot.pose.x, 0.505)  # it set off forward from x = 0.5
        self.assertFalse(sim.robot.bumped)
        self.assertGreaterEqual(len(list(frames.glob("frame_*.png"))), 2)

    @unittest.skipIf(pygame is None, reason("pygame"))
    def test_a_window_is_drawn_and_closed_with_the_node(self) -> None:
        # SDL's dummy driver (set above) stands in for a screen.
        view = SimViewFactory(World.box(4, 3), window=True, rate_hz=100)
        drawn = {"count": 0}
        flip = pygame.display.flip

        def counting_flip() -> None:
            drawn["count"] += 1
            flip()

        pygame.display.flip = counting_flip
        try:
            view.frames_written = 2  # no frames in window mode: wait for a flip instead
            self.run_rover(view, drawn=lambda: drawn["count"] >= 1)
        finally:
            pygame.display.flip = flip
        self.assertGreaterEqual(drawn["count"], 1)
        self.assertFalse(pygame.display.get_init())  # the loop let the display go

    def test_without_pygame_it_runs_and_says_how_to_see_it(self) -> None:
        with no_pygame():
            with self.assertRaisesRegex(ComponentError, re.escape(install_hint("controller"))):
                import_pygame()
            view = SimViewFactory(World.box(4, 3), window=False, rate_hz=100)
            with self.assertLogs("snr", "WARNING") as logs:
                # Nothing to draw, so only the steps are waited for.
                view.frames_written = 2
                sim = self.run_rover(view)
        self.assertIn("draws nothing: pygame is not installed", "\n".join(logs.output))
        self.assertGreaterEqual(sim.steps, 40)


class TestRoverExample(unittest.TestCase):
    @needs("serial")  # the rover role's serial link is built with the config
    def test_sim_and_rover_differ_only_in_what_drives_the_wheels(self) -> None:
        roles = rover.make_components(seconds=1.0, port="loop://")
        kinds = {role: [type(f).__name__ for f in factories] for role, factories in roles.items()}
        self.assertEqual(
            kinds,
            {
                "sim": [
                    "SimRobotFactory",
                    "SimViewFactory",
                    "WandererFactory",
                    "TimeoutLoopFactory",
                ],
                "drive": [
                    "SimRobotFactory",
                    "SimViewFactory",
                    "ControllerLoopFactory",
                    "InputMappingFactory",
                    "StickDriveFactory",
                    "TimeoutLoopFactory",
                ],
                "rover": ["SerialLinkFactory", "WandererFactory", "TimeoutLoopFactory"],
            },
        )


if __name__ == "__main__":
    unittest.main()
