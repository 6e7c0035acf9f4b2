"""Expectors, the expector endpoint, list replayer and mock node."""

import unittest

from snr import (
    Expector,
    ExpectorEndpointFactory,
    ListReplayerFactory,
    MockNode,
    OrderedExpector,
    SNRTestCase,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)

EV = TaskType.event


class TestExpector(unittest.TestCase):
    def test_exact_counts(self) -> None:
        with Expector({(EV, "a"): 2}) as expector:
            expector.call((EV, "a"))
            self.assertFalse(expector.is_satisfied())
            expector.call((EV, "a"))
            self.assertTrue(expector.is_satisfied())

    def test_too_few_and_too_many_fail_with_the_numbers(self) -> None:
        for calls in (1, 3):
            with self.subTest(calls=calls), self.assertRaises(AssertionError) as ctx:
                with Expector({(EV, "a"): 2}) as expector:
                    for _ in range(calls):
                        expector.call((EV, "a"))
            self.assertIn(f"TaskType.event(a): expected 2, saw {calls}", str(ctx.exception))

    def test_exception_inside_is_not_masked(self) -> None:
        with self.assertRaises(KeyError), Expector({(EV, "a"): 1}):
            raise KeyError("real problem")

    def test_ordered(self) -> None:
        with OrderedExpector([(EV, "a"), (EV, "b")]) as expector:
            expector.call((EV, "a"))
            expector.call((EV, "other"))  # not watched: ignored
            expector.call((EV, "b"))
        with self.assertRaises(AssertionError) as ctx:
            with OrderedExpector([(EV, "a"), (EV, "b")]) as expector:
                expector.call((EV, "b"))
                expector.call((EV, "a"))
        self.assertIn("at position 0", str(ctx.exception))


class TestExpectorEndpoint(SNRTestCase):
    def test_exits_when_satisfied(self) -> None:
        with self.expector({(TaskType.store_page, "x"): 3}) as expector:
            node = self.run_test_node(
                [
                    ListReplayerFactory([1, 2, 3], "x"),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                    TimeoutLoopFactory(seconds=5),
                ]
            )
        self.assertEqual(node.terminate_reason, "expectations satisfied")

    def test_ordered_expector_in_a_node(self) -> None:
        order = [(TaskType.store_page, "x"), (TaskType.process_data, "x")] * 2
        with self.ordered_expector(order) as expector:
            self.run_test_node(
                [
                    ListReplayerFactory([1, 2], "x", period_s=0.02),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )


class TestMockNode(SNRTestCase):
    def test_records_and_stores(self) -> None:
        node = MockNode()
        node.store_data("k", 5)
        node.schedule([tasks.event("a"), tasks.event("b")])
        self.assertEqual(node.get_data("k"), 5)
        self.assertEqual([t.name for t in node.scheduled], ["k", "a", "b"])

    def test_temp_file_and_assert_page(self) -> None:
        path = self.temp_file(".txt", "hi")
        with open(path) as f:
            self.assertEqual(f.read(), "hi")
        self.assertPage(self.mock_node().page("k", 1), "k", 1, origin="mock")


if __name__ == "__main__":
    unittest.main()
