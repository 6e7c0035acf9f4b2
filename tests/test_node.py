"""Node life cycle, pages, errors in handlers, shutdown and idling."""

import resource
import threading
import time
import unittest
from typing import Any, List, Optional

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    Page,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)
from snr.core import NodeState
from snr.prelude import HandlerError, LoopError, NodeStateError, ThreadSafetyError
from tests.helpers import (
    DRAINED,
    Log,
    RecorderFactory,
    StopWhenDrainedFactory,
    StopWhenTrueFactory,
    settle_the_heap,
)
from tests.quiet import capture_test_logs

EV = TaskType.event


class Boom(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode, returns: Any = None) -> None:
        super().__init__(factory, parent, "boom")
        self.returns = returns
        self.calls = 0
        self.task_handlers = {(EV, "boom"): self.explode, (EV, "bad_return"): self.bad_return}

    def explode(self, task: Task, key: TaskId) -> SomeTasks:
        self.calls += 1
        raise ValueError("sensor unplugged")

    def bad_return(self, task: Task, key: TaskId) -> SomeTasks:
        return self.returns  # type: ignore[no-any-return]  # a wrong value, on purpose


class BoomFactory(EndpointFactory):
    def __init__(self, returns: Any = None) -> None:
        super().__init__()
        self.returns = returns
        self.endpoint: Optional[Boom] = None

    def get(self, parent: AbstractNode) -> Boom:
        endpoint = Boom(self, parent, self.returns)
        self.endpoint = endpoint
        return endpoint


class Ticker(ThreadLoop):
    def __init__(self, factory: "TickerFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name, max_tick_rate_hz=factory.rate)
        self.factory_ = factory

    def setup(self) -> None:
        self.factory_.events.append("setup")

    def loop(self) -> None:
        self.factory_.ticks += 1
        if self.factory_.crash_after and self.factory_.ticks >= self.factory_.crash_after:
            raise RuntimeError("High velocity impact")
        if self.factory_.block:
            threading.Event().wait(0.05)  # "blocking I/O" that ignores halt

    def halt(self) -> None:
        self.factory_.events.append("halt")

    def terminate(self) -> None:
        self.factory_.events.append("terminate")


class TickerFactory(LoopFactory):
    def __init__(
        self, rate: float = 100, name: str = "ticker", crash_after: int = 0, block: bool = False
    ) -> None:
        super().__init__()
        self.rate, self.name, self.crash_after, self.block = rate, name, crash_after, block
        self.ticks = 0
        self.events: List[str] = []

    def get(self, parent: AbstractNode) -> Ticker:
        return Ticker(self, parent)


def snr_threads() -> List[str]:
    return [t.name for t in threading.enumerate() if t.name.startswith("snr-")]


class TestPages(SNRTestCase):
    def test_store_then_process_after_page_is_in_datastore(self) -> None:
        seen: List[Any] = []

        def check(task: Task, key: TaskId) -> SomeTasks:
            if (task.type, task.name) == DRAINED:
                return None  # the marker that stops the node, not a page
            stored = node.get_page(task.name)
            seen.append((task.type, stored is not None and stored == task.val_list[0]))
            return None

        log: Log = []
        node = Node(
            "test",
            self.get_config(
                [
                    RecorderFactory(
                        "watch", [TaskType.store_page, TaskType.process_data], log, check
                    ),
                    StopWhenDrainedFactory(),
                ]
            ),
        )
        node.store_data("depth", 3.5)
        node.store_data("quiet", 1, process=False)
        node.loop()
        # FIFO: both stores were queued first; process_data follows its page.
        self.assertEqual(
            seen,
            [
                (TaskType.store_page, True),
                (TaskType.store_page, True),
                (TaskType.process_data, True),
            ],
        )
        self.assertPage(node.get_page("depth"), "depth", 3.5, origin="test")
        self.assertEqual(node.get_data("quiet"), 1)
        self.assertIsNone(node.get_data("never_stored"))

    def test_pages_and_tasks_hold_only_their_fields(self) -> None:
        """Slotted (docs/design.md): smaller and quicker to make on a loop's path."""
        page = Page("depth", 1.0, "robot", 0.0)
        task = tasks.store_page(page)
        for thing in (page, task):
            with self.assertRaises(AttributeError):
                thing.note = 1  # type: ignore[union-attr]
            self.assertFalse(hasattr(thing, "__dict__"))
        self.assertEqual(task.page(), page)

    def test_tasks_store_data_is_stamped_with_the_node_role(self) -> None:
        stop = StopWhenDrainedFactory()
        node = Node("rover", Config({"rover": [stop]}, mode=Mode.TEST))
        node.schedule(tasks.store_data("speed", 2.0))
        node.loop()
        page = node.get_page("speed")
        assert page is not None
        self.assertEqual((page.origin, page.data), ("rover", 2.0))

    def test_pages_are_stored_in_order(self) -> None:
        node = Node("test", self.get_config([StopWhenDrainedFactory()]))
        log: Log = []
        node.add_component(RecorderFactory("r", [(TaskType.store_page, "n")], log).get(node))
        for i in range(100):
            node.store_data("n", i)
        node.loop()
        self.assertEqual(node.get_data("n"), 99)
        self.assertEqual(len(log), 100)

    def test_a_batch_of_pages_is_stored_as_one_task_per_page_would_be(self) -> None:
        def run(schedule: Any) -> tuple[Log, Any]:
            log: Log = []
            watched: List[TaskId] = [
                (TaskType.store_page, "b"),
                TaskType.process_data,
                (EV, "between"),
            ]
            node = Node(
                "test",
                self.get_config([RecorderFactory("r", watched, log), StopWhenDrainedFactory()]),
            )
            pages = [node.page("a", 1), node.page("b", 2), node.page("a", 3, process=False)]
            pages.append(node.page("c", 4))
            schedule(node, pages)
            node.schedule(tasks.event("between"))  # queued after the pages
            node.loop()
            return log, {key: node.get_data(key) for key in "abc"}

        one_each = run(lambda node, pages: node.schedule([tasks.store_page(p) for p in pages]))
        batch = run(lambda node, pages: node.schedule(tasks.store_pages(pages)))
        self.assertEqual(batch, one_each)
        self.assertEqual(one_each[1], {"a": 3, "b": 2, "c": 4})
        self.assertEqual(
            [entry[1][:2] for entry in batch[0] if entry[1][:2] != DRAINED],
            [
                (TaskType.store_page, "b"),  # 'b' has a handler: it sees its page, in its turn
                (EV, "between"),
                (TaskType.process_data, "a"),
                (TaskType.process_data, "b"),
                (TaskType.process_data, "c"),
            ],
        )

    def test_a_page_nobody_processes_makes_no_process_data_task(self) -> None:
        """The node core makes a page's process_data task only while some handler waits for it."""
        node = Node("test", self.get_config([StopWhenDrainedFactory()]))
        core = node.components["node_core"]
        store = core.store_page_handler  # type: ignore[attr-defined]
        self.assertFalse(node.is_handled(TaskType.process_data, "depth"))
        self.assertIsNone(store(tasks.store_page(node.page("depth", 1.0)), TaskType.store_page))
        self.assertEqual(node.get_data("depth"), 1.0)

        log: Log = []
        node.add_component(RecorderFactory("r", [(TaskType.process_data, "depth")], log).get(node))
        self.assertTrue(node.is_handled(TaskType.process_data, "depth"))
        self.assertFalse(node.is_handled(TaskType.process_data, "speed"))
        follow_up = store(tasks.store_page(node.page("depth", 2.0)), TaskType.store_page)
        assert isinstance(follow_up, Task)
        self.assertEqual((follow_up.type, follow_up.name), (TaskType.process_data, "depth"))
        # A handler for every process_data task (type-level) counts for every key.
        node.add_component(RecorderFactory("all", [TaskType.process_data], log).get(node))
        self.assertTrue(node.is_handled(TaskType.process_data, "speed"))


class TestLifeCycle(SNRTestCase):
    def test_terminate_task_stops_node_and_jumps_queue(self) -> None:
        log: Log = []
        node = Node("test", self.get_config([RecorderFactory("r", [EV, TaskType.terminate], log)]))
        node.schedule([tasks.event("late"), tasks.terminate("now")])
        node.loop()
        self.assertEqual(node.terminate_reason, "now")
        self.assertEqual([t[1] for _, t in log], ["now"])  # "late" never ran
        self.assertIs(node.state, NodeState.TERMINATED)
        self.assertTrue(node.is_terminated())

    def test_orderly_shutdown_halts_joins_and_terminates_every_loop(self) -> None:
        loops = [TickerFactory(name=f"t{i}", rate=200) for i in range(3)]
        slow = TickerFactory(name="slow", rate=0, block=True)  # ignores halt for ~50 ms
        # Stop while every loop runs: the slow one is inside its first wait.
        every_loop_runs = StopWhenTrueFactory(
            lambda: all(factory.ticks for factory in [*loops, slow]), within_s=0.2
        )
        node = Node("test", self.get_config([*loops, slow, every_loop_runs]))
        node.loop()
        for factory in [*loops, slow]:
            self.assertEqual(factory.events, ["setup", "halt", "terminate"])
        self.assertEqual(snr_threads(), [])

    def test_shutdown_of_a_stuck_loop_is_bounded(self) -> None:
        class Stuck(ThreadLoop):
            def loop(self) -> None:
                stuck.set()
                gate.wait(3)

        class StuckFactory(LoopFactory):
            def get(self, parent: AbstractNode) -> Stuck:
                return Stuck(self, parent, "stuck")

        gate, stuck = threading.Event(), threading.Event()
        stop = StopWhenTrueFactory(stuck.is_set, within_s=2)
        node = Node("test", self.get_config([StuckFactory(), stop]))
        node.join_timeout_s = 0.05
        started = time.monotonic()
        with self.assertLogs("snr.test", "WARNING") as logs:
            node.loop()
        self.assertLess(time.monotonic() - started, 2.5)
        self.assertIn("did not stop within", "\n".join(logs.output))
        gate.set()

    def test_loop_twice_is_refused_and_terminate_twice_is_safe(self) -> None:
        node = Node("test", self.get_config([TimeoutLoopFactory(seconds=0.01)]))
        node.loop()
        node.terminate()
        with self.assertRaises(NodeStateError) as ctx:
            node.loop()
        self.assertIn("terminated", str(ctx.exception))

    def test_terminate_flag_before_loop_stops_at_once(self) -> None:
        ticker = TickerFactory()
        node = Node("test", self.get_config([ticker]))
        node.set_terminate_flag("changed my mind")
        node.loop()
        self.assertEqual(node.terminate_reason, "changed my mind")

    def test_loop_tick_rate_is_honoured(self) -> None:
        ticker = TickerFactory(rate=100)
        self.run_test_node([ticker, TimeoutLoopFactory(seconds=0.15)])
        self.assertGreater(ticker.ticks, 3)
        self.assertLessEqual(ticker.ticks, 16)  # 100 Hz × 0.15 s = 15, plus one

    def test_loop_cannot_execute_tasks_directly(self) -> None:
        errors: List[Exception] = []

        class Rogue(ThreadLoop):
            def loop(self) -> None:
                try:
                    self.parent.execute_task(tasks.event("x"))
                except ThreadSafetyError as e:
                    errors.append(e)
                self.set_terminate_flag()

        class RogueFactory(LoopFactory):
            def get(self, parent: AbstractNode) -> Rogue:
                return Rogue(self, parent, "rogue")

        self.run_test_node([RogueFactory(), StopWhenTrueFactory(lambda: errors, within_s=0.1)])
        self.assertEqual(len(errors), 1)
        self.assertIn("self.schedule", str(errors[0]))

    def test_idle_node_does_not_spin(self) -> None:
        settle_the_heap(self)  # no collection of earlier tests' objects in the window
        # The first node of a class reads its source once (DEBUG class checks): not idling.
        Node("test", self.get_config([TickerFactory(rate=4)]))
        node = Node("test", self.get_config([TickerFactory(rate=4)]))
        thread = threading.Thread(target=node.loop)
        before = resource.getrusage(resource.RUSAGE_SELF)
        wall = time.monotonic()
        thread.start()
        time.sleep(0.3)
        node.set_terminate_flag("done")
        thread.join(5)
        after = resource.getrusage(resource.RUSAGE_SELF)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        # Catches a spin (a whole core); the process also holds other tests' threads.
        self.assertLess(cpu / (time.monotonic() - wall), 0.10, f"{cpu:.3f} s CPU")

    def test_a_node_waits_on_one_idle_waiter_the_first_comms_to_ask(self) -> None:
        class Waiter:
            def wait(self, timeout_s: Optional[float]) -> None: ...
            def woken(self) -> None: ...
            def wake(self) -> None: ...

        node = Node("test", self.get_config([TimeoutLoopFactory(seconds=1)]))
        first, second = Waiter(), Waiter()
        self.assertTrue(node.queue.use_waiter(first))
        self.assertFalse(node.queue.use_waiter(second), "one at a time")
        self.assertTrue(node.queue.use_waiter(first), "asking again is no harm")
        self.assertIs(node.queue.waiter, first)
        node.queue.stop_waiter(second)  # not the one: nothing changes
        self.assertIs(node.queue.waiter, first)
        node.queue.stop_waiter(first)
        self.assertIsNone(node.queue.waiter, "the bell again")
        self.assertTrue(node.queue.use_waiter(second))


class TestHandlerFailures(SNRTestCase):
    def test_test_mode_fails_naming_endpoint_handler_and_task(self) -> None:
        factory = BoomFactory()
        node = Node("test", self.get_config([factory, TimeoutLoopFactory(seconds=2)]))
        node.schedule(tasks.event("boom", [7]))
        with self.assertRaises(HandlerError) as ctx, self.assertLogs("snr.test", "ERROR") as logs:
            node.loop()
        self.assertIn("Stopping node 'test': Task handler Boom.explode", logs.output[0])
        text = str(ctx.exception)
        for part in (
            "Boom.explode",
            "'boom'",
            "ValueError: sensor unplugged",
            "test_node.py",
            "(event, 'boom')",
            "[7]",
        ):
            self.assertIn(part, text)
        self.assertIsInstance(ctx.exception.__cause__, ValueError)
        self.assertEqual(snr_threads(), [])

    def test_a_page_that_cannot_be_stored_is_a_failure_in_words(self) -> None:
        """Pages are stored before the handlers, outside the table: a failure still says so."""

        class Refusing(dict):  # type: ignore[type-arg]
            def __setitem__(self, key: Any, value: Any) -> None:
                raise MemoryError("no room for another page")

        node = Node("test", self.get_config([TimeoutLoopFactory(seconds=2)]))
        core: Any = node.components["node_core"]
        core.pages = Refusing()  # the dict the node's core writes pages into
        node.store_data("depth", 1.0)
        with self.assertRaises(HandlerError) as ctx, self.assertLogs("snr.test", "ERROR") as logs:
            node.loop()
        self.assertIn("NodeCoreEndpoint.store_page_handler", logs.output[0])
        self.assertIn("MemoryError: no room for another page", str(ctx.exception))
        self.assertIn("(store_page, 'depth')", str(ctx.exception))
        self.assertEqual(snr_threads(), [])

    def test_deployed_mode_logs_and_keeps_running(self) -> None:
        capture_test_logs(self)  # and the INFO level a DEPLOYED node gives "snr.test" goes
        factory = BoomFactory()
        booms = [tasks.event("boom"), tasks.event("boom")]
        stop = StopWhenDrainedFactory(booms)
        node = Node("test", Config({"test": [factory, stop]}, mode=Mode.DEPLOYED))
        with self.assertLogs("snr.test", "ERROR") as logs:
            node.loop()
        assert factory.endpoint is not None
        self.assertEqual(factory.endpoint.calls, 2)
        self.assertEqual(node.terminate_reason, "queue drained")  # the errors did not stop it
        self.assertIn("Boom.explode", logs.output[0])

    def test_wrong_return_type_is_reported(self) -> None:
        for bad in (5, "text", [tasks.event("ok"), 3]):
            with self.subTest(bad=bad):
                node = Node(
                    "test", self.get_config([BoomFactory(bad), TimeoutLoopFactory(seconds=2)])
                )
                node.schedule(tasks.event("bad_return"))
                with self.assertRaises(HandlerError) as ctx, self.assertLogs(node.log) as logs:
                    node.loop()
                self.assertIn("Stopping node 'test': Task handler Boom.bad_return", logs.output[0])
                self.assertIn("Boom.bad_return", str(ctx.exception))
                self.assertIn("must return a Task, a list of Tasks, or None", str(ctx.exception))

    def test_loop_exception_stops_node_in_test_mode(self) -> None:
        crasher = TickerFactory(rate=100, crash_after=2)
        node = Node("test", self.get_config([crasher, TimeoutLoopFactory(seconds=2)]))
        with self.assertRaises(LoopError) as ctx, self.assertLogs(node.log, "ERROR") as logs:
            node.loop()
        self.assertIn("Stopping node 'test': Loop 'ticker'", logs.output[0])
        self.assertIn("High velocity impact", str(ctx.exception))
        self.assertIn("ticker", str(ctx.exception))


class TestProfiler(SNRTestCase):
    def test_dump_lists_task_ids_and_loops(self) -> None:
        capture_test_logs(self)  # a DEBUG node: its INFO lines
        ticker = TickerFactory(rate=100)
        node = Node(
            "test",
            self.get_config(
                [ticker, StopWhenTrueFactory(lambda: ticker.ticks >= 2, 0.1)], Mode.DEBUG
            ),
        )
        node.store_data("x", 1)
        node.loop()
        assert node.profiler is not None
        dump = node.profiler.dump()
        self.assertTrue(dump.startswith("Times called,"))
        self.assertIn("(terminate):snr.core.node", dump)
        self.assertIn("Loop(ticker)", dump)
        self.assertRegex(dump, r"\n +1 x +[\d.]+ us -> +[\d.]+%: \(terminate\)")
        # Storing a page is the node's own work (before the handlers), not a handler.
        self.assertNotIn("(store_page", dump)
        self.assertEqual(node.get_data("x"), 1)

    def test_no_profiler_when_deployed(self) -> None:
        capture_test_logs(self)  # and the INFO level a DEPLOYED node gives "snr.t" goes
        node = Node("t", Config({"t": [TimeoutLoopFactory(seconds=0.01)]}, mode=Mode.DEPLOYED))
        self.assertIsNone(node.profiler)


if __name__ == "__main__":
    unittest.main()
