"""Life-cycle faults: reloads that fail, loops that will not stop or leave oddly,
handlers that fail over and over, and a queue that fills up."""

from __future__ import annotations

import sys
import threading
import time
import unittest
from typing import Any, Callable, List, Optional, Set

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    tasks,
)
from snr.core import TaskQueue
from tests.helpers import wait_until


class Ticker(ThreadLoop):
    """Counts its passes on the factory; ``block`` makes one pass wait on an Event."""

    def __init__(self, factory: TickerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "ticker", max_tick_rate_hz=200)
        self.ticker_factory = factory

    def loop(self) -> None:
        self.ticker_factory.passes += 1
        self.ticker_factory.threads.add(threading.get_ident())
        if self.ticker_factory.block.is_set():
            self.ticker_factory.release.wait(5.0)  # blocked "reading a device"


class TickerFactory(LoopFactory):
    def __init__(self, fail_on_build: int = 0) -> None:
        super().__init__()
        self.builds = 0
        self.fail_on_build = fail_on_build
        self.passes = 0
        self.threads: Set[int] = set()
        self.block = threading.Event()
        self.release = threading.Event()

    def get(self, parent: AbstractNode) -> Ticker:
        self.builds += 1
        if self.builds == self.fail_on_build:
            raise RuntimeError("the new code is broken")
        return Ticker(self, parent)


class Script(Endpoint):
    """Runs ``steps`` (functions of the node) one per ``next`` event, then stops the node."""

    def __init__(self, factory: ScriptFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "script")
        self.steps = factory.steps
        self.task_handlers = {(TaskType.event, "next"): self.next_step}

    def begin(self) -> None:
        self.schedule(tasks.event("next"))

    def next_step(self, task: Task, key: TaskId) -> SomeTasks:
        if not self.steps:
            return tasks.terminate("script done")
        self.steps.pop(0)(self.parent)
        return tasks.event("next")


class ScriptFactory(EndpointFactory):
    def __init__(self, steps: List[Callable[[Any], None]]) -> None:
        super().__init__()
        self.steps = list(steps)

    def get(self, parent: AbstractNode) -> Script:
        return Script(self, parent)


def run_node(factories: List[Any], mode: Mode = Mode.TEST, join_timeout_s: float = 1.0) -> Node:
    node = Node("life", Config({"life": factories}, mode=mode))
    node.join_timeout_s = join_timeout_s
    watchdog = threading.Timer(5.0, lambda: node.set_terminate_flag("test watchdog"))
    watchdog.start()
    try:
        node.loop()
    finally:
        watchdog.cancel()
    assert node.terminate_reason != "test watchdog", "the node did not stop by itself"
    return node


class TestReloadNeverLies(unittest.TestCase):
    def test_failed_rebuild_keeps_the_old_loop_running(self) -> None:
        ticker = TickerFactory(fail_on_build=2)
        seen: List[int] = []

        def reload(node: Any) -> None:
            node.reload_component("ticker")
            seen.append(ticker.passes)

        def check(node: Any) -> None:
            wait_until(lambda: ticker.passes > seen[0] + 3)
            seen.append(ticker.passes)

        with self.assertLogs("snr.life", "ERROR") as logs:
            node = run_node([ticker, ScriptFactory([lambda n: time.sleep(0.02), reload, check])])
        text = "\n".join(logs.output)
        self.assertIn("Rebuilding 'ticker' after its reload failed", text)
        self.assertIn("the old version keeps running", text)
        self.assertIn("RuntimeError: the new code is broken", text)
        self.assertIn("test_node_lifecycle.py", text)  # the line of get() that raised
        self.assertGreater(seen[1], seen[0] + 3, "the old loop ran on after the failed reload")
        self.assertIsInstance(node.components["ticker"], Ticker)

    def test_a_loop_that_will_not_stop_is_not_reloaded_beside_itself(self) -> None:
        ticker = TickerFactory()
        ticker.block.set()
        result: List[Any] = []

        def reload(node: Any) -> None:
            wait_until(lambda: ticker.passes >= 1)
            result.append(node.reload_component("ticker"))
            ticker.block.clear()
            ticker.release.set()  # the device answers: the old loop carries on
            passes = ticker.passes
            wait_until(lambda: ticker.passes > passes + 3)
            result.append(ticker.passes - passes)

        with self.assertLogs("snr.life", "ERROR") as logs:
            node = run_node([ticker, ScriptFactory([reload])], join_timeout_s=0.05)
        text = "\n".join(logs.output)
        self.assertEqual(result[0], [])  # nothing was rebuilt
        self.assertEqual(ticker.builds, 1)  # no second copy was even built
        self.assertIn("Cannot reload loop 'ticker'", text)
        self.assertIn("Reload refused; the old version keeps running", text)
        self.assertIn("self.ticker_factory.release.wait(5.0)", text)  # where it is blocked
        self.assertGreater(result[1], 3, "the old loop runs on once unblocked")
        self.assertEqual(len(ticker.threads), 1)
        self.assertFalse(node.components["ticker"].is_alive())


class Leaver(ThreadLoop):
    """Leaves its thread in an unusual way on its first pass."""

    def __init__(self, factory: LeaverFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "leaver")
        self.how = factory.how

    def loop(self) -> None:
        if self.how == "exit":
            sys.exit(3)
        raise KeyboardInterrupt


class LeaverFactory(LoopFactory):
    def __init__(self, how: str) -> None:
        super().__init__()
        self.how = how

    def get(self, parent: AbstractNode) -> Leaver:
        return Leaver(self, parent)


class TestLoopsLeaveInWords(unittest.TestCase):
    def setUp(self) -> None:
        self.hooked: List[Any] = []
        previous = threading.excepthook
        threading.excepthook = self.hooked.append
        self.addCleanup(setattr, threading, "excepthook", previous)

    def check(self, how: str, said: str) -> None:
        for mode in (Mode.TEST, Mode.DEPLOYED):
            with self.subTest(mode=mode), self.assertLogs("snr.life", "WARNING") as logs:
                node = run_node([LeaverFactory(how)], mode=mode)
            text = "\n".join(logs.output)
            self.assertIn(said, text)
            self.assertIn("Loop 'leaver'", text)
            self.assertIn("test_node_lifecycle.py", text)  # the student's line
            self.assertIn("leaver", node.terminate_reason or "")
        self.assertEqual(self.hooked, [], "no raw thread traceback")

    def test_sys_exit_in_a_loop_stops_the_node_and_says_why(self) -> None:
        self.check("exit", "sys.exit(3)")

    def test_keyboard_interrupt_in_a_loop_stops_the_node_and_says_why(self) -> None:
        self.check("ctrl-c", "KeyboardInterrupt")


class Stubborn(ThreadLoop):
    """Ignores the stop flag for a while (a blocking read without a timeout)."""

    def __init__(self, factory: StubbornFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stubborn")
        self.stubborn_factory = factory

    def loop(self) -> None:
        self.stubborn_factory.entered.set()
        self.stubborn_factory.release.wait(3.0)

    def terminate(self) -> None:
        self.warn("terminate() called while the thread is alive: %s", self.is_alive())


class StubbornFactory(LoopFactory):
    def __init__(self) -> None:
        super().__init__()
        self.entered = threading.Event()
        self.release = threading.Event()

    def get(self, parent: AbstractNode) -> Stubborn:
        return Stubborn(self, parent)


class TestShutdownNamesLiveLoops(unittest.TestCase):
    def test_a_loop_still_running_is_named_before_its_terminate(self) -> None:
        stubborn = StubbornFactory()

        def once_it_is_stuck(node: Any) -> None:
            stubborn.entered.wait(2.0)

        try:
            with self.assertLogs("snr.life", "WARNING") as logs:
                run_node([stubborn, ScriptFactory([once_it_is_stuck])], join_timeout_s=0.1)
        finally:
            stubborn.release.set()
        said = [line for line in logs.output if "stubborn" in line]
        self.assertIn("Loop 'stubborn' did not stop within 0.1 s", said[0])
        self.assertIn("self.stubborn_factory.release.wait(3.0)", said[0])  # where it is
        self.assertIn("terminate() called while the thread is alive: True", said[1])


class Failing(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "failing")
        self.task_handlers = {
            (TaskType.event, "poke"): self.on_poke,
            (TaskType.event, "done"): lambda task, key: tasks.terminate("done"),
        }

    def begin(self) -> None:
        self.schedule([tasks.event("poke") for _ in range(2000)] + [tasks.event("done")])

    def on_poke(self, task: Task, key: TaskId) -> SomeTasks:
        return 1 / 0  # type: ignore[return-value]


class FailingFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Failing:
        return Failing(self, parent)


class ReadsWhatSetupStored(ThreadLoop):
    """Thesis listing A.4's pattern: setup() stores a page that loop() reads at once."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "reader", max_tick_rate_hz=0.5)
        self.seen: List[Any] = []

    def setup(self) -> None:
        self.store_data("thruster_data", 0)

    def loop(self) -> None:
        page = self.get_page("thruster_data")
        self.seen.append(None if page is None else page.data)
        self.set_terminate_flag("read once")
        self.schedule(tasks.terminate("read once"))


class ReadsWhatSetupStoredFactory(LoopFactory):
    def __init__(self) -> None:
        super().__init__()
        self.built: List[ReadsWhatSetupStored] = []

    def get(self, parent: AbstractNode) -> ReadsWhatSetupStored:
        self.built.append(ReadsWhatSetupStored(self, parent))
        return self.built[-1]


class TestSetupComesFirst(unittest.TestCase):
    def test_what_setup_stored_is_there_in_the_first_loop(self) -> None:
        for _ in range(20):  # a race would show within a few runs
            factory = ReadsWhatSetupStoredFactory()
            run_node([factory])
            self.assertEqual(factory.built[0].seen, [0])


class TestRepeatedFailures(unittest.TestCase):
    def test_the_same_failure_is_shown_three_times_then_counted(self) -> None:
        with self.assertLogs("snr.life", "ERROR") as logs:
            run_node([FailingFactory()], mode=Mode.DEPLOYED)
        summaries = [line for line in logs.output if "more times in the last" in line]
        full = [line for line in logs.output if "Where it happened" in line]
        self.assertEqual(len(full), 3)
        self.assertIn("counted from now on", full[2])
        self.assertEqual(len(summaries), 1)  # flushed at shutdown
        self.assertIn("1997 more times", summaries[0])
        self.assertIn("(2000 in all)", summaries[0])
        self.assertLess(len(logs.output), 10)


class TestBoundedQueue(unittest.TestCase):
    def make_queue(self, high_water: int, max_wait_s: float) -> TaskQueue:
        queue = TaskQueue(high_water=high_water, max_wait_s=max_wait_s)
        queue.owner_thread = -1  # a consumer that is not this thread
        return queue

    def test_a_producer_waits_then_drops_counts_and_says_so(self) -> None:
        queue = self.make_queue(high_water=10, max_wait_s=0.02)
        with self.assertLogs("snr", "WARNING") as logs:
            for i in range(14):
                queue.schedule(tasks.event(str(i)))
        self.assertEqual(len(queue), 10)  # never above the high-water mark
        self.assertEqual(queue.loss.total, 4)
        self.assertIn("Dropped 1 tasks from other threads", logs.output[0])
        self.assertIn("queue held over 10 tasks", logs.output[0])
        self.assertLessEqual(len(logs.output), 2)  # at most once a second
        queue.schedule(tasks.terminate("urgent never waits"))
        self.assertEqual(len(queue.urgent), 1)

    def test_a_producer_resumes_when_the_node_catches_up(self) -> None:
        queue = self.make_queue(high_water=10, max_wait_s=2.0)
        queue.schedule([tasks.event(str(i)) for i in range(10)])

        def consume() -> None:
            # Only once the producer waits: popping sooner would leave it room.
            wait_until(lambda: queue.waits == 1, 2.0)
            for _ in range(8):
                queue.pop()

        consumer = threading.Thread(target=consume)
        consumer.start()
        queue.schedule(tasks.event("late"))  # waits for the lane to drain to 5
        consumer.join(2.0)
        self.assertEqual(queue.waits, 1)
        self.assertEqual(queue.loss.total, 0)
        self.assertEqual(queue.normal[-1].name, "late")

    def test_a_thread_that_holds_back_by_itself_never_waits(self) -> None:
        queue = self.make_queue(high_water=10, max_wait_s=5.0)
        queue.never_wait(threading.get_ident())  # as a socket I/O thread does
        started = time.monotonic()
        queue.schedule([tasks.event(str(i)) for i in range(30)])
        self.assertLess(time.monotonic() - started, 1.0)  # not the 5 s wait
        self.assertEqual((len(queue), queue.waits, queue.loss.total), (30, 0, 0))

    def test_the_node_itself_never_waits(self) -> None:
        queue = TaskQueue(high_water=10, max_wait_s=5.0)
        queue.owner_thread = threading.get_ident()
        queue.schedule([tasks.event(str(i)) for i in range(50)])
        self.assertEqual(len(queue), 50)
        self.assertEqual(queue.waits, 0)

    def test_a_fast_loop_is_held_to_the_node_pace_and_loses_nothing(self) -> None:
        class Flood(ThreadLoop):
            def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "flood")
                self.sent = 0

            def loop(self) -> None:
                if self.sent == 1000:
                    self.set_terminate_flag("sent everything")
                    return
                self.store_data("n", self.sent)
                self.sent += 1

        class FloodFactory(LoopFactory):
            def get(self, parent: AbstractNode) -> Flood:
                return Flood(self, parent)

        class Slow(Endpoint):
            def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "slow")
                self.got: List[int] = []
                self.longest = 0
                self.task_handlers = {(TaskType.store_page, "n"): self.on_n}

            def on_n(self, task: Task, key: TaskId) -> SomeTasks:
                self.got.append(task.val_list[0].data)
                assert isinstance(self.parent, Node)  # the queue is the Node's
                self.longest = max(self.longest, len(self.parent.queue))
                if len(self.got) % 100 == 0:
                    time.sleep(0.002)
                return tasks.terminate("all in") if len(self.got) == 1000 else None

        slow_box: List[Optional[Slow]] = [None]

        class SlowFactory(EndpointFactory):
            def get(self, parent: AbstractNode) -> Slow:
                slow = slow_box[0] = Slow(self, parent)
                return slow

        original = Node.max_queued_tasks
        Node.max_queued_tasks = 50
        try:
            node = run_node([FloodFactory(), SlowFactory()])
        finally:
            Node.max_queued_tasks = original
        slow = slow_box[0]
        assert slow is not None
        self.assertEqual(slow.got, list(range(1000)))  # in order, none lost
        self.assertGreater(node.queue.waits, 0, "the loop was held back")
        # The bound holds (a store_page task can add its process_data task).
        self.assertLessEqual(slow.longest, 2 * 50 + 2)


if __name__ == "__main__":
    unittest.main()
