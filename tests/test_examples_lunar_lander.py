"""examples/lunar_lander: the descent, the controllers and the Q-learning trainer (5.3, A.4)."""

import functools
import os
import re
import unittest
from typing import Any, List, Tuple

from snr import AbstractFactory, SNRTestCase, TaskType, tasks
from tests.examples_support import example_path, load_module, run_script

MAIN = example_path("lunar_lander", "main.py")
lander = load_module(MAIN, "lunar_lander_example")


@functools.cache
def trained() -> Tuple[Any, int]:
    """A table trained once (3000 flights, seed 1) and the flights flown: two tests use it."""
    table = lander.QTable()
    flown = lander.train(table, episodes=3000, seed=1, time_limit_s=20)
    return table, flown


class TestPhysics(unittest.TestCase):
    def test_free_fall_crashes_and_keeps_its_fuel(self) -> None:
        flight = lander.fly(lambda radar: 0)
        self.assertFalse(flight.landed_safely())
        self.assertEqual(flight.fuel, lander.INITIAL_FUEL)
        self.assertIn("Crashed", flight.outcome())

    def test_fuel_runs_out_when_hovering_too_long(self) -> None:
        flight = lander.fly(lambda radar: 3)  # climbs until the tank is empty, then falls
        self.assertEqual(flight.fuel, 0)
        self.assertFalse(flight.landed_safely())

    def test_the_engine_cannot_use_fuel_it_does_not_have(self) -> None:
        module = lander.Lander(fuel=2)
        self.assertEqual(module.step(3), 2)
        self.assertEqual(module.step(3), 0)
        self.assertEqual(module.fuel, 0)

    def test_baseline_policy_lands_from_every_start(self) -> None:
        flight = lander.fly(lander.baseline_policy)
        self.assertTrue(flight.landed_safely(), flight.outcome())
        self.assertEqual(lander.landing_rate(lander.baseline_policy), 1.0)


class TestTrainer(unittest.TestCase):
    def test_training_really_improves_the_landing_rate(self) -> None:
        before = lander.landing_rate(lander.QTable().best_action)
        table, flown = trained()
        after = lander.landing_rate(table.best_action)
        self.assertEqual(flown, 3000)
        self.assertEqual(before, 0.0)  # untrained, it never fires the engine
        self.assertGreaterEqual(after, 0.9)

    def test_training_is_repeatable_with_a_seed(self) -> None:
        first, second = lander.QTable(), lander.QTable()
        lander.train(first, episodes=200, seed=5)
        lander.train(second, episodes=200, seed=5)
        self.assertEqual(first.values, second.values)


class TestLanderNode(SNRTestCase):
    def fly_node(self, controller: AbstractFactory, **radar_options: float) -> str:
        node = self.run_test_node(
            [
                lander.RadarSensorLoopFactory(speed=0, **radar_options),
                controller,
                lander.FlightDisplayFactory(quiet=True),
            ],
            timeout_s=10,
        )
        loops = [c for c in node.components.values() if hasattr(c, "is_alive")]
        self.assertFalse(any(loop.is_alive() for loop in loops))
        return str(node.terminate_reason)

    def test_baseline_controller_lands_exactly_as_the_simulation_says(self) -> None:
        reason = self.fly_node(lander.ControllerFactory(lander.baseline_policy))
        # The loop steps in lockstep with the controller, so the node's flight
        # is the same as flying the simulation directly.
        self.assertEqual(reason, lander.fly(lander.baseline_policy).outcome())
        self.assertTrue(reason.startswith("Landed safely"))

    def test_untrained_q_controller_crashes_without_an_exception(self) -> None:
        table = lander.QTable()
        reason = self.fly_node(lander.QLearningControllerEndpointFactory(table.q_value))
        self.assertTrue(reason.startswith("Crashed"), reason)

    def test_trained_q_controller_lands(self) -> None:
        table, _ = trained()
        reason = self.fly_node(lander.QLearningControllerEndpointFactory(table.q_value))
        self.assertEqual(reason, lander.fly(table.best_action).outcome())
        self.assertTrue(reason.startswith("Landed safely"), reason)

    def test_without_a_controller_the_loop_says_what_is_missing(self) -> None:
        node = self.run_test_node(
            [lander.RadarSensorLoopFactory(speed=0, command_timeout_s=0.05)], timeout_s=5
        )
        self.assertIn("No thruster_data for 0.05 s", str(node.terminate_reason))

    def test_bad_radar_data_is_logged_and_ignored(self) -> None:
        endpoint = lander.ControllerFactory(lander.baseline_policy).get(self.mock_node())
        for bad in ["high", (1.0,), ("a", "b"), (True, 1.0)]:
            with self.assertLogs("snr.mock", "WARNING"):
                result = endpoint.set_throttle(
                    tasks.store_data("radar_data", bad), (TaskType.store_page, "radar_data")
                )
            self.assertIsNone(result)


def readme_output(command: str) -> List[str]:
    """The output the README shows under ``command`` (up to a blank line or the next command)."""
    with open(os.path.join(os.path.dirname(MAIN), "README.md"), encoding="utf-8") as f:
        lines = f.read().splitlines()
    start = next(i for i, line in enumerate(lines) if line.split("#")[0].strip() == command)
    shown: List[str] = []
    for line in lines[start + 1 :]:
        if not line.strip() or line.startswith(("python ", "```")):
            break
        shown.append(line.rstrip())
    return shown


def matches_shown(output: List[str], shown: List[str]) -> bool:
    """``output`` is what ``shown`` shows, where a "..." line stands for any lines."""
    pattern = "\n".join(".*?" if line == "..." else re.escape(line) for line in shown)
    return re.fullmatch(pattern, "\n".join(output), re.S) is not None


class TestLanderScript(unittest.TestCase):
    def test_main_lands_and_prints_what_the_readme_shows(self) -> None:
        done = run_script([MAIN, "--speed", "0"])
        self.assertEqual(done.returncode, 0, done.stderr)
        output = [line.rstrip() for line in done.stdout.splitlines()]
        shown = readme_output("python main.py")
        self.assertTrue(matches_shown(output, shown), f"README shows {shown}, ran {output}")

    def test_a_crash_ends_with_a_message_not_a_traceback(self) -> None:
        done = run_script([MAIN, "--policy", "untrained", "--speed", "0"])
        self.assertEqual(done.returncode, 1)
        output = [line.rstrip() for line in done.stdout.splitlines()]
        shown = readme_output("python main.py --policy untrained")
        self.assertTrue(matches_shown(output, shown), f"README shows {shown}, ran {output}")
        self.assertIn("Crashed at", done.stdout.splitlines()[-1])
        self.assertIn("altitude", done.stdout)  # the telemetry lines
        self.assertNotIn("Traceback", done.stderr)

    def test_train_reports_the_landing_rates(self) -> None:
        done = run_script([MAIN, "--train"])
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertRegex(done.stdout, r"landing rate 0% before, (9\d|100)% after")


if __name__ == "__main__":
    unittest.main()
