"""Errors that point at the line to fix, and keys that never cross a link.

docs/errors.md entries 2a, 2b, 3a, 4a, 4b and 5 (the offending line, with the
``def`` or class as context) and 9c (a key that should come from, or go to,
another node but does not). Each test makes the mistake as a student would,
with the real components.
"""

from __future__ import annotations

import inspect
import logging
import threading
import time
from types import SimpleNamespace
from typing import Any, Callable, List, Sequence, Tuple

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    Mode,
    Node,
    SNRTestCase,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)
from snr.core import MissingKeyHints
from snr.core.checks.explain import returning_lines
from snr.prelude import ComponentError, HandlerError, MissingSuperInitError
from tests.helpers import FactoryOf, free_port
from tests.quiet import capture_test_logs

HERE = "test_errors_wiring.py"
EV = TaskType.event


def line_of(func: Callable[..., Any], text: str) -> int:
    """The line number of the first line of ``func``'s source containing ``text``."""
    lines, first = inspect.getsourcelines(func)
    return first + next(i for i, line in enumerate(lines) if text in line)


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
        self.assertIn("before calling super().__init__", message)
        self.assertIn("HandlersTooEarly (", message)  # the class, as context
        self.assertIn(f"{HERE}:{line_of(HandlersTooEarly, 'class')})", message)
        self.assert_points_at(
            message, HandlersTooEarly.__init__, "self.task_handlers =", "HandlersTooEarly.__init__"
        )

    def test_using_the_component_before_super_init_points_at_that_line(self) -> None:
        with self.assertRaises(MissingSuperInitError) as ctx:
            Node("test", self.get_config([FactoryOf(LogsTooEarly)]))
        self.assertIsInstance(ctx.exception, AttributeError)  # hasattr() still works
        self.assertIn("super().__init__(factory, parent", str(ctx.exception))
        self.assert_points_at(
            str(ctx.exception), LogsTooEarly.__init__, 'self.info("starting")', "LogsTooEarly"
        )

    def test_no_super_init_points_at_the_def_init(self) -> None:
        message = self.build_error(NoSuperInit)
        self.assertIn("did not call super().__init__(factory, parent, name)", message)
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
        with self.assertRaises(HandlerError) as ctx, self.assertLogs(node.log, "ERROR") as logs:
            node.loop()
        self.assertIn(f"Stopping node 'test': Task handler {cls.__name__}.", logs.output[0])
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


# -- 9c. keys that should cross a link but do not -----------------------------------
class Watcher(Endpoint):
    """Handles pages under each of ``keys``."""

    def __init__(self, factory: WatcherFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "watcher")
        self.task_handlers = {(TaskType.store_page, key): self.on_page for key in factory.keys}

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class WatcherFactory(EndpointFactory):
    def __init__(self, keys: Sequence[str]) -> None:
        super().__init__()
        self.keys = keys

    def get(self, parent: AbstractNode) -> Watcher:
        return Watcher(self, parent)


class Hints(logging.Handler):
    """Collects the key hints of every node; ``wait`` until ``count`` have come."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.messages: List[Tuple[str, str, str]] = []  # (node logger, level, text)
        self.changed = threading.Condition()

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage()
        if "node.key_hints = None" in text:
            with self.changed:
                self.messages.append((record.name, record.levelname, text))
                self.changed.notify_all()

    def wait(self, count: int, timeout_s: float = 5.0) -> None:
        with self.changed:
            self.changed.wait_for(lambda: len(self.messages) >= count, timeout_s)


class TestKeysAcrossALink(SNRTestCase):
    def run_nodes(self, config: Config, link_s: float, hints: Hints, count: int) -> List[Node]:
        """Run topside and urov on threads until ``count`` hints came (or 5 s), then stop."""
        capture_test_logs(self)  # the hints and the links' INFO lines, read through `hints`
        nodes = [Node(role, config) for role in ("topside", "urov")]
        threads = [threading.Thread(target=node.loop, name=f"test-{node.role}") for node in nodes]
        for node in nodes:
            assert node.key_hints is not None
            node.key_hints.handlers_s = 60.0  # only the link check, not the one at start
            node.key_hints.link_s = link_s
            node.log.addHandler(hints)
            self.addCleanup(node.log.removeHandler, hints)
            # The "snr.<role>" loggers outlive a node: another test's mode may
            # have left one at WARNING, which would drop the INFO hints.
            self.addCleanup(node.log.setLevel, node.log.level)
            node.log.setLevel(logging.INFO)
        for thread in threads:
            thread.start()
        try:
            hints.wait(count)
        finally:
            for node in nodes:
                node.set_terminate_flag("test over")
            for thread in threads:
                thread.join(5.0)
        return nodes

    def test_5_1_telemetry_that_never_arrives(self) -> None:
        # The robot stores 'depth' and 'sonar' and forwards 'depth_m' (which it
        # never stores) and 'sonar'; the topside waits for 'depth_m', 'sonar'
        # (arrives: quiet) and 'sonr' (a typo for what arrives).
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        safety = TimeoutLoopFactory(seconds=8)
        config = Config(
            {
                "topside": [pair.server(), WatcherFactory(["depth_m", "sonar", "sonr"]), safety],
                "urov": [
                    ListReplayerFactory(list(range(200)), "depth", period_s=0.01),
                    ListReplayerFactory(list(range(200)), "sonar", period_s=0.01, name="sonar"),
                    pair.client(["depth_m", "sonar"]),
                    safety,
                ],
            },
            mode=Mode.DEBUG,
        )
        hints = Hints()
        self.run_nodes(config, link_s=0.2, hints=hints, count=3)
        self.assertEqual(len(hints.messages), 3, hints.messages)
        unsent = [m for m in hints.messages if m[0] == "snr.urov"]
        received = sorted(m for m in hints.messages if m[0] == "snr.topside")
        self.assertEqual(len(unsent), 1, hints.messages)
        _, level, text = unsent[0]
        self.assertEqual(level, "WARNING")
        for part in ("'depth_m'", "to node 'topside' at 127.0.0.1:", "Did you mean 'depth'?"):
            self.assertIn(part, text)
        texts = {t.split("pages under ")[1].split(",")[0]: (lvl, t) for _, lvl, t in received}
        self.assertEqual(sorted(texts), ["'depth_m'", "'sonr'"])  # 'sonar' arrived: quiet
        level, text = texts["'sonr'"]
        self.assertEqual(level, "WARNING")
        for part in ("Watcher.on_page", HERE, "from node 'urov' at", "Did you mean 'sonar'?"):
            self.assertIn(part, text)
        self.assertIn("Keys received from it: 'sonar'", text)
        level, text = texts["'depth_m'"]
        self.assertEqual(level, "INFO")  # nothing like it arrived: perhaps only rare
        self.assertNotIn("Did you mean", text)
        self.assertIn("sockets.client(['depth_m'])", text)

    def test_once_per_key_and_quiet_once_the_key_is_there(self) -> None:
        log = logging.getLogger("snr.test.link_hints")
        hints = MissingKeyHints(log, time.monotonic, link_s=3.0)
        handled = [("sonr", pair_or_one)]
        with self.assertLogs(log, "INFO") as logs:
            hints.check_link("'c'", "node 'urov' at here", ["x"], handled, [], ["sonar"])
            hints.check_link("'c'", "node 'urov' at here", ["x"], handled, [], ["sonar"])
            hints.check_link("'c'", "node 'urov' at here", ["y"], [], ["y"], [])  # stored: quiet
            log.info("end")
        self.assertEqual(len(logs.output), 3, logs.output)  # x, sonr, end
        self.assertIn("Comms component 'c' forwards pages under 'x'", logs.output[0])
        self.assertIn("Did you mean 'sonar'?", logs.output[1])

    def test_a_key_read_early_that_a_handler_waits_for_is_still_checked(self) -> None:
        now = [0.0]
        log = logging.getLogger("snr.test.link_hints")
        hints = MissingKeyHints(log, lambda: now[0])
        hints.expected_keys = lambda: {"depth_m"}
        with self.assertLogs(log, "INFO") as logs:
            for step in range(100):  # a display loop reads it for 10 s: no read hint
                now[0] = step * 0.1
                hints.missed("depth_m", ["depth"])
            hints.check_link("'c'", "node 'urov'", [], [("depth_m", pair_or_one)], [], ["depth"])
        self.assertEqual(len(logs.output), 1, logs.output)
        self.assertIn("none has arrived from node 'urov'", logs.output[0])
        self.assertIn("Did you mean 'depth'?", logs.output[0])

    def test_the_check_at_start_leaves_comms_keys_to_the_link_check(self) -> None:
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        node = Node("urov", Config({"urov": [pair.client("depth_m")]}, mode=Mode.TEST))
        comms: Any = node.components["sockets_client_" + str(pair.server_tuple[1])]
        student = Watcher(WatcherFactory(["depth_m"]), node)
        log = logging.getLogger("snr.test.link_hints")
        hints = MissingKeyHints(log, time.monotonic)
        with self.assertLogs(log, "INFO") as logs:
            hints.check_handlers([("depth_m", comms.forward_page)], ["depth"])
            log.info("end")
            hints.check_handlers([("depth_m", student.on_page)], ["depth"])
        self.assertEqual(len(logs.output), 2, logs.output)  # the student's handler only
        self.assertIn("Watcher.on_page", logs.output[1])

    def test_no_watching_outside_debug_mode(self) -> None:
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        for mode in (Mode.TEST, Mode.DEPLOYED):
            node = Node("urov", Config({"urov": [pair.client("depth")]}, mode=mode))
            link: Any = SimpleNamespace(keys_received=None)
            comms: Any = node.components["sockets_client_" + str(pair.server_tuple[1])]
            comms.watch_link(link)
            self.assertIsNone(link.keys_received, mode)  # nothing is noted, no timer is set
            self.assertIsNone(node.key_hints)
