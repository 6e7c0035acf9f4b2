"""Expectors, the expector endpoint, list replayer and mock node."""

import io
import os
import unittest
from typing import Sequence

from snr import (
    AbstractFactory,
    Expector,
    ExpectorEndpointFactory,
    ListReplayerFactory,
    MovingAvgFilterFactory,
    SNRTestCase,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)
from snr.utils import DummyEndpointFactory, MockNode, OrderedExpector

EV = TaskType.event
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


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
            self.assertIn(f"(event, 'a'): expected 2, saw {calls}", str(ctx.exception))

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


class TestWhatWasSeenInstead(unittest.TestCase):
    """A failure lists the keys seen but not expected, and the closest to each missing one."""

    def test_the_closest_key_seen_is_named(self) -> None:
        with self.assertRaises(AssertionError) as ctx:
            with Expector({(EV, "beep"): 2, (EV, "stop"): 1}) as expector:
                for key in [(EV, "Beep"), (EV, "Beep"), (EV, "go"), (EV, "stop")]:
                    expector.call(key)
        self.assertEqual(
            str(ctx.exception),
            "Expectations not met:\n"
            "  (event, 'beep'): expected 2, saw 0 (closest seen instead: "
            "(event, 'Beep'), 2 times)\n"
            "Seen but not expected: (event, 'Beep') 2 times, (event, 'go') once.",
        )

    def test_nothing_close_names_nothing(self) -> None:
        expector = Expector({(TaskType.store_page, "depth"): 1})
        expector.call((TaskType.store_page, "heading"))
        self.assertEqual(expector.problems(), ["(store_page, 'depth'): expected 1, saw 0"])
        self.assertEqual(
            expector.seen_instead(), "Seen but not expected: (store_page, 'heading') once."
        )

    def test_the_same_name_under_another_type(self) -> None:
        expector = Expector({(TaskType.store_page, "depth"): 1})
        expector.call((TaskType.process_data, "depth"))
        self.assertIn("closest seen instead: (process_data, 'depth')", expector.problems()[0])

    def test_keys_that_are_not_task_ids(self) -> None:
        expector = Expector[str]({"beep": 1})
        expector.call("bep")
        self.assertEqual(
            expector.problems(), ["'beep': expected 1, saw 0 (closest seen instead: 'bep', once)"]
        )

    def test_an_ordered_expector_names_the_closest_to_the_first_missing(self) -> None:
        expector = OrderedExpector([(EV, "a"), (EV, "start")])
        expector.call((EV, "a"))
        expector.call((EV, "stat"))
        self.assertEqual(
            expector.problems(),
            ["missing at the end: (event, 'start') (closest seen instead: (event, 'stat'), once)"],
        )

    def test_what_is_seen_instead_is_bounded(self) -> None:
        expector = Expector({(EV, "a"): 1})
        for i in range(Expector.MAX_OTHERS + 50):
            expector.call((EV, f"other_{i}"))
        self.assertEqual(len(expector.others), Expector.MAX_OTHERS)
        self.assertIn("and 80 more.", expector.seen_instead())


class TestExpectorEndpoint(SNRTestCase):
    def test_exits_when_satisfied(self) -> None:
        with self.expector({(TaskType.store_page, "x"): 3}) as expector:
            node = self.run_test_node(
                [
                    ListReplayerFactory([1, 2, 3], "x"),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
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


class TestRunTestNodeTimeLimit(SNRTestCase):
    """A node that never stops fails its test, instead of passing after a wait."""

    def assertFailsWith(
        self,
        factories: Sequence[AbstractFactory],
        *parts: str,
        timeout_s: float,
        expect_timeout: bool = False,
    ) -> str:
        with self.assertRaises(AssertionError) as ctx:
            self.run_test_node(factories, timeout_s=timeout_s, expect_timeout=expect_timeout)
        message = str(ctx.exception)
        for part in parts:
            self.assertIn(part, message)
        return message

    def test_a_node_that_never_stops_fails_naming_its_components(self) -> None:
        message = self.assertFailsWith(
            [
                ListReplayerFactory([1], "x"),  # stops itself; the node runs on
                DummyEndpointFactory("motors"),
                TimeoutLoopFactory(seconds=60),  # still waiting at the limit
            ],
            "The 'test' node was still running when its time limit of 0.4 s ran out",
            "list_replayer_x (ListReplayerLoop, finished)",
            "motors (DummyEndpoint)",
            "timeout_loop (TimeoutLoop, still running)",
            "ExpectorEndpointFactory(expector, exit_when_satisfied=True)",
            'tasks.terminate("done")',
            "timeout_s=",
            "expect_timeout=True",
            # Not 0.1 s: on a busy machine the loops' threads may not have started by then.
            timeout_s=0.4,
        )
        self.assertNotIn("node_core", message)

    def test_an_expector_that_is_still_waiting_says_for_what(self) -> None:
        expector = Expector({(TaskType.store_page, "x"): 2})
        self.assertFailsWith(
            [ListReplayerFactory([1], "x"), ExpectorEndpointFactory(expector)],
            "It waited the whole time limit, and the expectations of expector_endpoint were "
            "still not met: (store_page, 'x'): expected 2, saw 1.",
            timeout_s=0.1,
        )

    def test_a_satisfied_expector_without_exit_when_satisfied_is_pointed_out(self) -> None:
        expector = Expector({(TaskType.store_page, "x"): 1})
        self.assertFailsWith(
            [ListReplayerFactory([1], "x"), ExpectorEndpointFactory(expector)],
            "expector_endpoint was satisfied but was made without exit_when_satisfied=True",
            timeout_s=0.1,
        )

    def test_the_class_attribute_sets_the_default_limit(self) -> None:
        class Quick(SNRTestCase):
            timeout_s = 0.05

            def runTest(self) -> None:
                self.run_test_node([DummyEndpointFactory()])

        self.assertEqual(SNRTestCase.timeout_s, 2.0)
        result = unittest.TestResult()
        Quick().run(result)
        self.assertEqual(len(result.failures), 1, result.errors)
        self.assertIn("time limit of 0.05 s", result.failures[0][1])

    def test_expect_timeout_runs_until_the_limit(self) -> None:
        node = self.run_test_node([DummyEndpointFactory()], timeout_s=0.05, expect_timeout=True)
        self.assertEqual(node.terminate_reason, "test time limit of 0.05 s reached")

    def test_expect_timeout_fails_when_the_node_stops_first(self) -> None:
        self.assertFailsWith(
            [TimeoutLoopFactory(ms=10)],
            "The 'test' node was expected to run until its time limit of 5 s",
            "but it stopped earlier: Timeout.",
            timeout_s=5,
            expect_timeout=True,
        )

    def test_a_node_that_stops_by_itself_is_not_a_timeout(self) -> None:
        runner_node = self.run_test_node([TimeoutLoopFactory(ms=10)])
        self.assertEqual(runner_node.terminate_reason, "Timeout")

    def test_the_message_shown_in_the_docs_is_the_real_one(self) -> None:
        expector = Expector({(TaskType.store_page, "out"): 4})
        message = self.assertFailsWith(
            [
                ListReplayerFactory([0, 1, 2, 4], "in"),
                MovingAvgFilterFactory("in", "out", 2),
                ExpectorEndpointFactory(expector),
            ],
            timeout_s=0.1,
        )
        with open(os.path.join(ROOT, "docs", "utilities.md"), encoding="utf-8") as f:
            page = f.read()
        shown = message.replace("time limit of 0.1 s", "time limit of 2 s")
        self.assertIn(f"AssertionError: {shown}\n", page)

    def test_the_failure_is_a_unittest_failure_not_an_error(self) -> None:
        class Forgotten(SNRTestCase):
            def test_never_stops(self) -> None:
                self.run_test_node([DummyEndpointFactory("forgotten")], timeout_s=0.05)

        suite = unittest.defaultTestLoader.loadTestsFromTestCase(Forgotten)
        stream = io.StringIO()
        result = unittest.TextTestRunner(stream=stream, verbosity=0).run(suite)
        self.assertEqual((len(result.failures), len(result.errors)), (1, 0))
        self.assertIn("forgotten (DummyEndpoint)", stream.getvalue())


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


class TestTempFile(SNRTestCase):
    """``temp_file``: today's calls (a str path) and the 2021 release's (an object)."""

    def test_a_suffix_by_position_names_file_plus_suffix(self) -> None:
        path = self.temp_file(".jsonl")
        self.assertEqual(os.path.basename(path), "file.jsonl")
        self.assertIsInstance(path, str)
        self.assertEqual(os.fspath(path), str(path))
        self.assertIs(type(path.path), str)
        self.assertTrue(path.endswith(".jsonl"))
        main = self.temp_file("_main.py", "print('hi')\n")
        self.assertEqual(os.path.basename(main), "file_main.py")
        with open(main, encoding="utf-8") as f:
            self.assertEqual(f.read(), "print('hi')\n")

    def test_a_name_by_position_is_the_file_name(self) -> None:
        temp = self.temp_file("log.txt")
        self.assertEqual(os.path.basename(temp.path), "log.txt")
        self.assertFalse(temp.exists())
        self.assertEqual(os.path.basename(self.temp_file(filename=".hidden")), ".hidden")
        self.assertEqual(os.path.basename(self.temp_file(suffix="log.txt")), "filelog.txt")
        self.assertEqual(os.path.basename(self.temp_file()), "file")

    def test_second_argument_is_contents_or_overwrite(self) -> None:
        self.assertFalse(self.temp_file("a.txt", True).exists())  # overwrite=True
        self.assertTrue(self.temp_file("a.txt", "x").exists())  # contents
        self.assertTrue(self.temp_file("a.txt", contents="x", overwrite=True).exists())

    def test_paths_outside_the_folder_are_refused(self) -> None:
        for name in ("/etc/passwd", "../x.txt", "a/../../x"):
            with self.assertRaises(ValueError):
                self.temp_file(filename=name)
        with self.assertRaises(TypeError):
            self.temp_file("a.txt", filename="b.txt")

    def test_context_manager_checks_the_file_and_removes_it(self) -> None:
        with self.temp_file() as temp:
            with temp.open() as f:
                f.write("data")
            temp.assertExists()
        self.assertFalse(os.path.exists(temp))
        with self.assertRaises(AssertionError) as ctx, self.temp_file("never.txt"):
            pass
        self.assertIn("never.txt", str(ctx.exception))
        self.assertIn("does not exist", str(ctx.exception))

    def test_cleanup_false_keeps_the_file(self) -> None:
        import shutil

        with self.temp_file("kept.txt", cleanup=False) as temp:
            with temp.open() as f:
                f.write("x")
        self.addCleanup(shutil.rmtree, os.path.dirname(temp.path), True)
        self.assertTrue(temp.exists())

    def test_pickles_as_a_plain_path(self) -> None:
        import pickle

        temp = self.temp_file(".txt")
        again = pickle.loads(pickle.dumps(temp))
        self.assertIs(type(again), str)
        self.assertEqual(again, temp)

    def test_the_folder_is_removed_after_the_test(self) -> None:
        inner = SNRTestCase()
        temp = inner.temp_file("x.txt", "data")
        self.assertTrue(temp.exists())
        inner.doCleanups()
        self.assertFalse(os.path.exists(os.path.dirname(temp)))


if __name__ == "__main__":
    unittest.main()
