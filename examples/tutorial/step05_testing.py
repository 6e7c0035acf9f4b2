"""Tutorial step 5: testing your component with expectors.

A test builds a small node around the component, feeds it data, and says
which tasks it expects. The node stops as soon as the expectations are met,
and leaving the ``with`` block fails the test unless every expected task
happened exactly as often as expected. A node still running after the time
limit (2 s unless told) fails the test.

    python step05_testing.py          # or: python -m unittest step05_testing -v

These tests check the converter of step 2 and the sensor loop of step 3.
"""

import unittest

from step02_pages_and_keys import CelsiusToFahrenheitFactory
from step03_a_loop import DepthSensorFactory

from snr import (
    ExpectorEndpointFactory,
    ListReplayerFactory,
    Mode,
    SNRTestCase,
    Task,
    TaskType,
    tasks,
)


class TestCelsiusToFahrenheit(SNRTestCase):
    def test_every_reading_is_converted(self) -> None:
        """Three readings in, three conversions out, then the node stops."""
        expectations = {
            (TaskType.store_page, "temperature_c"): 3,
            (TaskType.store_page, "temperature_f"): 3,
        }
        with self.expector(expectations) as expector:
            node = self.run_test_node(
                [
                    ListReplayerFactory([0, 100, -40], "temperature_c"),  # plays the list
                    CelsiusToFahrenheitFactory(),  # the component under test
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )
        # The stopped node's datastore holds the newest page under each key.
        self.assertPage(node.get_page("temperature_f"), "temperature_f", -40.0)

    def test_conversions_come_in_order(self) -> None:
        """An ordered expector checks the order of the tasks, too."""
        f = (TaskType.store_page, "temperature_f")
        c = (TaskType.store_page, "temperature_c")
        with self.ordered_expector([c, f, c, f]) as expector:
            self.run_test_node(
                [
                    ListReplayerFactory([0, 100], "temperature_c", period_s=0.01),
                    CelsiusToFahrenheitFactory(),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )

    def test_the_handler_alone_on_a_mock_node(self) -> None:
        """No running node at all: call the handler and look at what it returns."""
        converter = CelsiusToFahrenheitFactory().get(self.mock_node())
        result = converter.convert(
            tasks.store_data("temperature_c", 100), (TaskType.store_page, "temperature_c")
        )
        assert isinstance(result, Task)
        self.assertPage(result.val_list[0], "temperature_f", 212.0)

    def test_text_is_refused_politely(self) -> None:
        converter = CelsiusToFahrenheitFactory().get(self.mock_node())
        with self.assertLogs("snr.mock", "WARNING"):
            self.assertIsNone(
                converter.convert(
                    tasks.store_data("temperature_c", "hot"),
                    (TaskType.store_page, "temperature_c"),
                )
            )


class TestDepthSensorLoop(SNRTestCase):
    def test_the_loop_stores_readings(self) -> None:
        """A loop is tested the same way: expect five readings, in DEBUG mode."""
        with self.expector({(TaskType.store_page, "depth_m"): 5}) as expector:
            self.run_test_node(
                [
                    DepthSensorFactory(rate_hz=200),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ],
                mode=Mode.DEBUG,
                timeout_s=5,
            )


if __name__ == "__main__":
    unittest.main()
