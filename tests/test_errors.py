"""Errors that teach: one test per entry of docs/errors.md.

Each test makes the mistake as a student would write it and checks the
message names their class or handler, their file, and the fix.
"""

from __future__ import annotations

import contextlib
import errno
import io
import logging
import math
import os
import socket
import subprocess
import sys
import textwrap
import threading
import time
import unittest
from abc import ABC, abstractmethod
from functools import partial
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple
from unittest import mock

import tests.test_errors_silence as silence
from snr import (
    AbstractEndpoint,
    AbstractFactory,
    AbstractNode,
    CliRunner,
    ComponentsByRole,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    Page,
    SNRTestCase,
    SocketsPair,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)
from snr.core import MissingKeyHints
from snr.core.checks.os_errors import OsAction, explain_os_error
from snr.extras.serial import port as serial_port
from snr.extras.serial.board import compact_line
from snr.extras.viz.live_view import _listen as live_view_listen
from snr.prelude import (
    CommsError,
    ComponentError,
    ConfigError,
    HandlerError,
    LoopError,
    NotSerializableError,
    ThreadSafetyError,
)
from snr.prelude.not_serializable import not_serializable_error
from snr.std_mods.codec import page_json, page_to_line
from snr.std_mods.comms.sockets import _listen as sockets_listen
from snr.std_mods.io.console_protocol import ConsoleConnectionError
from snr.std_mods.io.remote_console import RemoteConsole
from tests.helpers import StopWhenDrainedFactory, StopWhenFactory, StopWhenTrueFactory, free_port
from tests.optional import reason
from tests.quiet import capture_test_logs, captured_logs

HERE = "test_errors.py"
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EV = TaskType.event


class FactoryOf(EndpointFactory):
    """Builds whatever ``build(factory, parent)`` returns: one factory for many mistakes.

    Not tests/helpers.py's: the messages under test point at this file's
    ``get``, as they point at a student's own factory.
    """

    def __init__(self, build: Callable[[Any, AbstractNode], Any]) -> None:
        super().__init__()
        self.build = build

    def get(self, parent: AbstractNode) -> Any:
        return self.build(self, parent)


class LoopFactoryOf(LoopFactory):
    def __init__(self, build: Callable[[Any, AbstractNode], Any]) -> None:
        super().__init__()
        self.build = build

    def get(self, parent: AbstractNode) -> Any:
        return self.build(self, parent)


# -- 1. forgotten methods -----------------------------------------------------
class OnlyAHandler(Endpoint):
    """Writes no begin/halt/terminate: they are optional."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "only_a_handler")
        self.task_handlers = {(EV, "ping"): self.on_ping}
        self.pings = 0

    def on_ping(self, task: Task, key: TaskId) -> SomeTasks:
        self.pings += 1
        return None


class OnlyALoop(ThreadLoop):
    """Writes no setup/halt/terminate: they are optional."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "only_a_loop", max_tick_rate_hz=100)

    def loop(self) -> None:
        self.schedule(tasks.event("ping"))


class NoLoopMethod(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sensor")

    def lop(self) -> None:  # typo: should be loop
        pass


class HalfEndpoint(AbstractEndpoint):
    """Implements the interface directly and forgets most of it."""

    def __init__(self, factory: AbstractFactory, parent: AbstractNode) -> None:
        self.factory, self.parent, self.name = factory, parent, "half"

    def begin(self) -> None:
        pass


class Sensor(ABC):
    """A student's own abstract base class."""

    @abstractmethod
    def read(self) -> float: ...


class DepthSensor(Sensor, Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_sensor")


class PressureSensor(Sensor):
    """A plain (non-SNR) class that forgets read()."""

    def calibrate(self) -> None:
        pass


def build_with_plain_sensor(factory: Any, parent: AbstractNode) -> OnlyAHandler:
    PressureSensor()  # type: ignore[abstract]
    return OnlyAHandler(factory, parent)


class FactoryWithoutReload(AbstractFactory):
    def get(self, parent: AbstractNode) -> Any:
        return None


class TestForgottenMethods(SNRTestCase):
    def test_lifecycle_hooks_are_optional(self) -> None:
        endpoint = FactoryOf(OnlyAHandler)
        node = self.run_test_node(
            [endpoint, LoopFactoryOf(OnlyALoop), StopWhenFactory((EV, "ping"))]
        )
        handler = node.components["only_a_handler"]
        assert isinstance(handler, OnlyAHandler)
        self.assertGreater(handler.pings, 0)

    def test_missing_loop_method(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([LoopFactoryOf(NoLoopMethod)]))
        self.assertMessage(ctx.exception, "NoLoopMethod", HERE, "def loop(self) -> None:")

    def test_interface_implemented_directly_names_missing_methods(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(HalfEndpoint)]))
        message = str(ctx.exception)
        self.assertMessage(ctx.exception, "HalfEndpoint", HERE, "subclass snr.Endpoint")
        self.assertIn("halt, join, store_page, task_handlers, terminate", message)
        self.assertIn("FactoryOf.get", message)  # where it was being created
        self.assertNotIn("abstract class", message)

    def test_direct_construction_is_explained_too(self) -> None:
        # Thesis listing 7.1 built the class straight from a test.
        with self.assertRaises(ComponentError) as ctx:
            HalfEndpoint(FactoryOf(OnlyAHandler), self.mock_node())  # type: ignore[abstract]
        self.assertIn("test_direct_construction_is_explained_too", str(ctx.exception))
        self.assertNotIn("abstract class", str(ctx.exception))

    def test_students_own_abstract_base_is_explained(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(DepthSensor)]))
        message = str(ctx.exception)
        self.assertMessage(ctx.exception, "DepthSensor", HERE, "read")
        self.assertIn("Sensor requires", message)
        self.assertNotIn("abstract class", message)

    def test_plain_abstract_class_built_in_get_is_explained(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(build_with_plain_sensor)]))
        message = str(ctx.exception)
        for part in ("PressureSensor", HERE, "Sensor requires: read", "build_with_plain_sensor"):
            self.assertIn(part, message)
        self.assertNotIn("abstract class", message)

    def test_factory_implementing_interface_directly(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            FactoryWithoutReload()  # type: ignore[abstract]
        self.assertMessage(ctx.exception, "FactoryWithoutReload", HERE, "snr.EndpointFactory")
        self.assertIn("reload", str(ctx.exception))

    def test_factory_without_get(self) -> None:
        class NoGetFactory(EndpointFactory):
            pass

        with self.assertRaises(ComponentError) as ctx:
            NoGetFactory()
        self.assertMessage(ctx.exception, "NoGetFactory", HERE, "def get(self, parent")

    def assertMessage(self, error: BaseException, *parts: str) -> None:
        for part in parts:
            self.assertIn(part, str(error))


# -- 2. super().__init__ forgotten or given the wrong arguments -------------------
# (Handlers set or the component used before super().__init__, and no
# super().__init__ at all: tests/test_errors_wiring.py, TestTheLineToFix.)
class SwappedArguments(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(parent, factory, "swapped")  # type: ignore[arg-type]


class NameFirst(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__("name_first", factory, parent)  # type: ignore[arg-type]


class FactoryNoSuperInit(EndpointFactory):
    def __init__(self) -> None:
        self.settings = 1

    def get(self, parent: AbstractNode) -> OnlyAHandler:
        return OnlyAHandler(self, parent)


class TestSuperInit(SNRTestCase):
    def build(self, cls: Callable[[Any, AbstractNode], Any]) -> BaseException:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(cls)]))
        return ctx.exception

    def test_swapped_arguments(self) -> None:
        error = self.build(SwappedArguments)
        for part in ("SwappedArguments", HERE, "swapped", "super().__init__(factory, parent"):
            self.assertIn(part, str(error))

    def test_name_first(self) -> None:
        error = self.build(NameFirst)
        for part in ("NameFirst", HERE, "wrong order", "the factory first"):
            self.assertIn(part, str(error))

    def test_factory_without_super_init(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryNoSuperInit()]))
        for part in ("FactoryNoSuperInit", HERE, "super().__init__()"):
            self.assertIn(part, str(ctx.exception))


# -- 3, 4, 5. handlers: signature, return value, key ----------------------------
class OneArgumentHandler(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "one_arg")
        self.task_handlers = {(EV, "go"): self.go}  # type: ignore[dict-item]

    def go(self, task: Task) -> SomeTasks:
        return None


class CalledHandler(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "called")
        self.task_handlers = {(EV, "go"): self.go()}  # type: ignore[dict-item]

    def go(self) -> SomeTasks:
        return None


class Returns(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode, value: Any) -> None:
        super().__init__(factory, parent, "returns")
        self.value = value
        self.task_handlers = {(EV, "go"): self.go}

    def go(self, task: Task, key: TaskId) -> SomeTasks:
        return self.value  # type: ignore[no-any-return]  # a wrong value, on purpose


class BareStringKey(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode, key: Any) -> None:
        super().__init__(factory, parent, "bare_key")
        self.task_handlers = {key: self.on_depth}

    def on_depth(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class TestHandlers(SNRTestCase):
    def test_wrong_signature_found_at_start_up(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(OneArgumentHandler)]))
        for part in (
            "OneArgumentHandler.go",
            HERE,
            "`def go(self, task)`",
            "`def go(self, task: Task, key: TaskId) -> SomeTasks:`",
        ):
            self.assertIn(part, str(ctx.exception))

    def test_handler_called_instead_of_named(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(CalledHandler)]))
        for part in ("CalledHandler", HERE, "instead of naming it"):
            self.assertIn(part, str(ctx.exception))

    def run_returning(self, value: Any) -> str:
        factory = FactoryOf(lambda f, p: Returns(f, p, value))
        node = Node("test", self.get_config([factory, TimeoutLoopFactory(seconds=2)]))
        node.schedule(tasks.event("go", [1]))
        with self.assertRaises(HandlerError) as ctx, self.assertLogs(node.log, "ERROR") as logs:
            node.loop()
        message = str(ctx.exception)
        for part in ("Returns.go", HERE, "(event, 'go')", "a Task, a list of Tasks, or None"):
            self.assertIn(part, message)
        self.assertEqual(len(logs.output), 1, logs.output)  # the log says it once
        self.assertIn("Stopping node 'test': Task handler Returns.go", logs.output[0])
        return message

    def test_wrong_return_value(self) -> None:
        self.assertIn("returned 5 (int)", self.run_returning(5))

    def test_wrong_return_value_hints(self) -> None:
        cases = {
            "not a tuple": (tasks.event("a"), tasks.event("b")),
            "Leave None out": [tasks.event("a"), None],
            "one flat list": [tasks.event("a"), [tasks.event("b")]],
            "tasks.store_page(page)": Page("k", 1, "test", 0.0),
            "Return None when": True,
        }
        for hint, value in cases.items():
            with self.subTest(hint=hint):
                self.assertIn(hint, self.run_returning(value))

    def test_bare_string_key(self) -> None:
        for key, hint in (
            ("depth", "(TaskType.store_page, 'depth')"),
            ("event", "Did you mean TaskType.event?"),
            (("depth", TaskType.store_page), "(TaskType.store_page, 'depth')"),
        ):
            with self.subTest(key=key), self.assertRaises(ComponentError) as ctx:
                Node("test", self.get_config([FactoryOf(partial(BareStringKey, key=key))]))
            for part in ("BareStringKey", HERE, hint):
                self.assertIn(part, str(ctx.exception))


# -- 6. factories whose get() returns the wrong thing ------------------------------
class ReturnsAFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Any:
        return self


class ForgetsToReturn(EndpointFactory):
    def get(self, parent: AbstractNode) -> Any:
        OnlyAHandler(self, parent)


class SometimesNothing(EndpointFactory):
    def __init__(self, enabled: bool) -> None:
        super().__init__()
        self.enabled = enabled

    def get(self, parent: AbstractNode) -> Optional[OnlyAHandler]:
        if self.enabled:
            return OnlyAHandler(self, parent)
        return None


class TestFactoryGet(SNRTestCase):
    def test_returns_something_that_is_not_a_component(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([ReturnsAFactory()]))
        for part in ("ReturnsAFactory", HERE, "not an endpoint or loop", "return MyEndpoint("):
            self.assertIn(part, str(ctx.exception))

    def test_returns_the_class_instead_of_an_object(self) -> None:
        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(lambda factory, parent: OnlyAHandler)]))
        for part in ("FactoryOf.get", HERE, "the class OnlyAHandler itself", "OnlyAHandler(self"):
            self.assertIn(part, str(ctx.exception))

    def test_forgets_to_return(self) -> None:
        capture_test_logs(self)  # and the INFO level a DEBUG node gives "snr.test" goes
        for mode in Mode:
            with self.subTest(mode=mode), self.assertRaises(ComponentError) as ctx:
                Node("test", self.get_config([ForgetsToReturn()], mode))
            for part in ("ForgetsToReturn.get", HERE, "no `return` with a value"):
                self.assertIn(part, str(ctx.exception))

    def test_none_this_time_is_a_warning_not_an_error(self) -> None:
        with self.assertLogs("snr.test", "WARNING") as logs:
            node = Node("test", self.get_config([SometimesNothing(False)]))
        self.assertIn("SometimesNothing.get", logs.output[0])
        self.assertIn("returned None this time", logs.output[0])
        self.assertEqual(list(node.components), ["node_core"])

    def test_none_again_is_not_said_again(self) -> None:
        # A.5's factory returns None every time once its limit is reached.
        with self.assertLogs("snr.test", "WARNING") as logs:
            node = Node("test", self.get_config([SometimesNothing(False)] * 3))
            self.assertIsNone(node.build_component(SometimesNothing(False)))
        self.assertEqual(len(logs.output), 1, logs.output)
        self.assertIn("Said once per factory class", logs.output[0])

    def test_get_that_raises_shows_student_frames(self) -> None:
        def broken(factory: Any, parent: AbstractNode) -> Any:
            settings: Dict[str, Any] = {}
            return settings["missing"]

        with self.assertRaises(ComponentError) as ctx:
            Node("test", self.get_config([FactoryOf(broken)]))
        message = str(ctx.exception)
        for part in ("FactoryOf.get", "KeyError", HERE, "in broken", "node 'test'"):
            self.assertIn(part, message)
        self.assertNotIn("node.py", message)


# -- 7, 8. roles and names ---------------------------------------------------------
class TestRolesAndNames(SNRTestCase):
    components: ComponentsByRole = {
        "urov": [TimeoutLoopFactory(seconds=0.05)],
        "topside": [],
    }

    def run_cli(self, argv: List[str]) -> str:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as ctx:
            CliRunner(self.components, argv).run()
        self.assertNotEqual(ctx.exception.code, 0)
        return err.getvalue()

    def test_unknown_role_on_command_line(self) -> None:
        err = self.run_cli(["main.py", "urv"])
        for part in ("Unknown role 'urv'", "'urov', 'topside'", "Did you mean 'urov'?"):
            self.assertIn(part, err)
        self.assertNotIn("Traceback", err)

    def test_no_role_on_command_line(self) -> None:
        err = self.run_cli(["main.py"])
        for part in ("no role given", "urov, topside", "python main.py urov"):
            self.assertIn(part, err)

    def test_unknown_role_in_synchronous_runner(self) -> None:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as ctx:
            SynchronousRunner("urv", self.components).run()
        self.assertEqual(ctx.exception.code, 1)
        self.assertIn("ConfigError", err.getvalue())
        self.assertIn("Did you mean 'urov'?", err.getvalue())

    def test_empty_role(self) -> None:
        err = self.run_cli(["main.py", "topside"])
        self.assertIn("Role 'topside' has no components", err)
        self.assertIn("Add at least one factory", err)

    def test_factory_class_instead_of_object(self) -> None:
        err = io.StringIO()
        components: Any = {"robot": [TimeoutLoopFactory]}
        with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as ctx:
            CliRunner(components, ["main.py", "robot"]).run()
        self.assertEqual(ctx.exception.code, 1)
        for part in ("ConfigError", "Role 'robot' lists", "add () to make a factory object"):
            self.assertIn(part, err.getvalue())

    def test_same_factory_listed_twice(self) -> None:
        timeout = TimeoutLoopFactory(seconds=1)
        with self.assertRaises(ConfigError) as ctx:
            Node("test", self.get_config([timeout, timeout]))
        for part in ("'timeout_loop'", "TimeoutLoopFactory", "listed twice", "List it once"):
            self.assertIn(part, str(ctx.exception))

    def test_two_components_with_one_name(self) -> None:
        with self.assertRaises(ConfigError) as ctx:
            Node("test", self.get_config([FactoryOf(OnlyAHandler), FactoryOf(OnlyAHandler)]))
        for part in ("'only_a_handler'", "OnlyAHandler", HERE, "unique name"):
            self.assertIn(part, str(ctx.exception))


# -- 9. reading a data key nothing has stored ---------------------------------------
class Reader(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode, key: str) -> None:
        super().__init__(factory, parent, "reader", max_tick_rate_hz=200)
        self.key = key
        self.seen: List[Any] = []

    def setup(self) -> None:
        self.store_data("depth", 1.5)

    def loop(self) -> None:
        self.seen.append(self.get_data(self.key))


class TestMissingDataKey(SNRTestCase):
    def run_reader(
        self,
        key: str,
        typo_s: float,
        missing_s: float,
        handled: Sequence[str] = (),
        hint_expected: bool = False,
    ) -> List[str]:
        """Run a node whose loop reads ``key``; the hints it logged.

        A run that expects a hint ends 0.05 s after one is logged (within 3 s);
        one that expects none ends after 20 reads (0.1 s at 200 Hz, or longer
        on a busy machine), well past ``typo_s``/``missing_s``.
        """
        readers: List[Reader] = []

        def read_enough() -> bool:
            return bool(readers) and len(readers[0].seen) >= 20

        def make_reader(factory: LoopFactory, parent: AbstractNode) -> Reader:
            readers.append(Reader(factory, parent, key))
            return readers[-1]

        node = Node(
            "test",
            self.get_config(
                [
                    LoopFactoryOf(make_reader),
                    TimeoutLoopFactory(seconds=3.0)
                    if hint_expected
                    else StopWhenTrueFactory(read_enough, within_s=3.0),
                    *([KeyWatcherFactory(list(handled))] if handled else []),
                ],
                Mode.DEBUG,
            ),
        )
        assert node.key_hints is not None
        node.key_hints.typo_s, node.key_hints.missing_s = typo_s, missing_s
        # INFO, then the level it had: the "snr.test" logger is shared with other tests
        with captured_logs(node.log.name, logging.INFO) as records:
            if hint_expected:
                # Stop 0.05 s after the hint: about ten more reads, which must not repeat it.
                node.log.addHandler(_OnHint(lambda: threading.Timer(
                    0.05, node.set_terminate_flag, args=("hint seen",)
                ).start()))  # fmt: skip
            node.loop()
        reader = node.components["reader"]
        assert isinstance(reader, Reader)
        self.assertIn(None, reader.seen)  # get_data keeps returning None
        return [r for r in records if "get_data/get_page return None" in r]

    def test_typo_gets_one_hint_with_the_closest_key(self) -> None:
        hints = self.run_reader("depht", typo_s=0.02, missing_s=60, hint_expected=True)
        self.assertEqual(len(hints), 1, hints)  # once, though read ~25 times
        for part in ("'depht'", "Did you mean 'depth'?", "'depth'", HERE, "Reader.loop"):
            self.assertIn(part, hints[0])

    def test_key_never_stored_gets_one_hint_after_a_while(self) -> None:
        hints = self.run_reader("speed", typo_s=0.02, missing_s=0.05, hint_expected=True)
        self.assertEqual(len(hints), 1, hints)
        for part in ("'speed'", "nothing has stored it", "'depth'", "Reader.loop"):
            self.assertIn(part, hints[0])

    def test_no_hint_for_a_key_a_handler_waits_for(self) -> None:
        # The UROV's Telemetry reads 'motor_speed' before the pilot connects;
        # a handler on the node is registered for it, so its pages are planned
        # (and 'depht' being close to the stored 'depth' is no evidence of a typo).
        self.assertEqual(
            self.run_reader("depht", typo_s=0.02, missing_s=0.05, handled=["depht"]), []
        )

    def test_no_hint_before_the_grace_period(self) -> None:
        self.assertEqual(self.run_reader("speed", typo_s=0.02, missing_s=60), [])

    def test_hints_with_a_fake_clock(self) -> None:
        now = [0.0]
        log = logging.getLogger("snr.test.key_hints")
        hints = MissingKeyHints(log, lambda: now[0], typo_s=0.5, missing_s=5.0)
        stored = ["depth", "speed"]
        with self.assertLogs(log, "INFO") as logs:
            for step in range(200):  # 20 s of reads at 10 Hz
                now[0] = step * 0.1
                hints.missed("depht", stored)  # a typo: hinted after 0.5 s
                hints.missed("heading", stored)  # nothing like it: hinted after 5 s
                if now[0] < 1.0:
                    hints.missed("later", stored)  # stored after 1 s: never hinted
            log.info("end")
        self.assertEqual(len(logs.output), 3, logs.output)
        typo, missing, _ = logs.output
        self.assertIn("'depht'", typo)
        self.assertIn("Did you mean 'depth'?", typo)
        self.assertIn("'heading' has been read for 5.0 s", missing)

    def test_no_hint_outside_debug_mode(self) -> None:
        node = Node("test", self.get_config([TimeoutLoopFactory(seconds=1)], Mode.TEST))
        self.assertIsNone(node.key_hints)


class KeyWatcher(Endpoint):
    """Handles pages under each of ``keys`` (a test for the wiring hint)."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode, keys: List[str]) -> None:
        super().__init__(factory, parent, "watcher")
        self.task_handlers = {(TaskType.store_page, key): self.on_page for key in keys}

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class KeyWatcherFactory(EndpointFactory):
    def __init__(self, keys: List[str]) -> None:
        super().__init__()
        self.keys = keys

    def get(self, parent: AbstractNode) -> KeyWatcher:
        return KeyWatcher(self, parent, self.keys)


class TestHandlerForAMisspelledKey(SNRTestCase):
    def test_a_handler_for_a_key_nothing_stores_gets_a_did_you_mean(self) -> None:
        from snr import ListReplayerFactory

        records: List[str] = []
        boxes: List[Node] = []

        def hinted_after_depth_came() -> bool:
            # The node's own check runs 3 s after start, once pages flow: here it
            # runs as soon as the first 'depth' page is stored, then the test ends.
            node = boxes[0]
            if "depth" in node.datastore and not boxes[1:]:
                boxes.append(node)
                node.schedule(tasks.event(tasks.CHECK_WIRING))
            return any("handles pages under" in r for r in records)

        node = Node(
            "test",
            self.get_config(
                [
                    ListReplayerFactory([1, 2, 3], "depth", period_s=0.01),
                    KeyWatcherFactory(["Depth", "depth", "never_sent_sonar"]),
                    StopWhenTrueFactory(hinted_after_depth_came, within_s=3.0),
                ],
                Mode.DEBUG,
            ),
        )
        boxes.append(node)
        assert node.key_hints is not None
        node.key_hints.handlers_s = 60.0  # run by the test instead, above
        with captured_logs(node.log.name) as logged:
            records = logged
            node.loop()
        hints = [r for r in records if "handles pages under" in r]
        self.assertEqual(len(hints), 1, records)  # 'Depth' only: 'depth' is right,
        # and 'never_sent_sonar' has no close match (its pages may come later)
        for part in ("KeyWatcher.on_page", HERE, "'Depth'", "Did you mean 'depth'?"):
            self.assertIn(part, hints[0])

    def test_no_wiring_hint_outside_debug_mode(self) -> None:
        node = Node("test", self.get_config([KeyWatcherFactory(["Depth"])], Mode.TEST))
        self.assertIsNone(node.key_hints)


class _OnHint(logging.Handler):
    """Calls ``on_hint`` when a missing-key hint is logged."""

    def __init__(self, on_hint: Callable[[], None]) -> None:
        super().__init__(logging.INFO)
        self.on_hint = on_hint

    def emit(self, record: logging.LogRecord) -> None:
        if "get_data/get_page return None" in record.getMessage():
            self.on_hint()


# -- 10. changing node state from a loop thread -------------------------------------
class Rogue(ThreadLoop):
    """Tries every unsafe call once from its own thread, recording the errors."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "rogue")
        self.errors: Dict[str, ThreadSafetyError] = {}

    def loop(self) -> None:
        node = self.parent
        assert isinstance(node, Node)
        attempts: Dict[str, Callable[[], Any]] = {
            "execute_task": lambda: node.execute_task(tasks.event("x")),
            "add_component": lambda: node.add_component(OnlyAHandler(FactoryOf(print), node)),
            "write_page": lambda: node.write_page(self.page("x", 1)),
            "remove_component": lambda: node.remove_component("node_core"),
            "handle_task": lambda: node.handle_task(print, tasks.event("x"), EV),
            "terminate": node.terminate,
        }
        for name, attempt in attempts.items():
            try:
                attempt()
            except ThreadSafetyError as error:
                self.errors[name] = error
        self.schedule(tasks.terminate("tried everything"))  # the safe way to stop the node
        self.set_terminate_flag("tried everything")


class TestThreadSafety(SNRTestCase):
    def test_loop_thread_cannot_change_node_state(self) -> None:
        factory = LoopFactoryOf(Rogue)
        node = self.run_test_node([factory])
        rogue = node.components["rogue"]
        assert isinstance(rogue, Rogue)
        fixes = {
            "execute_task": "self.schedule(task)",
            "add_component": "self.schedule(tasks.add_component(factory))",
            "write_page": "self.store_page(page) or self.store_data(key, value)",
            "remove_component": "self.schedule(tasks.remove_component(name))",
            "handle_task": "self.schedule(task)",
            "terminate": "self.schedule(tasks.terminate(reason))",
        }
        self.assertEqual(set(rogue.errors), set(fixes))
        for method, fix in fixes.items():
            with self.subTest(method=method):
                message = str(rogue.errors[method])
                # Before Python 3.11 code objects have no qualified name, so a
                # lambda inside Rogue.loop is only "<lambda>" there.
                where = "Rogue.loop" if sys.version_info >= (3, 11) else "test_errors.py:"
                for part in (fix, HERE, where, "snr-test-rogue", f"{method}()"):
                    self.assertIn(part, message)
        self.assertNotIn("x", node.datastore)
        # Only the terminate task stopped the node: its terminate() call did not.
        self.assertEqual(node.terminate_reason, "tried everything")


# -- 11. a blocking call in a handler -------------------------------------------------
class Sleepy(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sleepy")
        self.task_handlers = {(EV, "nap"): self.nap}

    def nap(self, task: Task, key: TaskId) -> SomeTasks:
        time.sleep(0.02)  # over the test's slow_handler_s of 0.01 s
        return None


class TestBlockingHandler(SNRTestCase):
    def test_slow_handler_is_named_with_its_time(self) -> None:
        capture_test_logs(self)  # and the INFO level a DEBUG node gives "snr.test" goes
        for mode in (Mode.DEBUG, Mode.TEST):
            with self.subTest(mode=mode):
                naps = [tasks.event("nap"), tasks.event("nap")]
                safety = TimeoutLoopFactory(seconds=5)
                node = Node(
                    "test",
                    self.get_config(
                        [FactoryOf(Sleepy), StopWhenDrainedFactory(naps), safety], mode
                    ),
                )
                node.slow_handler_s = 0.01
                with self.assertLogs("snr.test", "WARNING") as logs:
                    node.loop()
                self.assertEqual(node.terminate_reason, "queue drained")
                slow = [line for line in logs.output if "Sleepy.nap" in line]
                self.assertEqual(len(slow), 1)  # once per handler, not per call
                for part in (HERE, "took 0.0", "(event, 'nap')", "ThreadLoop", "time.sleep"):
                    self.assertIn(part, slow[0])

    def test_a_slow_handler_of_snr_s_own_is_not_blamed_on_the_student(self) -> None:
        capture_test_logs(self)
        naps = [tasks.event("nap")]
        node = Node(
            "test",
            self.get_config(
                [FactoryOf(Sleepy), StopWhenDrainedFactory(naps), TimeoutLoopFactory(seconds=5)],
                Mode.DEBUG,
            ),
        )
        node.slow_handler_s = 0.01
        # The same slow function, as if SNR's own module had defined it.
        Sleepy.nap.__module__ = "snr.core.node"
        try:
            with self.assertLogs("snr.test", "DEBUG") as logs:
                node.loop()
        finally:
            Sleepy.nap.__module__ = __name__
        slow = [r for r in logs.records if "Sleepy.nap" in r.getMessage()]
        self.assertEqual([r.levelname for r in slow], ["DEBUG"], logs.output)


# -- 12. ports and serial devices: the real components ---------------------------------
def catalogue_section(number: int) -> str:
    """Section ``number`` of docs/errors.md, as text."""
    text = Path(ROOT, "docs", "errors.md").read_text("utf-8")
    start = text.index(f"\n## {number}. ")
    return text[start : text.index("\n## ", start + 1)]


def shown_messages(section: str, heading: str) -> List[str]:
    """The messages of the first text block under ``heading``, one per paragraph."""
    block = section.split(heading, 1)[1].split("```text\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


class TestOsErrors(unittest.TestCase):
    """docs/errors.md section 12: each message as the real component gives it."""

    def setUp(self) -> None:
        self.section = catalogue_section(12)

    def test_12a_a_port_in_use_prints_what_the_page_shows(self) -> None:
        entry = self.section.split("### 12a.", 1)[1]
        program = entry.split("```python\n", 1)[1].split("```", 1)[0]
        shown = entry.split("```text\n", 1)[1].split("```", 1)[0].splitlines()
        self.assertIn("9000", program)
        with socket.socket() as holder:  # the earlier run that still holds the port
            holder.bind(("127.0.0.1", 0))
            holder.listen()
            port = str(holder.getsockname()[1])
            lines, status = silence.run_program(program.replace("9000", port), [])
        got = {silence.comparable(line.replace(port, "9000")) for line in lines}
        wanted = [c for c in map(silence.comparable, shown[1:-2]) if c is not None]
        self.assertEqual([w for w in wanted if w not in got], [], "\n".join(lines))
        self.assertEqual(status, int(shown[-1]))

    def test_12b_a_refused_console_connection(self) -> None:
        with socket.socket() as probe:  # a port nothing listens on
            probe.bind(("127.0.0.1", 0))
            port = probe.getsockname()[1]
        console = RemoteConsole("127.0.0.1", port, timeout_s=1.0)
        with self.assertRaises(ConsoleConnectionError) as ctx:
            console.connect()
        message = str(ctx.exception).replace(str(port), "9124")
        self.assertEqual(message, shown_messages(self.section, "### 12b.")[0])

    def test_12b_a_missing_serial_port(self) -> None:
        try:
            import serial  # noqa: F401 - only to know pyserial is there
        except ImportError:  # pragma: no cover - pyserial is an extra
            self.skipTest(reason("serial"))
        missing = "/dev/snr-no-such-port"
        with mock.patch.object(serial_port, "available_ports", lambda: ["/dev/ttyACM0"]):
            with self.assertRaises(CommsError) as ctx:
                serial_port.open_serial_port(missing, 115200, 0.1, 0.1, "urov")
        message = str(ctx.exception).replace(missing, "/dev/ttyUSB0")
        self.assertEqual(message, shown_messages(self.section, "### 12b.")[1])

    def test_12b_a_serial_port_not_permitted(self) -> None:
        denied = PermissionError(errno.EACCES, "Permission denied", "/dev/ttyACM0")
        message = str(serial_port.describe_open_error("/dev/ttyACM0", denied, "urov"))
        self.assertEqual(message, shown_messages(self.section, "### 12b.")[2])

    def test_every_place_that_listens_words_a_port_in_use_the_same(self) -> None:
        with socket.socket() as holder:
            holder.bind(("127.0.0.1", 0))
            holder.listen()
            port = holder.getsockname()[1]
            with self.assertRaises(CommsError) as sockets_error:
                sockets_listen(("127.0.0.1", port), "urov")
            with self.assertRaises(CommsError) as view_error:
                live_view_listen("127.0.0.1", port, "urov", "live_view")
        for error, who, setting in (
            (sockets_error, "The sockets server of node 'urov'", "SocketsPair("),
            (view_error, "The live view 'live_view' of node 'urov'", "FoxgloveBridgeFactory("),
        ):
            message = str(error.exception)
            self.assertTrue(message.startswith(f"{who} cannot listen on 127.0.0.1:{port}"))
            for part in (f"port {port} is in use", f"lsof -i :{port}", setting):
                self.assertIn(part, message)
            self.assertIsInstance(error.exception.__cause__, OSError)

    def test_the_rarer_failures(self) -> None:
        cases: List[Tuple[OSError, OsAction, str, str]] = [
            (PermissionError(errno.EACCES, "Permission denied"), "listen", "0.0.0.0:80", "1024"),
            (
                socket.gaierror(socket.EAI_NONAME, "Name or service not known"),
                "connect",
                "robto.local:9000",
                "'robto.local' cannot be found",
            ),
            (OSError(errno.EADDRNOTAVAIL, "x"), "listen", "10.9.9.9:9000", "not an address"),
            (OSError(errno.EHOSTUNREACH, "x"), "connect", "10.9.9.9:9000", "did not answer"),
            (OSError(errno.ECONNRESET, "x"), "connect", "10.9.9.9:9000", "closed the connection"),
            (OSError(errno.EBUSY, "x"), "open", "/dev/ttyUSB0", "another program has it open"),
        ]
        for error, action, target, part in cases:
            with self.subTest(part=part):
                message = explain_os_error(error, action=action, target=target, who="It")
                self.assertIn(part, message)


# -- 13. data that cannot be sent between nodes -----------------------------------------
class TestNotSerializableAsPrinted(unittest.TestCase):
    """docs/errors.md section 13a, run as printed against a real topside node."""

    def test_13a_a_set_inside_a_list_prints_what_the_page_shows(self) -> None:
        entry = catalogue_section(13).split("### 13a.", 1)[1]
        program = entry.split("```python\n", 1)[1].split("```", 1)[0]
        shown = entry.split("```text\n", 1)[1].split("```", 1)[0].splitlines()
        port = str(free_port())
        topside = Node(
            "topside",
            Config(  # a stand-in for the student's topside: it lets any system in
                {"topside": [SocketsPair(("127.0.0.1", int(port)), system=None).server()]}
            ),
        )
        with captured_logs("snr.topside"):
            serving = threading.Thread(target=topside.loop, daemon=True)
            serving.start()
            try:
                wanted = [c for c in map(silence.comparable, shown[1:-2]) if c is not None]
                expected = [line.replace("9000", port) for line in wanted]
                lines, status = silence.run_program(program.replace("9000", port), expected)
            finally:
                topside.set_terminate_flag("test over")
                serving.join(5.0)
        got = {silence.comparable(line.replace(port, "9000")) for line in lines}
        self.assertEqual([w for w in wanted if w not in got], [], "\n".join(lines))
        self.assertEqual(status, int(shown[-1]))

    def test_every_way_out_words_it_the_same(self) -> None:
        data = {"pose": [1.0, 2.0, {3}]}
        page = Page("pose", data, "robot", 0.0)
        shown = catalogue_section(13).split("ERROR: ", 1)[1].split(" The page was dropped")[0]
        with self.assertRaises(NotSerializableError) as by_serialize:
            page.serialize()
        with self.assertRaises(NotSerializableError) as by_line:
            page_to_line(page)
        with self.assertRaises(NotSerializableError) as by_compact:
            compact_line(page)
        self.assertEqual(str(by_serialize.exception), shown)
        to_a_file = shown.replace("to another node", "to a recording or serial link")
        self.assertEqual(str(by_line.exception), to_a_file)
        self.assertEqual(str(by_compact.exception), shown.replace("another node", "a serial link"))

    def test_serialize_no_longer_turns_a_set_into_a_list(self) -> None:
        for data in ({3}, math.nan, {"x": [math.inf]}, {(1, 2): "a"}):
            with self.subTest(data=data), self.assertRaises(NotSerializableError):
                Page("k", data, "robot", 0.0).serialize()
        page = Page("k", {"x": [1, 2.5, None, True, "t"], "n": (1, 2)}, "robot", 0.0)
        self.assertEqual(Page.deserialize(page.serialize()).data["x"], [1, 2.5, None, True, "t"])


class TestNotSerializable(unittest.TestCase):
    def test_path_to_the_bad_part(self) -> None:
        with self.assertRaises(NotSerializableError) as ctx:
            page_json(Page("pose", {"pose": [1.0, 2.0, {3}]}, "urov", 0.0))
        self.assertIn("data['pose'][2] is a set ({3})", str(ctx.exception))
        page_json(Page("pose", {"pose": (1.0, 2.0), "ok": [None, True, "x"]}, "urov", 0.0))

    def test_message_names_key_path_type_and_fix(self) -> None:
        message = str(not_serializable_error("pose", {"pose": [1.0, 2.0, {3}]}))
        for part in ("'pose'", "data['pose'][2] is a set", "list(value)"):
            self.assertIn(part, message)

    def test_other_kinds(self) -> None:
        class Pose:
            pass

        loop: List[Any] = []
        loop.append(loop)
        for data, part in (
            ({(1, 2): "a"}, "has a key that is a tuple"),
            ({"raw": b"\x00"}, "value.hex()"),
            ({"mode": Mode.DEBUG}, "value.name or value.value"),
            ({"pose": Pose()}, "data['pose'] is a Pose"),
            (loop, "contains itself"),
        ):
            with self.subTest(part=part), self.assertRaises(NotSerializableError) as ctx:
                page_json(Page("k", data, "urov", 0.0))
            self.assertIn(part, str(ctx.exception))

    def test_page_serialize_names_the_path(self) -> None:
        class Pose:
            pass

        page = Page("pose", {"history": [1, Pose()]}, "urov", 0.0)
        with self.assertRaises(NotSerializableError) as ctx:
            page.serialize()
        self.assertIn("data['history'][1] is a Pose", str(ctx.exception))


# -- 14. an exception inside a handler ---------------------------------------------------
class Crasher(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "crasher")
        self.task_handlers = {(TaskType.store_page, "depth"): self.on_depth}

    def on_depth(self, task: Task, key: TaskId) -> SomeTasks:
        return self.store_data_task("speed", 1 / task.val_list[0].data)


class CrashingLoop(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "crashing_loop")

    def loop(self) -> None:
        raise RuntimeError("High velocity impact")


class TestHandlerExceptions(SNRTestCase):
    def test_message_shows_student_frames_and_task(self) -> None:
        node = Node("test", self.get_config([FactoryOf(Crasher), TimeoutLoopFactory(seconds=2)]))
        node.schedule(tasks.store_data("depth", 0))
        with self.assertRaises(HandlerError) as ctx, self.assertLogs(node.log, "ERROR") as logs:
            node.loop()
        self.assertIn("Stopping node 'test': Task handler Crasher.on_depth", logs.output[0])
        message = str(ctx.exception)
        for part in (
            "Crasher.on_depth",
            "endpoint 'crasher'",
            "ZeroDivisionError: division by zero",
            "(store_page, 'depth') carrying the page 'depth' with data 0",
            HERE,
            "1 / task.val_list[0].data",
            "Fix the handler",
        ):
            self.assertIn(part, message)
        self.assertNotIn("node.py", message)
        # The chained original error's traceback starts in the student's code too.
        cause = ctx.exception.__cause__
        assert cause is not None and cause.__traceback__ is not None
        self.assertTrue(cause.__traceback__.tb_frame.f_code.co_filename.endswith(HERE))

    def test_unsafe_call_stops_the_loop_with_the_fix(self) -> None:
        class Clock(ThreadLoop):
            def loop(self) -> None:
                self.parent.execute_task(tasks.event("tick"))

        factory = LoopFactoryOf(lambda f, p: Clock(f, p, "clock"))
        node = Node("test", self.get_config([factory, TimeoutLoopFactory(seconds=2)]))
        with self.assertRaises(LoopError) as ctx, self.assertLogs(node.log, "ERROR") as logs:
            node.loop()
        self.assertIn("Stopping node 'test': Loop 'clock'", logs.output[0])
        message = str(ctx.exception)
        for part in ("'clock'", "ThreadSafetyError", "self.schedule(task)", "Clock.loop", HERE):
            self.assertIn(part, message)
        self.assertNotIn("node.py", message)
        self.assertNotIn("catch the error", message)  # the fix is the schedule call

    def test_loop_exception(self) -> None:
        node = Node("test", self.get_config([LoopFactoryOf(CrashingLoop)]))
        with self.assertRaises(LoopError) as ctx, self.assertLogs(node.log, "ERROR") as logs:
            node.loop()
        self.assertIn("Stopping node 'test': Loop 'crashing_loop'", logs.output[0])
        message = str(ctx.exception)
        for part in ("'crashing_loop'", "CrashingLoop", HERE, "High velocity impact", "Fix loop()"):
            self.assertIn(part, message)
        self.assertNotIn("loop.py", message)

    def test_runner_prints_no_framework_traceback(self) -> None:
        script = textwrap.dedent(
            """
            from snr import *

            class Crasher(Endpoint):
                def __init__(self, factory, parent):
                    super().__init__(factory, parent, "crasher")
                    self.task_handlers = {(TaskType.event, "go"): self.go}

                def begin(self):
                    self.schedule(tasks.event("go", [0]))

                def go(self, task, key):
                    return 1 / task.val_list[0]

            class CrasherFactory(EndpointFactory):
                def get(self, parent):
                    return Crasher(self, parent)

            CliRunner({"robot": [CrasherFactory(), TimeoutLoopFactory(seconds=5)]}).run()
            """
        )
        main = self.temp_file("_main.py", script)
        env = dict(os.environ, PYTHONPATH=ROOT)
        proc = subprocess.run(
            [sys.executable, main, "robot"],
            capture_output=True,
            text=True,
            env=env,
            timeout=30,
        )
        self.assertEqual(proc.returncode, 1)
        self.assertNotIn("Traceback", proc.stderr)
        self.assertNotIn("snr/core", proc.stderr)
        for part in (
            "HandlerError in node 'robot'",
            "Crasher.go",
            "(event, 'go') with values [0]",
            '_main.py", line 13, in go',
            "return 1 / task.val_list[0]",
        ):
            self.assertIn(part, proc.stderr)


if __name__ == "__main__":
    unittest.main()
