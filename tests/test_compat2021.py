"""The names kept for code written against the 2021 release, and the ones refused."""

import multiprocessing
import sys
import unittest
from typing import Any, Mapping

import snr
from snr import (
    AbstractContext,
    Consumer,
    Context,
    Expector,
    ExpectorProtocol,
    ListReplayerFactory,
    MovingAvgEndpointFactory,
    MovingAvgFilterFactory,
    MPExpector,
    MultiProcExpector,
    RemovedApiError,
    Settings,
    SNRError,
    SNRTestCase,
    SocketsListenerFactory,
    SocketsLoopFactory,
    SocketsWrapper,
    TaskExpectations,
    TaskExpector,
    TaskId,
    TaskType,
)
from snr.prelude import ComponentError
from snr.utils import OrderedExpector

EV = TaskType.event


def count_twice(expector: Any) -> None:
    expector.call("child")
    expector.call("child")


class TestExpectorNames(unittest.TestCase):
    def test_every_expector_is_an_expector_protocol(self) -> None:
        for expector in (
            Expector({(EV, "a"): 1}),
            Expector[str]({"a": 1}),
            OrderedExpector([(EV, "a")]),
            MultiProcExpector({"a": 1}),
            TaskExpector({(EV, "a"): 1}),
        ):
            self.assertIsInstance(expector, ExpectorProtocol)
        self.assertNotIsInstance(object(), ExpectorProtocol)

    def test_expector_is_subscriptable_and_counts_any_key(self) -> None:
        with Expector[str]({"a": 2, "b": 0}, self) as expector:
            expector.call("a")
            expector.call("a")
            expector.call("not expected")
        self.assertIsInstance(expector, Expector)

    def test_unmet_expectation_names_key_expected_and_seen(self) -> None:
        for testcase in (self, None):
            with self.assertRaises(AssertionError) as ctx, Expector[str]({"a": 3}, testcase) as e:
                e.call("a")
            self.assertIn("'a': expected 3, saw 1", str(ctx.exception))
        with self.assertRaises(AssertionError) as ctx, Expector[TaskId]({(EV, "go"): 1}):
            pass
        self.assertIn("(event, 'go'): expected 1, saw 0", str(ctx.exception))

    def test_mp_expector_is_the_multiprocess_expector(self) -> None:
        self.assertIs(MPExpector, MultiProcExpector)

    def test_mp_expector_counts_from_a_spawned_child(self) -> None:
        # spawn pickles the expector (with its Expector[str] type) into the child
        ctx = multiprocessing.get_context("spawn")
        with MPExpector[str]({"child": 2}, self, context=ctx) as expector:
            child = ctx.Process(target=count_twice, args=(expector,))
            child.start()
            child.join(30)
            self.assertEqual(child.exitcode, 0)

    def test_task_expector_and_task_expectations(self) -> None:
        expectations: TaskExpectations = {(EV, "go"): 1, TaskType.terminate: 0}
        # Equal, not the same object: typing caches a few hundred subscriptions only.
        self.assertEqual(TaskExpectations, Mapping[TaskId, int])
        with TaskExpector(expectations, self) as expector:
            expector.call((EV, "go"))
        self.assertIsInstance(expector, Expector)
        self.assertEqual(expector.task_ids(), [(EV, "go"), TaskType.terminate])


class TestMovingAvgEndpointFactory(SNRTestCase):
    def test_is_the_moving_average_factory_with_2021_arguments(self) -> None:
        factory = MovingAvgEndpointFactory(input_key="raw", output_key="avg", window=2)
        self.assertIsInstance(factory, MovingAvgFilterFactory)
        self.assertEqual((factory.input, factory.output), ("raw", "avg"))
        self.assertEqual(factory.backing_deque.maxlen, 2)
        with self.assertRaises(ComponentError):
            MovingAvgEndpointFactory("raw", "avg", 0)

    def test_filters_in_a_node(self) -> None:
        with self.expector({(TaskType.store_page, "avg"): 3}) as expector:
            node = self.run_test_node(
                [
                    ListReplayerFactory([2, 4, 9], "raw"),
                    MovingAvgEndpointFactory("raw", "avg", 2),
                    snr.ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )
        self.assertEqual(node.get_data("avg"), 6.5)


class TestRefusedNames(unittest.TestCase):
    REPLACEMENTS = {
        Settings: "Config(factories, mode=Mode.DEBUG, profile=True)",
        Context: "self.parent (the node)",
        AbstractContext: "pass the node (an AbstractNode)",
        SocketsLoopFactory: "SocketsPair(server_tuple).client(keys)",
        SocketsListenerFactory: "SocketsPair(server_tuple).server(keys)",
        SocketsWrapper: "docs/wire-format.md",
        Consumer: "ThreadLoop",
    }

    def test_making_one_names_the_replacement(self) -> None:
        for cls, replacement in self.REPLACEMENTS.items():
            with self.subTest(cls.__name__), self.assertRaises(RemovedApiError) as ctx:
                cls(("localhost", 9000), ["depth"])
            message = str(ctx.exception)
            self.assertTrue(message.startswith(f"{cls.__name__}(...): "), message)
            self.assertIn("2021 release", message)
            self.assertIn(replacement, message)
            self.assertIsInstance(ctx.exception, SNRError)

    def test_subclassing_one_fails_too(self) -> None:
        with self.assertRaises(RemovedApiError) as ctx:

            class MyContext(Context):
                pass

        self.assertIn("class MyContext(Context)", str(ctx.exception))

    def test_settings_constants_name_the_replacement(self) -> None:
        with self.assertRaises(RemovedApiError) as ctx:
            Settings.NODE_SLEEP_TIME  # noqa: B018
        self.assertIn("Settings.NODE_SLEEP_TIME", str(ctx.exception))
        self.assertIn("does not map onto Config", str(ctx.exception))
        self.assertFalse(hasattr(Settings, "__wrapped__"))  # tools can still probe

    def test_not_silent_aliases_of_todays_classes(self) -> None:
        for cls in self.REPLACEMENTS:
            self.assertNotIn(cls, (snr.Config, snr.SocketsPair, snr.ThreadLoop))
            self.assertTrue(issubclass(cls, object))


class TestExported(unittest.TestCase):
    def test_names_are_exported_from_snr_lazily(self) -> None:
        import snr.extras.compat2021

        kernel = {"snr.prelude", "snr.core", "snr.utils"}
        for name in snr.extras.compat2021.__all__:
            self.assertIn(name, snr.__all__)
            # Today's own classes under their 2021 names are the kernel's, imported at
            # once (the testing utilities on first use); what the layer adds is loaded
            # on first use.
            home = snr._HOME.get(name, "")
            self.assertIn(home, {"snr.extras.compat2021", "snr.utils", ""}, name)
            self.assertIs(getattr(snr, name), getattr(snr.extras.compat2021, name), name)
            if not home:
                self.assertTrue(any(name in sys.modules[m].__all__ for m in kernel), name)
        self.assertIn("2021 release", snr.extras.compat2021.__doc__ or "")


if __name__ == "__main__":
    unittest.main()
