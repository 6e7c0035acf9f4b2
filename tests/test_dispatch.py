"""Two-phase matching (thesis 4.4.1) and the O(1) handler table (8.1)."""

from __future__ import annotations

import random
import unittest
from typing import Any, List, Tuple

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    Node,
    Page,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.core import HandlerTable
from snr.core.dispatch import check_burst_handlers
from snr.prelude import ComponentError, HandlerError, TaskPriority
from snr.utils import DummyEndpointFactory
from tests.helpers import Log, RecorderFactory, StopWhenDrainedFactory

EV = TaskType.event
SP = TaskType.store_page


def naive_match(components: List[Any], task: Task) -> List[Tuple[str, TaskId]]:
    """The thesis algorithm: ask every endpoint, specific id first, then type."""
    found = []
    for component in components:
        for key in ((task.type, task.name), task.type):
            if key in component.task_handlers:
                found.append((component.name, key))
                break
    return found


class TestTwoPhaseMatching(SNRTestCase):
    def run_node(self, factories: List[Any], first: List[Task]) -> None:
        # The node stops once ``first`` and every task it led to have run.
        self.run_test_node([*factories, StopWhenDrainedFactory(first)])

    def test_specific_beats_type_per_endpoint_and_all_endpoints_run(self) -> None:
        log: Log = []
        self.run_node(
            [
                RecorderFactory("both", [(EV, "go"), EV], log),
                RecorderFactory("type_only", [EV], log),
                RecorderFactory("specific_only", [(EV, "go")], log),
                RecorderFactory("other", [(EV, "stop")], log),
            ],
            [tasks.event("go")],
        )
        self.assertEqual(
            [(name, key) for name, (_, _, key) in log],
            [("both", (EV, "go")), ("type_only", EV), ("specific_only", (EV, "go"))],
        )

    def test_returned_tasks_are_queued_after_all_handlers_in_order(self) -> None:
        log: Log = []

        def reply(prefix: str) -> Any:
            return lambda task, key: (
                [tasks.event(f"{prefix}1"), tasks.event(f"{prefix}2")]
                if task.name == "go"
                else None
            )

        self.run_node(
            [
                RecorderFactory("a", [(EV, "go")], log, reply("a")),
                RecorderFactory("b", [(EV, "go")], log, reply("b")),
                RecorderFactory("watch", [EV], log),
            ],
            [tasks.event("go")],
        )
        order = [(n, t[1]) for n, t in log]
        self.assertEqual(order[:3], [("a", "go"), ("b", "go"), ("watch", "go")])
        self.assertEqual(
            [name for who, name in order if who == "watch"], ["go", "a1", "a2", "b1", "b2"]
        )

    def test_handlers_changed_at_run_time_take_effect(self) -> None:
        log: Log = []
        switch = RecorderFactory("switch", [(EV, "flip")], log)

        def flip(task: Task, key: TaskId) -> Any:
            endpoint = switch.built["switch"]
            endpoint.task_handlers[(EV, "second")] = endpoint.record
            del endpoint.task_handlers[(EV, "first")]
            return None

        switch.reply = lambda t, k: flip(t, k) if t.name == "flip" else None
        switch.keys = [(EV, "flip"), (EV, "first")]
        self.run_node(
            [switch],
            [
                tasks.event("first"),
                tasks.event("flip"),
                tasks.event("first"),
                tasks.event("second"),
            ],
        )
        self.assertEqual([t[1] for _, t in log], ["first", "flip", "second"])

    def test_reassigning_task_handlers_is_seen(self) -> None:
        log: Log = []
        factory = RecorderFactory("r", [(EV, "a")], log)

        def swap(task: Task, key: TaskId) -> Any:
            endpoint = factory.built["r"]
            endpoint.task_handlers = {(EV, "b"): endpoint.record}
            return None

        factory.reply = swap
        self.run_node([factory], [tasks.event("a"), tasks.event("a"), tasks.event("b")])
        self.assertEqual([t[1] for _, t in log], ["a", "b"])


class TestHandlerTable(unittest.TestCase):
    def test_matches_the_naive_algorithm_on_random_systems(self) -> None:
        rng = random.Random(42)
        names = ["a", "b", "c", "d"]
        types = [TaskType.event, TaskType.store_page, TaskType.process_data]
        for trial in range(60):
            config = Config({"r": [DummyEndpointFactory("x")]}, mode=Mode.TEST)
            node = Node("r", config)
            components = list(node.components.values())
            table = HandlerTable()
            table.rebuild(components)
            for i in range(rng.randint(1, 8)):
                keys: List[TaskId] = []
                for _ in range(rng.randint(0, 4)):
                    t = rng.choice(types)
                    keys.append(t if rng.random() < 0.3 else (t, rng.choice(names)))
                factory = DummyEndpointFactory(f"e{i}", keys)
                component = factory.get(node)
                if rng.random() < 0.5:  # some take runs of their pages in one call
                    component.burst_handlers = {
                        key: lambda run: None
                        for key in keys
                        if isinstance(key, tuple) and key[0] is SP
                    }
                components.append(component)
                if rng.random() < 0.5:
                    table.add(component)  # incremental, as when the node adds one
                else:
                    table.rebuild(components)
            for t in types:
                for n in [*names, "zzz"]:
                    task = Task(t, n)
                    got = [(c.name, k) for _, k, c, _ in table.lookup(t, n)]
                    self.assertEqual(got, naive_match(components, task), f"trial {trial}: {task}")
            # The burst handlers found one add at a time are those a rebuild finds:
            # where exactly one component handles (store_page, name) and has one.
            rebuilt = HandlerTable()
            rebuilt.rebuild(components)
            self.assertEqual(table.bursts, rebuilt.bursts, f"trial {trial}")
            for n in names:
                matched = naive_match(components, Task(SP, n))
                expected = None
                if len(matched) == 1:
                    owner = next(c for c in components if c.name == matched[0][0])
                    expected = owner.burst_handlers.get(matched[0][1])
                found = table.bursts.get((SP, n))
                self.assertIs(found[0] if found else None, expected, f"trial {trial}: {n}")

    def test_a_later_component_handling_every_page_ends_the_bursts(self) -> None:
        node = Node("r", Config({"r": [DummyEndpointFactory("x")]}, mode=Mode.TEST))
        first = DummyEndpointFactory("first", [(SP, "a")]).get(node)
        first.burst_handlers = {(SP, "a"): lambda run: None}
        table = HandlerTable()
        table.add(first)
        self.assertIn((SP, "a"), table.bursts)
        table.add(DummyEndpointFactory("every_page", [SP]).get(node))
        self.assertNotIn((SP, "a"), table.bursts, "two components now handle its pages")

    def test_a_burst_handler_needs_a_task_handler_for_its_id(self) -> None:
        node = Node("r", Config({"r": [DummyEndpointFactory("x")]}, mode=Mode.TEST))
        component = DummyEndpointFactory("lonely", [(SP, "a")]).get(node)
        component.burst_handlers = {(SP, "b"): lambda run: None}
        with self.assertRaises(ComponentError) as raised:
            node.add_component(component)
        self.assertIn("no handler for it in task_handlers", str(raised.exception))
        component.burst_handlers = {SP: lambda run: None}
        with self.assertRaises(ComponentError) as raised:
            check_burst_handlers(component)
        self.assertIn("(TaskType.store_page, 'the_key')", str(raised.exception))
        # The table itself never raises (it is built between two tasks): it
        # leaves such a burst handler unused.
        table = HandlerTable()
        table.add(component)
        self.assertEqual(table.bursts, {})

    def test_idle_endpoints_do_not_grow_the_lookup(self) -> None:
        node = Node(
            "r", Config({"r": [DummyEndpointFactory("ping", [(EV, "ping")])]}, mode=Mode.TEST)
        )
        for i in range(1000):
            node.add_component(DummyEndpointFactory(f"idle{i}", [(EV, f"idle{i}")]).get(node))
        entries = node.get_task_handlers(tasks.event("ping"))
        self.assertEqual(len(entries), 1)  # one dict look-up, one handler: not 1000 checks


class Burster(Endpoint):
    """Logs the pages under "x" it forwards: one by one, or a run in one call."""

    def __init__(self, factory: BursterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "burster")
        self.spec = factory
        self.task_handlers = {(SP, "x"): self.one, (TaskType.process_data, "x"): self.processed}
        self.burst_handlers = {(SP, "x"): self.many}

    def one(self, task: Task, key: TaskId) -> SomeTasks:
        self.spec.log.append(("one", task.val_list[0].data))
        return None

    def many(self, run: List[Task]) -> SomeTasks:
        stored = self.parent.get_page("x")
        data = [task.val_list[0].data for task in run]
        self.spec.log.append(("many", data, stored.data if stored else None))
        if self.spec.fail:
            raise RuntimeError("the burst broke")
        return tasks.event("burst_done")

    def processed(self, task: Task, key: TaskId) -> SomeTasks:
        self.spec.log.append(("processed", task.val_list[0].data))
        return None


class BursterFactory(EndpointFactory):
    def __init__(self, log: List[Any], fail: bool = False) -> None:
        super().__init__()
        self.log, self.fail = log, fail

    def get(self, parent: AbstractNode) -> Burster:
        return Burster(self, parent)


class TestBursts(SNRTestCase):
    """A run of store_page tasks under one key may reach a component in one call."""

    FIRST = [
        *[tasks.store_data("x", i) for i in range(5)],
        tasks.store_data("y", 9),  # another key ends the run
        tasks.store_data("x", 5),  # alone: the usual handler
    ]

    def test_a_run_is_stored_first_then_handed_over_in_one_call(self) -> None:
        log: List[Any] = []
        node = self.run_test_node([BursterFactory(log), StopWhenDrainedFactory(self.FIRST)])
        self.assertEqual(log[0], ("many", [0, 1, 2, 3, 4], 4), "every page stored first")
        self.assertEqual(log[1], ("one", 5))
        self.assertEqual([d for kind, d in log[2:] if kind == "processed"], [0, 1, 2, 3, 4, 5])
        cell = node._components.table.table[(SP, "x")][0][3]
        self.assertEqual(cell[0], 6, "timed as one call a task")

    def test_an_urgent_page_never_starts_a_run(self) -> None:
        log: List[Any] = []
        urgent = Task(SP, "x", [Page("x", -1, "test", 0.0)], priority=TaskPriority.high)
        self.run_test_node([BursterFactory(log), StopWhenDrainedFactory([urgent, *self.FIRST])])
        self.assertEqual(log[0], ("one", -1), "the urgent page went alone")
        self.assertEqual(log[1], ("many", [0, 1, 2, 3, 4], 4))

    def test_no_run_when_another_component_handles_the_key_too(self) -> None:
        log: List[Any] = []
        other: Log = []
        self.run_test_node(
            [
                BursterFactory(log),
                RecorderFactory("other", [(SP, "x"), (EV, "burst_done")], other),
                StopWhenDrainedFactory(self.FIRST),
            ]
        )
        self.assertEqual([d for kind, d in log if kind == "one"], [0, 1, 2, 3, 4, 5])
        self.assertNotIn("many", [entry[0] for entry in log])
        self.assertEqual(len(other), 6, "each handler saw every page, in turn")

    def test_what_a_burst_handler_returns_is_queued_and_what_it_raises_is_reported(
        self,
    ) -> None:
        log: List[Any] = []
        done: Log = []
        self.run_test_node(
            [
                BursterFactory(log),
                RecorderFactory("done", [(EV, "burst_done")], done),
                StopWhenDrainedFactory(self.FIRST),
            ]
        )
        self.assertEqual(len(done), 1, "the returned event ran")
        with self.assertRaises(HandlerError) as raised, self.assertLogs("snr", "ERROR"):
            self.run_test_node([BursterFactory([], fail=True), StopWhenDrainedFactory(self.FIRST)])
        self.assertIn("many", str(raised.exception))
        self.assertIn("the burst broke", str(raised.exception))

    def test_execute_task_runs_one_page_though_a_run_waits_behind_it(self) -> None:
        log: List[Any] = []

        def execute_one_page(task: Task, key: TaskId) -> SomeTasks:
            node.schedule(tasks.terminate("stop first"))  # urgent: next after this one
            node.execute_task(tasks.store_data("x", -1))
            return None

        trigger = RecorderFactory("trigger", [(EV, "go")], [], reply=execute_one_page)
        waiting = [tasks.event("go"), *[tasks.store_data("x", i) for i in range(10)]]
        node = Node("r", Config({"r": [BursterFactory(log), trigger]}, mode=Mode.TEST))
        node.schedule(waiting)
        node.loop()
        self.assertEqual(log, [("one", -1)], "one task ran, then the terminate")
        self.assertEqual(node.get_data("x"), -1)

    def test_a_run_ends_where_a_failed_store_stopped_the_node(self) -> None:
        log: List[Any] = []
        unstorable = Task(SP, "x", [Page(["x"], 3, "test", 0.0)])  # type: ignore[arg-type]
        first = [*[tasks.store_data("x", i) for i in range(3)], unstorable]
        first += [tasks.store_data("x", i) for i in range(4, 10)]
        with self.assertRaises(HandlerError), self.assertLogs("snr", "ERROR"):
            self.run_test_node([BursterFactory(log), StopWhenDrainedFactory(first)])
        self.assertEqual(len(log), 1)
        kind, data, _ = log[0]
        self.assertEqual((kind, data[:3], len(data)), ("many", [0, 1, 2], 4), "no page after it")

    def test_a_failing_burst_handler_is_reported_with_the_size_of_its_run(self) -> None:
        with self.assertRaises(HandlerError) as raised, self.assertLogs("snr", "ERROR"):
            self.run_test_node([BursterFactory([], fail=True), StopWhenDrainedFactory(self.FIRST)])
        self.assertIn("a run of 5 tasks given to it at once, the first", str(raised.exception))

    def test_a_bad_burst_handler_added_or_made_at_run_time_is_an_error_the_node_survives(
        self,
    ) -> None:
        class LosesItsHandler(Burster):
            def processed(self, task: Task, key: TaskId) -> SomeTasks:
                self.task_handlers = {(EV, "later"): self.processed}  # the burst's id is gone
                return None

        class LosesItsHandlerFactory(BursterFactory):
            def get(self, parent: AbstractNode) -> Burster:
                return LosesItsHandler(self, parent)

        class Lonely(Burster):
            def __init__(self, factory: BursterFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent)
                self.name = "lonely"
                self.burst_handlers = {(SP, "nowhere"): self.many}

        class LonelyFactory(BursterFactory):
            def get(self, parent: AbstractNode) -> Burster:
                return Lonely(self, parent)

        for factory in (LosesItsHandlerFactory([]), LonelyFactory([])):
            after: Log = []
            first = [
                tasks.store_data("x", 0),
                tasks.add_component(factory),
                tasks.event("after"),
                tasks.store_data("x", 1),
                tasks.store_data("x", 2),
            ]
            with self.subTest(type(factory).__name__), self.assertLogs("snr", "ERROR") as logs:
                node = self.run_test_node(
                    [
                        RecorderFactory("after", [(EV, "after")], after),
                        StopWhenDrainedFactory(first),
                    ],
                    mode=Mode.DEPLOYED,
                )
            self.assertEqual(node.terminate_reason, "queue drained")
            self.assertEqual(len(after), 1, "the tasks after it still ran")
            self.assertIn("no handler for it in task_handlers", "\n".join(logs.output))
            self.assertIn("The node keeps running", "\n".join(logs.output))


if __name__ == "__main__":
    unittest.main()
