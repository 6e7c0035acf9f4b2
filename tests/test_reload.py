"""Hot reload: new code, same factory, state kept; a broken edit keeps the old code."""

import importlib
import os
import sys
import tempfile
import textwrap
import unittest
from typing import Any, List

from snr import SNRTestCase, TaskType, TimeoutLoopFactory, tasks
from tests.helpers import StopWhenDrainedFactory, StopWhenFactory

MODULE = "snr_reload_target_mod"

SOURCE = """
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
import sys

class Greeter(Endpoint):
    def __init__(self, factory: "GreeterFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "greeter")
        self.task_handlers = {{(TaskType.event, "greet"): self.greet}}

    def greet(self, task: Task, key: TaskId) -> SomeTasks:
        self.factory.calls += 1
        self.factory.said.append("{word}")
        return None

class GreeterFactory(EndpointFactory):
    def __init__(self) -> None:
        super().__init__(sys.modules[__name__])
        self.calls = 0
        self.said: list = []

    def get(self, parent: AbstractNode) -> Greeter:
        return Greeter(self, parent)
"""


class TestHotReload(SNRTestCase):
    def setUp(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-reload-")
        sys.path.insert(0, self.folder)
        self.path = os.path.join(self.folder, f"{MODULE}.py")
        self.write("hello")
        importlib.invalidate_caches()
        self.module: Any = importlib.import_module(MODULE)

    def tearDown(self) -> None:
        sys.path.remove(self.folder)
        sys.modules.pop(MODULE, None)

    def write(self, word: str, broken: bool = False) -> None:
        text = SOURCE.format(word=word)
        if broken:
            text += "\ndef oops(:\n"
        with open(self.path, "w") as f:
            f.write(textwrap.dedent(text))
        # Make sure the new source is seen even within the same second.
        stamp = os.stat(self.path).st_mtime + (2 if broken or word != "hello" else 0)
        os.utime(self.path, (stamp, stamp))
        importlib.invalidate_caches()

    def run_script(self, steps: List[Any]) -> Any:
        factory = self.module.GreeterFactory()
        node_box: List[Any] = []

        class Script:
            """Runs each step between greetings, on the node's thread."""

        from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId

        class Driver(Endpoint):
            def __init__(self, f: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(f, parent, "driver")
                self.step = 0
                self.task_handlers = {(TaskType.event, "next"): self.next_step}

            def begin(self) -> None:
                self.schedule(tasks.event("next"))

            def next_step(self, task: Task, key: TaskId) -> SomeTasks:
                if self.step >= len(steps):
                    return tasks.terminate("script done")
                action = steps[self.step]
                self.step += 1
                return [*action(self.parent), tasks.event("next")]

        class DriverFactory(EndpointFactory):
            def get(self, parent: AbstractNode) -> Driver:
                node_box.append(parent)
                return Driver(self, parent)

        self.run_test_node([factory, DriverFactory(), TimeoutLoopFactory(seconds=3)])
        return factory, node_box[0]

    def test_reload_runs_new_code_and_keeps_factory_state(self) -> None:
        def edit(node: Any) -> List[Any]:
            self.write("bonjour")
            return [tasks.reload_component("greeter")]

        greet = lambda node: [tasks.event("greet")]  # noqa: E731
        factory, node = self.run_script([greet, greet, edit, greet])
        self.assertEqual(factory.said, ["hello", "hello", "bonjour"])
        self.assertEqual(factory.calls, 3)  # state on the factory survived
        self.assertEqual(list(node.components), ["node_core", "greeter", "driver", "timeout_loop"])

    def test_reload_with_syntax_error_keeps_old_component(self) -> None:
        def break_it(node: Any) -> List[Any]:
            self.write("broken", broken=True)
            return [tasks.reload_component("all")]

        greet = lambda node: [tasks.event("greet")]  # noqa: E731
        with self.assertLogs("snr.test", "ERROR") as logs:
            factory, _ = self.run_script([greet, break_it, greet])
        self.assertEqual(factory.said, ["hello", "hello"])
        self.assertIn("old version keeps running", "\n".join(logs.output))
        self.assertIn("SyntaxError", "\n".join(logs.output))
        line = len(textwrap.dedent(SOURCE.format(word="broken")).splitlines()) + 2
        self.assertIn(f"{MODULE}.py:{line}: SyntaxError", "\n".join(logs.output))  # file:line

    def test_reload_unknown_name_lists_components(self) -> None:
        with self.assertLogs("snr.test", "ERROR") as logs:
            self.run_script([lambda node: [tasks.reload_component("greetr")]])
        self.assertIn("greeter", logs.output[0])


class TestAddRemove(SNRTestCase):
    def test_add_and_remove_component_tasks(self) -> None:
        from snr.utils import DummyEndpointFactory

        dummy = DummyEndpointFactory("extra", [(TaskType.event, "poke")])
        node = self.run_test_node([TimeoutLoopFactory(seconds=0.01)])
        self.assertNotIn("extra", node.components)

        from snr import Config, Mode, Node

        node = Node("t", Config({"t": [StopWhenDrainedFactory()]}, mode=Mode.TEST))
        node.schedule(
            [
                tasks.add_component(dummy),
                tasks.event("poke"),
                tasks.remove_component("extra"),
                tasks.event("poke"),
            ]
        )
        node.loop()
        self.assertEqual(dummy.built[0].calls, 1)
        self.assertNotIn("extra", node.components)

    def test_node_core_cannot_be_removed_or_reloaded(self) -> None:
        from snr import Config, Mode, Node

        stored = StopWhenFactory((TaskType.store_page, "depth_m"))
        node = Node("t", Config({"t": [stored]}, mode=Mode.TEST))
        node.schedule(
            [
                tasks.remove_component("node_core"),
                tasks.reload_component("node_core"),
                tasks.reload_component("all"),  # skips the core, refuses nothing
                tasks.store_data("depth_m", 3.5),
            ]
        )
        with self.assertLogs("snr.t", "ERROR") as logs:
            node.loop()
        text = "\n".join(logs.output)
        self.assertEqual(len(logs.output), 2, text)
        self.assertIn("Refused to remove 'node_core'", text)
        self.assertIn("stores every page", text)
        self.assertIn("Refused to reload 'node_core'", text)
        self.assertIn("node_core", node.components)
        self.assertEqual(node.get_data("depth_m"), 3.5)  # pages are still stored
        self.assertEqual(node.terminate_reason, "test work done")  # and terminate still stops it


if __name__ == "__main__":
    unittest.main()
