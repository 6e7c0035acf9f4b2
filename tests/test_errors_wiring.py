"""Errors that point at the line to fix.

docs/errors.md entries 2a, 2b, 3a, 4a, 4b and 5: the offending line, with the
``def`` or class as context. Each test makes the mistake as a student would,
with the real components.
"""

from __future__ import annotations

import inspect
from typing import Any, Callable, List

from snr import (
    AbstractNode,
    ComponentError,
    Endpoint,
    EndpointFactory,
    HandlerError,
    Mode,
    Node,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)
from snr.core.explain import returning_lines
from snr.prelude import MissingSuperInitError

HERE = "test_errors_wiring.py"
EV = TaskType.event


def line_of(func: Callable[..., Any], text: str) -> int:
    """The line number of the first line of ``func``'s source containing ``text``."""
    lines, first = inspect.getsourcelines(func)
    return first + next(i for i, line in enumerate(lines) if text in line)


class FactoryOf(EndpointFactory):
    """Builds whatever ``build(factory, parent)`` returns."""

    def __init__(self, build: Callable[[Any, AbstractNode], Any]) -> None:
        super().__init__()
        self.build = build

    def get(self, parent: AbstractNode) -> Any:
        return self.build(self, parent)


# -- components with a mistake on one line ------------------------------------------
class HandlersTooEarly(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        self.task_handlers = {(EV, "go"): self.go}
        super().__init__(factory, parent, "too_early")

    def go(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class LogsTooEarly(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        self.info("starting")
        super().__init__(factory, parent, "logs_early")


class NoSuperInit(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        self.volume = 3


class BareKey(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "bare_key")
        self.task_handlers = {"depth": self.on_depth}  # type: ignore[dict-item]

    def on_depth(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class OneArgument(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "one_arg")
        self.task_handlers = {(EV, "go"): self.go}  # type: ignore[dict-item]

    def go(self, task: Task) -> SomeTasks:
        return None


class Counter(Endpoint):
    """Docs entry 4b: the third tick returns a string."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counter")
        self.count = 0
        self.task_handlers = {(EV, "tick"): self.on_tick}

    def begin(self) -> None:
        self.schedule(tasks.event("tick"))

    def on_tick(self, task: Task, key: TaskId) -> SomeTasks:
        self.count += 1
        if self.count < 3:
            return tasks.event("tick")
        if self.count == 3:
            return "done"  # type: ignore[return-value]
        return None


class TwoComputed(Endpoint):
    """Returns one of two computed values; which one the source cannot tell."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "two_computed")
        self.task_handlers = {(EV, "go"): self.go}

    def go(self, task: Task, key: TaskId) -> SomeTasks:
        if task.val_list:
            return task.val_list[0]  # type: ignore[no-any-return]
        return len(task.name)  # type: ignore[return-value]


def pair_or_one(task: Task, key: TaskId) -> Any:
    if task.val_list:
        return tasks.event("a"), tasks.event("b")
    return task.val_list


def generator(task: Task, key: TaskId) -> Any:
    yield tasks.event("a")


class TestTheLineToFix(SNRTestCase):
    def build_error(self, cls: Callable[[Any, AbstractNode], Any]) -> str:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(cls)]))
        return str(ctx.exception)

    def assert_points_at(self, message: str, func: Any, text: str, name: str) -> None:
        line = line_of(func, text)
        self.assertIn(f'{HERE}", line {line}, in {name}', message)
        self.assertIn(text, message.splitlines()[-1])  # the code itself, last

    def test_task_handlers_before_super_init_points_at_that_line(self) -> None:
        message = self.build_error(HandlersTooEarly)
        self.assertIn("HandlersTooEarly (", message)  # the class, as context
        self.assertIn(f"{HERE}:{line_of(HandlersTooEarly, 'class')})", message)
        self.assert_points_at(
            message, HandlersTooEarly.__init__, "self.task_handlers =", "HandlersTooEarly.__init__"
        )

    def test_using_the_component_before_super_init_points_at_that_line(self) -> None:
        with self.assertRaises(MissingSuperInitError) as ctx:
            Node("test", self.get_config([FactoryOf(LogsTooEarly)]))
        self.assert_points_at(
            str(ctx.exception), LogsTooEarly.__init__, 'self.info("starting")', "LogsTooEarly"
        )

    def test_no_super_init_points_at_the_def_init(self) -> None:
        message = self.build_error(NoSuperInit)
        self.assert_points_at(message, NoSuperInit.__init__, "def __init__", "NoSuperInit.__init__")

    def test_a_bad_key_points_at_the_line_that_registers_it(self) -> None:
        message = self.build_error(BareKey)
        self.assert_points_at(message, BareKey.__init__, "self.task_handlers =", "BareKey.__init__")

    def test_a_wrong_signature_shows_the_def(self) -> None:
        message = self.build_error(OneArgument)
        self.assert_points_at(message, OneArgument.go, "def go(self, task: Task)", "OneArgument.go")

    def run_until_failure(self, cls: Callable[[Any, AbstractNode], Any], go: bool) -> str:
        node = Node("test", self.get_config([FactoryOf(cls), TimeoutLoopFactory(seconds=2)]))
        if go:
            node.schedule(tasks.event("go", [7]))
        with self.assertRaises(HandlerError) as ctx:
            node.loop()
        return str(ctx.exception)

    def test_a_wrong_return_points_at_that_return(self) -> None:
        message = self.run_until_failure(Counter, go=False)
        line = line_of(Counter.on_tick, 'return "done"')
        first = line_of(Counter.on_tick, "def on_tick")
        self.assertIn("returned 'done' (str) at ", message)
        self.assertIn(f"{HERE}:{line} while handling (event, 'tick')", message)
        self.assertIn(f"in Counter.on_tick (defined at line {first})", message)
        self.assertIn('    return "done"', message)

    def test_every_return_that_may_have_given_it_is_shown(self) -> None:
        message = self.run_until_failure(TwoComputed, go=True)
        lines = [line_of(TwoComputed.go, text) for text in ("return task.val_list", "return len")]
        self.assertIn("at one of its returns, ", message)
        self.assertIn(f"{HERE}:{lines[0]}, {lines[1]}, while handling", message)
        for line in lines:
            self.assertIn(f'{HERE}", line {line}, in TwoComputed.go', message)

    def test_which_returns_can_give_the_value(self) -> None:
        def line(func: Any, text: str) -> List[int]:
            return [line_of(func, text)]

        pair = (tasks.event("a"), tasks.event("b"))
        self.assertEqual(returning_lines(pair_or_one, pair), line(pair_or_one, "return tasks"))
        self.assertEqual(returning_lines(pair_or_one, [1]), line(pair_or_one, "return task.val"))
        self.assertEqual(returning_lines(Counter.on_tick, "done"), line(Counter.on_tick, "done"))
        self.assertEqual(returning_lines(generator, None), [])  # a generator: the def is named
        self.assertEqual(returning_lines(lambda task, key: 5, 5), [])  # no def to read

    def test_deployed_logs_the_line_and_keeps_running(self) -> None:
        node = Node(
            "test",
            self.get_config([FactoryOf(Counter), TimeoutLoopFactory(seconds=0.05)], Mode.DEPLOYED),
        )
        with self.assertLogs(node.log, "ERROR") as logs:
            node.loop()  # no error raised: DEPLOYED keeps running
        line = line_of(Counter.on_tick, 'return "done"')
        self.assertIn(f"{HERE}:{line} while handling", logs.output[0])
