"""Game controller modules without pygame: simulated joystick, mapping, button events."""

from __future__ import annotations

import io
import sys
import unittest
from typing import Any, Callable, Dict, List, Tuple
from unittest import mock

from snr import (
    ControllerLoopFactory,
    ControlProcessorFactory,
    ExpectorEndpointFactory,
    InputMappingFactory,
    Joystick,
    Mode,
    Node,
    Page,
    PrinterEndpointFactory,
    SimulatedJoystick,
    SNRTestCase,
    Task,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)
from snr.extras.controller import (
    STEAM_CONTROLLER_BUTTONS,
    STEAM_CONTROLLER_MAPPING,
    ControlProcessorEndpoint,
)
from snr.extras.controller.joystick import read_joystick
from snr.prelude import ComponentError
from snr.prelude.install import install_hint
from tests.helpers import StopWhenTrueFactory

PRESSED = (TaskType.event, "button_pressed")
RELEASED = (TaskType.event, "button_released")


def stepping_clock(step_s: float) -> Callable[[], float]:
    """A clock that moves ``step_s`` each time it is read, whatever the wall time.

    A simulated joystick reads its clock once per control, so a script then
    plays in the same number of loop passes however busy the machine is.
    """
    now = [0.0]

    def clock() -> float:
        now[0] += step_s
        return now[0]

    return clock


class FixedClock:
    """A clock that shows whatever time the test sets."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def store_page_task(key: str, data: Any) -> Task:
    return tasks.store_page(Page(key, data, "test", 0.0))


class TestSimulatedJoystick(unittest.TestCase):
    def test_is_a_joystick_with_the_steam_controller_shape(self) -> None:
        pad = SimulatedJoystick()
        self.assertIsInstance(pad, Joystick)
        self.assertEqual((pad.get_numaxes(), pad.get_numbuttons(), pad.get_numhats()), (4, 21, 2))

    def test_plays_the_script_on_its_clock(self) -> None:
        clock = FixedClock()
        script = [(0.5, "button_2", 1), (1.0, "button_2", 0), (0.75, "axis_1", -0.5)]
        pad = SimulatedJoystick([*script, (0.75, "dhat_1", (1, 0))], clock=clock)
        self.assertEqual(pad.get_button(2), 0)  # the first read starts the clock
        clock.now += 0.5
        self.assertEqual(pad.get_button(2), 1)
        self.assertEqual(pad.get_axis(1), 0.0)
        clock.now += 0.25
        self.assertEqual((pad.get_axis(1), pad.get_hat(1)), (-0.5, (1, 0)))
        self.assertFalse(pad.finished)
        clock.now += 0.25
        self.assertEqual(pad.get_button(2), 0)
        self.assertTrue(pad.finished)

    def test_repeats_from_rest(self) -> None:
        clock = FixedClock()
        pad = SimulatedJoystick([(0.1, "button_0", 1)], repeat_after_s=1.0, clock=clock)
        pad.get_button(0)
        clock.now += 0.5
        self.assertEqual(pad.get_button(0), 1)
        clock.now += 0.55  # 1.05 s: a new cycle, at rest until 0.1 s into it
        self.assertEqual(pad.get_button(0), 0)
        clock.now += 10.0  # 11.05 s: far ahead, still in step
        self.assertEqual(pad.get_button(0), 0)
        clock.now += 0.1
        self.assertEqual(pad.get_button(0), 1)
        self.assertFalse(pad.finished)

    def test_restart(self) -> None:
        clock = FixedClock()
        pad = SimulatedJoystick([(0.1, "button_0", 1)], clock=clock)
        pad.get_button(0)
        clock.now += 1
        self.assertEqual(pad.get_button(0), 1)
        pad.restart()
        self.assertEqual(pad.get_button(0), 0)

    def test_default_script_presses_a_b_x_y(self) -> None:
        pad = SimulatedJoystick(clock=stepping_clock(0.001))
        pressed: List[int] = []
        for _ in range(10000):
            state = read_joystick(pad)
            pressed += [n for n in (2, 3, 4, 5) if state[f"button_{n}"] and n not in pressed]
            if pad.finished:
                break
        self.assertTrue(pad.finished)
        self.assertEqual(pressed, [2, 3, 4, 5])
        self.assertEqual(read_joystick(pad), read_joystick(SimulatedJoystick()))  # back at rest

    def test_read_joystick_names_every_control(self) -> None:
        state = read_joystick(SimulatedJoystick([], num_axes=1, num_buttons=2, num_hats=1))
        self.assertEqual(state, {"axis_0": 0.0, "button_0": 0, "button_1": 0, "dhat_0": [0, 0]})

    def test_bad_scripts_are_explained(self) -> None:
        cases: List[Tuple[Dict[str, Any], str]] = [
            ({"script": [(0.1, "button_21", 1)]}, "has 21 buttons"),
            ({"script": [(0.1, "trigger_0", 1)]}, "names no control"),
            ({"script": [(0.1, "axis_0", 2.0)]}, "from -1.0 to 1.0"),
            ({"script": [(0.1, "button_0", 5)]}, "0 (released) or 1"),
            ({"script": [(0.1, "dhat_0", 1)]}, "(x, y) pair"),
            ({"script": [(-1, "button_0", 1)]}, "0 or more"),
            ({"script": [(0.1, "button_0")]}, "triple"),
            ({"script": [(2.0, "button_0", 1)], "repeat_after_s": 1.0}, "later than"),
        ]
        for kwargs, words in cases:
            with self.subTest(kwargs=kwargs), self.assertRaises(ComponentError) as caught:
                SimulatedJoystick(**kwargs)
            self.assertIn(words, str(caught.exception))


class TestInputMapping(SNRTestCase):
    def test_default_mapping_is_the_steam_controller(self) -> None:
        node = self.mock_node()
        endpoint = InputMappingFactory("raw", "named").get(node)
        raw = {"button_2": 1, "button_10": 1, "axis_0": 0.5, "dhat_0": [0, 1]}
        result = endpoint.map_raw_input(store_page_task("raw", raw), (TaskType.store_page, "raw"))
        assert isinstance(result, Task)
        self.assertEqual(result.name, "named")
        self.assertEqual(result.val_list[0].data, {"A": 1, "left_stick_X": 0.5})
        self.assertEqual(STEAM_CONTROLLER_MAPPING["button_2"], "A")

    def test_custom_mapping(self) -> None:
        endpoint = InputMappingFactory("raw", "named", mapping={"dhat_0": "d_pad"}).get(
            self.mock_node()
        )
        result = endpoint.map_raw_input(
            store_page_task("raw", {"dhat_0": [0, 1], "button_2": 1}), (TaskType.store_page, "raw")
        )
        assert isinstance(result, Task)
        self.assertEqual(result.val_list[0].data, {"d_pad": [0, 1]})

    def test_bad_input_is_logged_and_dropped(self) -> None:
        endpoint = InputMappingFactory("raw", "named").get(self.mock_node())
        with self.assertLogs("snr", "WARNING") as logs:
            result = endpoint.map_raw_input(store_page_task("raw", 3), (TaskType.store_page, "raw"))
        self.assertIsNone(result)
        self.assertIn("dict of controls", logs.output[0])

    def test_mapping_giving_one_name_twice_is_an_error(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            InputMappingFactory(mapping={"button_0": "A", "button_1": "A"})
        self.assertIn("'button_0' and 'button_1'", str(caught.exception))


class TestControlProcessor(SNRTestCase):
    def process(self, endpoint: ControlProcessorEndpoint, data: Any) -> List[Tuple[str, str]]:
        result = endpoint.process_input(
            store_page_task("controller", data), (TaskType.store_page, "controller")
        )
        found = [] if result is None else [result] if isinstance(result, Task) else result
        return [(t.name, t.val_list[0]) for t in found]

    def test_first_input_is_the_baseline(self) -> None:
        endpoint = ControlProcessorFactory("controller").get(self.mock_node())
        self.assertEqual(self.process(endpoint, {"A": 1, "B": 0}), [])

    def test_pressed_and_released_in_watch_order(self) -> None:
        endpoint = ControlProcessorFactory("controller").get(self.mock_node())
        self.process(endpoint, {"B": 1, "A": 0, "X": 0})
        self.assertEqual(
            self.process(endpoint, {"B": 0, "A": 1, "X": 0}),
            [("button_pressed", "A"), ("button_released", "B")],
        )
        self.assertEqual(self.process(endpoint, {"B": 0, "A": 1, "X": 0}), [])
        self.assertEqual(self.process(endpoint, {"B": 0, "A": 0}), [("button_released", "A")])

    def test_only_watched_buttons_give_events(self) -> None:
        endpoint = ControlProcessorFactory("controller", watch_buttons=["A"]).get(self.mock_node())
        self.process(endpoint, {"A": 0, "B": 0, "left_stick_X": 1.0})
        self.assertEqual(self.process(endpoint, {"A": 1, "B": 1, "left_stick_X": 0.0}), [
            ("button_pressed", "A")
        ])  # fmt: skip

    def test_axes_are_not_buttons(self) -> None:
        # Listing A.7 compared every key: a stick going from 1.0 to 0 "released" it.
        endpoint = ControlProcessorFactory("controller").get(self.mock_node())
        self.process(endpoint, {"left_stick_X": 1.0, "A": 0})
        self.assertEqual(self.process(endpoint, {"left_stick_X": 0.0, "A": 0}), [])
        self.assertNotIn("left_stick_X", STEAM_CONTROLLER_BUTTONS)

    def test_previous_input_survives_a_rebuild(self) -> None:
        factory = ControlProcessorFactory("controller")
        node = self.mock_node()
        self.process(factory.get(node), {"A": 0})
        rebuilt = factory.get(node)  # what a hot reload does
        self.assertEqual(self.process(rebuilt, {"A": 1}), [("button_pressed", "A")])

    def test_bad_and_unknown_input_is_logged_not_fatal(self) -> None:
        endpoint = ControlProcessorFactory("controller").get(self.mock_node())
        with self.assertLogs("snr", "WARNING") as logs:
            self.assertEqual(self.process(endpoint, [1, 0]), [])
            self.assertEqual(self.process(endpoint, {"button_2": 1}), [])
            self.assertEqual(self.process(endpoint, {"button_2": 0}), [])
        self.assertIn("dict of buttons", logs.output[0])
        self.assertIn("has none of them", logs.output[1])
        self.assertEqual(len(logs.output), 2)  # the missing-names warning comes once

    def test_watch_buttons_must_be_names(self) -> None:
        with self.assertRaises(ComponentError):
            ControlProcessorFactory("controller", watch_buttons="A")


class TestControllerLoop(SNRTestCase):
    def test_simulated_pad_in_a_node_prints_figure_5_4_lines(self) -> None:
        pad = SimulatedJoystick(
            [
                (0.1, "button_2", 1),
                (0.2, "button_2", 0),
                (0.3, "button_5", 1),
                (0.4, "button_5", 0),
            ],
            clock=stepping_clock(0.001),  # 27 controls: about 0.027 s a pass
        )
        out = io.StringIO()
        with self.expector({PRESSED: 2, RELEASED: 2}) as expector:
            node = self.run_test_node([
                ControllerLoopFactory("raw_controller_data", joystick=pad, max_tick_rate_hz=200),
                InputMappingFactory("raw_controller_data", "controller_data"),
                ControlProcessorFactory("controller_data"),
                PrinterEndpointFactory([PRESSED, RELEASED], stream=out),
                ExpectorEndpointFactory(expector, exit_when_satisfied=True),
            ])  # fmt: skip
        self.assertEqual(
            out.getvalue().splitlines(),
            [
                "(event, 'button_pressed'): ['A']",
                "(event, 'button_released'): ['A']",
                "(event, 'button_pressed'): ['Y']",
                "(event, 'button_released'): ['Y']",
            ],
        )
        self.assertEqual((node.get_data("controller_data") or {}).get("Y"), 0)

    def test_state_is_stored_only_when_it_changes(self) -> None:
        step = stepping_clock(0.001)
        reads = [0]

        def clock() -> float:
            reads[0] += 1
            return step()

        pad = SimulatedJoystick([(0.05, "axis_0", 0.5)], clock=clock)
        # 100 passes (a pass reads the clock once per control): the state at
        # rest, then the one change, then no more stores
        controls = pad.num_axes + pad.num_buttons + pad.num_hats
        with self.expector({(TaskType.store_page, "raw"): 2}) as expector:
            node = self.run_test_node([
                ControllerLoopFactory("raw", joystick=pad, max_tick_rate_hz=2000),
                StopWhenTrueFactory(lambda: reads[0] >= 100 * controls, within_s=0.5),
                ExpectorEndpointFactory(expector),
            ])  # fmt: skip
        self.assertEqual((node.get_data("raw") or {}).get("axis_0"), 0.5)

    def test_not_a_joystick_is_explained(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            ControllerLoopFactory("raw", joystick=object())  # type: ignore[arg-type]
        self.assertIn("get_numaxes", str(caught.exception))

    def test_missing_pygame_is_explained(self) -> None:
        node = Node("test", self.get_config([TimeoutLoopFactory(seconds=1)], Mode.TEST))
        with (
            mock.patch.dict(sys.modules, {"pygame": None}),
            self.assertRaises(ComponentError) as caught,
        ):
            ControllerLoopFactory("raw").get(node)
        message = str(caught.exception)
        self.assertIn("pygame is not installed", message)
        self.assertIn(install_hint("controller"), message)
        self.assertIn("SimulatedJoystick()", message)
        node.terminate()


if __name__ == "__main__":
    unittest.main()
