"""The example's moving average filter behaves as the one SNR ships.

examples/moving_average writes thesis listings A.1 and A.2 out in full, so a
student can read how a filter is made; SNR ships the same filter as
`snr.MovingAvgFilterFactory`. This test feeds both the same stored values,
good and bad, and checks they answer alike, so the two cannot drift apart.
"""

from __future__ import annotations

import sys
import unittest
from typing import Any, List, Optional

from snr import MovingAvgFilterFactory, TaskType, tasks
from snr.prelude import Task
from snr.utils import MockNode
from tests.examples_support import example_path, load_module
from tests.quiet import captured_logs

__all__ = ["TestExampleFilterMatchesShipped"]

EXAMPLE = load_module(
    f"{example_path('moving_average')}/moving_average.py", "moving_average_twin_of_shipped"
)

# The factory finds its own module by name (to reload it), so the module must be registered.
sys.modules[EXAMPLE.__name__] = EXAMPLE

# Numbers, then data the filter must refuse (text, a bool, a list), numbers again.
STORED: List[Any] = [0, 1, 2.5, 4, "four", True, [5], -3, 7.25, 1e6]
NUMBERS = [0, 1, 2.5, 4, -3, 7.25, 1e6]


def answers(factory: Any, stored: List[Any]) -> List[Optional[float]]:
    """What the filter stores for each value: the new mean, or None when it refuses one."""
    endpoint = factory.get(MockNode())
    found: List[Optional[float]] = []
    for value in stored:
        reply = endpoint.update_filter(tasks.store_data("raw", value), (TaskType.store_page, "raw"))
        if reply is None:
            found.append(None)
            continue
        assert isinstance(reply, Task)
        page = reply.page()
        assert page is not None and page.key == "mean"
        found.append(page.data)
    return found


class TestExampleFilterMatchesShipped(unittest.TestCase):
    def test_same_means_and_same_refusals(self) -> None:
        for length in (1, 3, 5):
            with self.subTest(length=length), captured_logs("snr"):
                shipped = answers(MovingAvgFilterFactory("raw", "mean", length), STORED)
                example = answers(EXAMPLE.MovingAvgFilterFactory("raw", "mean", length), STORED)
                self.assertEqual(example, shipped)
                # Not vacuous: both refused the three bad values and averaged the numbers.
                self.assertEqual([i for i, mean in enumerate(shipped) if mean is None], [4, 5, 6])
                self.assertEqual(shipped[-1], sum(NUMBERS[-length:]) / length)

    def test_both_ignore_a_task_for_another_key(self) -> None:
        other = tasks.store_data("elsewhere", 1.0)
        for factory in (
            MovingAvgFilterFactory("raw", "mean"),
            EXAMPLE.MovingAvgFilterFactory("raw", "mean"),
        ):
            with captured_logs("snr"):
                endpoint = factory.get(MockNode())
                self.assertIsNone(endpoint.update_filter(other, (TaskType.store_page, "raw")))


if __name__ == "__main__":
    unittest.main()
