"""Tests for the moving average filter (thesis listing A.3, and a few more).

Run them from this folder::

    python -m unittest test_moving_average
"""

import unittest

from moving_average import MovingAvgFilterFactory

from snr import (
    ExpectorEndpointFactory,
    ListReplayerFactory,
    SNRTestCase,
    Task,
    TaskType,
    tasks,
)


class TestMovingAvgEndpoint(SNRTestCase):
    def test_moving_avg_endpoint(self) -> None:
        """Listing A.3: four numbers in, four means out, then the node stops."""
        input_data = "input_data"
        output_data = "filtered_data"

        expectations = {
            (TaskType.store_page, input_data): 4,
            (TaskType.process_data, input_data): 4,
            (TaskType.store_page, output_data): 4,
            (TaskType.process_data, output_data): 4,
        }
        with self.expector(expectations) as expector:
            node = self.run_test_node(
                [
                    ListReplayerFactory([0, 1, 2, 4], input_data),
                    MovingAvgFilterFactory(input_data, output_data, 2),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )
        # The last mean is of the last two numbers: (2 + 4) / 2.
        self.assertPage(node.get_page(output_data), output_data, 3.0)

    def test_means_of_the_newest_samples(self) -> None:
        """Call the handler directly, on a mock node, to see each mean."""
        endpoint = MovingAvgFilterFactory("in", "out", 2).get(self.mock_node())
        means = []
        for value in [0, 1, 2, 4]:
            stored = tasks.store_data("in", value)
            result = endpoint.update_filter(stored, (TaskType.store_page, "in"))
            assert isinstance(result, Task)
            means.append(result.val_list[0].data)
        self.assertEqual(means, [0.0, 0.5, 1.5, 3.0])

    def test_samples_survive_a_rebuild(self) -> None:
        """A reload builds a new endpoint from the same factory: the samples stay."""
        factory = MovingAvgFilterFactory("in", "out", 3)
        node = self.mock_node()
        first = factory.get(node)
        first.update_filter(tasks.store_data("in", 6), (TaskType.store_page, "in"))
        second = factory.get(node)
        self.assertEqual(second.filter.avg(), 6.0)

    def test_text_is_ignored_with_a_warning(self) -> None:
        endpoint = MovingAvgFilterFactory("in", "out").get(self.mock_node())
        stored = tasks.store_data("in", "deep")
        with self.assertLogs("snr.mock", "WARNING"):
            result = endpoint.update_filter(stored, (TaskType.store_page, "in"))
        self.assertIsNone(result)


if __name__ == "__main__":
    unittest.main()
