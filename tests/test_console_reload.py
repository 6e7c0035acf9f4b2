"""Edit a component's file on disk, type `reload <name>`, see the new code run.

The component's factory counts the pings it has seen; that state must
survive the reload, while the behaviour (the word it answers with) changes.
A reload of a broken edit keeps the old code running, and the reply says why.
"""

from __future__ import annotations

import importlib
import os
import shutil
import sys
import tempfile
import unittest
from typing import Any

from snr.core import NodeState
from snr.std_mods.io import RemoteConsole
from snr.std_mods.io.console_protocol import Status
from tests.console_helpers import NodeInThread
from tests.helpers import wait_until

MODULE = "snr_console_reload_target"

SOURCE = """
import sys

from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType


class Pinger(Endpoint):
    def __init__(self, factory: "PingerFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pinger")
        self.task_handlers = {(TaskType.event, "ping"): self.on_ping}

    def on_ping(self, task: Task, key: TaskId) -> SomeTasks:
        self.factory.pings += 1
        return self.store_data_task("pong", ["WORD", self.factory.pings])


class PingerFactory(EndpointFactory):
    def __init__(self) -> None:
        super().__init__(sys.modules[__name__])
        self.pings = 0

    def get(self, parent: AbstractNode) -> Pinger:
        return Pinger(self, parent)
"""


class TestReloadFromConsole(unittest.TestCase):
    def setUp(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-console-reload-")
        self.addCleanup(shutil.rmtree, self.folder, True)
        self.path = os.path.join(self.folder, f"{MODULE}.py")
        self.edits = 0
        self.write(SOURCE.replace("WORD", "v1"))
        sys.path.insert(0, self.folder)
        self.addCleanup(sys.path.remove, self.folder)
        self.addCleanup(sys.modules.pop, MODULE, None)
        self.module: Any = importlib.import_module(MODULE)

    def write(self, text: str) -> None:
        with open(self.path, "w", encoding="utf-8") as f:
            f.write(text)
        # The edit must be seen even within the same second as the last one:
        # move the file's time forward and drop any cached bytecode.
        self.edits += 1
        stamp = os.stat(self.path).st_mtime + 10 * self.edits
        os.utime(self.path, (stamp, stamp))
        shutil.rmtree(os.path.join(self.folder, "__pycache__"), ignore_errors=True)
        importlib.invalidate_caches()

    def ping(self, run: NodeInThread, console: RemoteConsole, expected: Any) -> None:
        reply = console.send("task event ping")
        self.assertEqual(reply.status, Status.OK, reply.text)
        got = wait_until(lambda: run.node.get_data("pong") == expected and expected)
        self.assertEqual(run.node.get_data("pong"), expected)
        self.assertTrue(got)

    def test_edit_reload_and_keep_state(self) -> None:
        factory = self.module.PingerFactory()
        with NodeInThread([factory]) as run, run.console() as console:
            self.ping(run, console, ["v1", 1])
            self.ping(run, console, ["v1", 2])
            old_endpoint = run.node.components["pinger"]

            self.write(SOURCE.replace("WORD", "v2"))
            reply = console.send("reload pinger")
            self.assertEqual(reply.status, Status.OK, reply.text)
            self.assertIn("Reloaded 'pinger'", reply.text)

            self.ping(run, console, ["v2", 3])  # new code, same factory, count kept
            self.assertIsNot(run.node.components["pinger"], old_endpoint)
            self.assertIs(run.node.components["pinger"].factory, factory)
            self.assertIn(f"reloads: {MODULE}", console.send("list endpoints").text)

            # A broken edit: the reply says why, and v2 keeps running.
            self.write(SOURCE.replace("WORD", "v3") + "\ndef broken(:\n")
            with self.assertLogs("snr.robot", "ERROR") as logs:
                reply = console.send("reload pinger")
            self.assertEqual(reply.status, Status.ERROR)
            self.assertIn("old version keeps running", reply.text)
            self.assertIn("SyntaxError", reply.text)
            self.assertIn("SyntaxError", logs.output[0])  # the node's log says it too
            self.ping(run, console, ["v2", 4])

            # Fixed again, through `reload all`.
            self.write(SOURCE.replace("WORD", "v4"))
            reply = console.send("reload all")
            self.assertEqual(reply.status, Status.OK, reply.text)
            self.assertIn("Reloaded 'pinger'", reply.text)
            self.ping(run, console, ["v4", 5])
            self.assertIs(run.node.state, NodeState.RUNNING)
        self.assertEqual(factory.pings, 5)

    def test_code_that_raises_on_import_keeps_the_old_version(self) -> None:
        factory = self.module.PingerFactory()
        with NodeInThread([factory]) as run, run.console() as console:
            self.write(SOURCE + "\nraise RuntimeError('motor driver missing')\n")
            with self.assertLogs("snr.robot", "ERROR") as logs:
                reply = console.send("reload pinger")
            self.assertEqual(reply.status, Status.ERROR)
            self.assertIn("RuntimeError: motor driver missing", reply.text)
            self.assertIn("RuntimeError: motor driver missing", logs.output[0])
            self.ping(run, console, ["v1", 1])


if __name__ == "__main__":
    unittest.main()
