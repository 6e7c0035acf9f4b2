"""Thesis listing A.3, as printed (the test method is annotated for mypy)."""

import unittest

from snr import *


class TestMovingAvgEndpoint(SNRTestCase):
    def test_moving_avg_endpoint(self) -> None:
        input_data = "input_data"
        output_data = "filtered_Data"

        expectations = {
            (TaskType.store_page, input_data): 4,
            (TaskType.process_data, input_data): 4,
            (TaskType.store_page, output_data): 4,
            (TaskType.process_data, output_data): 4,
        }
        with self.expector(expectations) as expector:
            self.run_test_node(
                [
                    ListReplayerFactory([0, 1, 2, 4], input_data),
                    MovingAvgFilterFactory(input_data, output_data, 2),
                    ExpecterEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )


class TestMovingAvgListingsA1A2(SNRTestCase):
    """The endpoint and factory of listings A.1 and A.2, checked in detail."""

    def test_filter_values_and_state_on_factory(self) -> None:
        factory = MovingAvgFilterFactory("in", "out", 2)
        node = self.mock_node()
        endpoint = factory.get(node)
        outputs = []
        for value in [0, 1, 2, 4]:
            result = endpoint.update_filter(
                tasks.store_data("in", value), (TaskType.store_page, "in")
            )
            assert isinstance(result, Task)
            outputs.append(result.val_list[0].data)
        self.assertEqual(outputs, [0.0, 0.5, 1.5, 3.0])
        # A new endpoint from the same factory (as after a reload) keeps the samples.
        again = factory.get(node)
        self.assertEqual(again.filter.avg(), 3.0)

    def test_invalid_data_is_warned_and_ignored(self) -> None:
        endpoint = MovingAvgFilterFactory("in", "out").get(self.mock_node())
        with self.assertLogs("snr.mock", "WARNING"):
            self.assertIsNone(
                endpoint.update_filter(tasks.store_data("in", "abc"), (TaskType.store_page, "in"))
            )


if __name__ == "__main__":
    unittest.main()
