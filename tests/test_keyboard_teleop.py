"""Keyboard teleop: the simulator window's arrow keys drive the rover through the
controller components (docs/simulator.md, "Drive it yourself"); and the window
drawn on the main thread, with the node on another (`run_in_window`).

Headless: SDL's dummy video driver gives the window, and the test posts key
events to it as a keyboard would.
"""

from __future__ import annotations

import importlib
import os
import threading
import time
import unittest
from typing import Any, Callable, Dict, List, Tuple

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # before pygame is imported
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

from snr import (
    AbstractFactory,
    Config,
    ControllerLoopFactory,
    InputMappingFactory,
    Mode,
    Node,
    SimRobotFactory,
    SimViewFactory,
    TimeoutLoopFactory,
    World,
)
from snr.extras.controller import KeyboardJoystick
from snr.extras.sim import SimViewLoop, StickDriveFactory, run_in_window
from snr.utils.mock_node import MockNode
from tests.optional import reason

try:
    pygame: Any = importlib.import_module("pygame")
except ImportError:
    pygame = None


def wait_for(condition: Callable[[], Any], timeout_s: float = 5.0) -> Any:
    deadline = time.monotonic() + timeout_s
    while not condition() and time.monotonic() < deadline:
        time.sleep(0.01)
    return condition()


def teleop_rover() -> Tuple[SimRobotFactory, SimViewFactory, List[AbstractFactory]]:
    """A simulated rover, its window, and the keyboard teleop path that drives it."""
    world = World.box(4.0, 3.0)
    view = SimViewFactory(world, window=True, rate_hz=50)
    teleop: List[AbstractFactory] = [
        ControllerLoopFactory("raw_controller_input", view.keyboard, max_tick_rate_hz=50),
        InputMappingFactory("raw_controller_input", "controller_input"),
        StickDriveFactory("controller_input"),
    ]
    return SimRobotFactory(world, seed=1), view, teleop


def window_of(node: Node) -> Any:
    view = node.components.get("sim_view")
    return view.window if isinstance(view, SimViewLoop) else None


class TestStickDrive(unittest.TestCase):
    def wheels(self, controls: Dict[str, Any]) -> Dict[str, float]:
        return StickDriveFactory().get(MockNode()).wheels(controls)

    def test_forward_turn_and_rest(self) -> None:
        self.assertEqual(self.wheels({"left_stick_Y": -1.0}), {"left": 0.3, "right": 0.3})
        self.assertEqual(self.wheels({"left_stick_X": 1.0}), {"left": 0.15, "right": -0.15})
        rest = self.wheels({"left_stick_X": 0.0, "left_stick_Y": 0.0})
        self.assertEqual(repr(rest), "{'left': 0.0, 'right': 0.0}")  # not -0.0
        self.assertEqual(self.wheels({"left_stick_Y": "up", "A": 1}), rest)  # not a number


@unittest.skipIf(pygame is None, reason("pygame"))
class TestKeyboardJoystick(unittest.TestCase):
    def test_keys_move_the_left_stick_and_focus_loss_lets_go(self) -> None:
        keys = KeyboardJoystick()
        self.assertTrue(keys.handle(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_w)))
        self.assertTrue(keys.handle(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_LEFT)))
        self.assertFalse(keys.handle(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_q)))
        self.assertEqual((keys.get_axis(0), keys.get_axis(1)), (-1.0, -1.0))
        keys.handle(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_SPACE))
        self.assertEqual(keys.get_button(2), 1)
        keys.handle(pygame.event.Event(pygame.KEYUP, key=pygame.K_LEFT))
        self.assertEqual(keys.get_axis(0), 0.0)
        self.assertTrue(keys.handle(pygame.event.Event(pygame.WINDOWFOCUSLOST)))
        self.assertEqual((keys.get_axis(1), keys.get_button(2)), (0.0, 0))


@unittest.skipIf(pygame is None, reason("pygame"))
class TestTeleopInTheSimulatorWindow(unittest.TestCase):
    def test_arrow_keys_drive_the_rover_and_letting_go_stops_it(self) -> None:
        sim, view, teleop = teleop_rover()
        node = Node("sim", Config({"sim": [sim, view, *teleop]}, mode=Mode.TEST))
        thread = threading.Thread(target=node.loop, name="teleop-node", daemon=True)
        thread.start()
        try:
            self.assertTrue(wait_for(lambda: window_of(node) is not None), "no window")
            start_x = sim.robot.pose.x
            pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_UP))
            forward = {"left": 0.3, "right": 0.3}
            self.assertTrue(wait_for(lambda: node.get_data("wheel_cmd") == forward))
            self.assertTrue(wait_for(lambda: sim.robot.pose.x > start_x + 0.01), "it did not move")
            pygame.event.post(pygame.event.Event(pygame.KEYUP, key=pygame.K_UP))
            stop = {"left": 0.0, "right": 0.0}
            self.assertTrue(wait_for(lambda: node.get_data("wheel_cmd") == stop))
        finally:
            node.set_terminate_flag("test finished")
            thread.join(5.0)
        self.assertFalse(thread.is_alive())


@unittest.skipIf(pygame is None, reason("pygame"))
class TestWindowOnTheMainThread(unittest.TestCase):
    """What ``python -m snr demo --sim`` does on every platform (macOS requires it)."""

    def test_the_window_is_drawn_and_read_here_while_the_node_runs_beside_it(self) -> None:
        sim, view, teleop = teleop_rover()
        components = [sim, *teleop, TimeoutLoopFactory(seconds=10.0)]  # if it never closes
        start_x = sim.robot.pose.x
        seen: Dict[str, Any] = {}

        def keyboard_user() -> None:  # presses Up, then closes the window
            if wait_for(lambda: pygame.display.get_init() and pygame.display.get_surface()):
                seen["window"] = pygame.display.get_surface().get_size()
                pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_UP))
                seen["moved"] = wait_for(lambda: sim.robot.pose.x > start_x + 0.01)
            pygame.event.post(pygame.event.Event(pygame.QUIT))

        user = threading.Thread(target=keyboard_user, daemon=True)
        user.start()
        node = run_in_window("sim", Config({"sim": components}, mode=Mode.TEST), view)
        user.join(5.0)
        self.assertIs(threading.current_thread(), threading.main_thread())
        self.assertEqual(seen.get("window"), view.scene(pygame).view.size_px)
        self.assertTrue(seen.get("moved"), "the keys did not drive the rover")
        self.assertEqual(node.terminate_reason, "simulator window closed")
        self.assertFalse(pygame.display.get_init(), "the window was not closed")
