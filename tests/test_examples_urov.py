"""The UROV example (thesis 5.1): its parts in snr.extras.demo and examples/urov/main.py.

tests/test_demo.py runs it as `python -m snr demo`.
"""

import unittest
from typing import Any

import snr.extras.demo.urov
from snr import Mode, SNRTestCase, TaskType, tasks
from snr.utils import ListReplayerFactory
from tests.examples_support import early, example_path, load_module, start_script
from tests.helpers import StopWhenFactory, free_port

# Started when this module is imported (`early`); it runs while other tests do.
VEHICLE_ALONE = early(
    lambda: start_script(
        [example_path("urov", "main.py"), "urov", "--port", str(free_port()), "--seconds", "1"]
    )
)


def setUpModule() -> None:
    VEHICLE_ALONE()  # (started already, unless in a pytest-xdist worker)


class TestUrovParts(SNRTestCase):
    urov: Any = snr.extras.demo.urov

    def test_mixing_of_surge_yaw_heave(self) -> None:
        node = self.mock_node()
        mixer = self.urov.ControlsProcessorFactory("cmd", "speed").get(node)
        out = mixer.mix(tasks.store_data("cmd", {"surge": 0.5, "yaw": 0.25, "heave": -1}), None)
        self.assertEqual(out.val_list[0].data, {"left": 75, "right": 25, "vertical": -100})
        with self.assertLogs("snr.mock", "WARNING"):
            self.assertIsNone(mixer.mix(tasks.store_data("cmd", [1, 2]), None))

    def test_motor_board_parses_lines_and_ignores_garbage(self) -> None:
        vehicle = self.urov.Vehicle()
        board = self.urov.MotorBoard(vehicle)
        for line in ["M,10,-20,300", "garbage", "M,1,2", "M,a,b,c", ""]:
            board.handle_line(line)
        self.assertEqual(board.commands, 1)
        self.assertEqual(board.bad_lines, 4)
        self.assertEqual(vehicle.thrusters, {"left": 10, "right": -20, "vertical": 100})

    def test_vehicle_dives_and_turns(self) -> None:
        vehicle = self.urov.Vehicle()
        vehicle.set_thrusters(100, 0, -100)
        for _ in range(250):  # 5 s
            vehicle.step(0.02)
        self.assertGreater(vehicle.depth_m, 0.5)
        self.assertGreater(vehicle.heading_deg, 100)

    def test_one_node_with_both_pipelines_over_a_real_pty(self) -> None:
        """The whole data flow without sockets: sticks to thrusters to sensors."""
        u = self.urov
        depth_raw = (TaskType.store_page, "depth_raw")

        def diving() -> bool:
            # The vehicle starts at the surface (0 m, never less): any depth is the dive.
            return bool(u.motor_board.commands >= 1 and u.vehicle.depth_m > 0.01)

        node = self.run_test_node(
            [
                ListReplayerFactory(
                    [{"axis_1": 0.0, "axis_2": 0.0, "axis_3": 1.0}], "raw", period_s=0.05
                ),
                u.InputProcessorFactory("raw", "controller_input"),
                u.ControlsProcessorFactory("controller_input", "motor_speed"),
                u.SerialConnectionFactory("motor_speed"),
                u.SensorReaderFactory(),
                # Checked at each sensor reading: stop once the board has dived the vehicle.
                StopWhenFactory(depth_raw, lambda task: diving()),
            ],
            mode=Mode.TEST,
            timeout_s=5,  # the simulated vehicle is 1 cm down about 0.2 s after the command
        )
        self.assertEqual(node.get_data("motor_speed"), {"left": 0, "right": 0, "vertical": -100})
        self.assertGreaterEqual(u.motor_board.commands, 1)
        self.assertEqual(u.motor_board.bad_lines, 0)
        self.assertGreater(u.vehicle.depth_m, 0.01)  # the motor board got the command


class TestUrovSystem(unittest.TestCase):
    def test_main_builds_both_roles_from_the_command_line(self) -> None:
        main = load_module(example_path("urov", "main.py"), "urov_example_main")
        components = main.make_components("127.0.0.1", 9100, seconds=3)
        self.assertEqual(sorted(components), ["topside", "urov"])
        names = [type(f).__name__ for f in components["urov"]]
        self.assertIn("SerialConnectionFactory", names)
        self.assertEqual(names[-1], "TimeoutLoopFactory")

    def test_vehicle_alone_gives_no_false_hint(self) -> None:
        """The first of two terminals: the vehicle runs before the pilot connects.

        Its telemetry reads 'motor_speed' long before any arrives; that is
        planned (the serial link handles those pages), not a misspelt 'speed'.
        run_script fails on any "Did you mean" line.
        """
        result = VEHICLE_ALONE().result()
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("terminated: Timeout", result.stderr)


if __name__ == "__main__":
    unittest.main()
