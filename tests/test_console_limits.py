"""A console that cannot be locked, flooded or guessed.

Each test plays one misbehaving console (or many) against a node and checks
that the operator still gets in, the node keeps working, and nothing grows
without bound. Figures worth knowing are printed (run pytest with ``-s``).
"""

from __future__ import annotations

import logging
import unittest

from snr import TimeoutLoopFactory
from snr.std_mods.io.console_commands import REPLY_BUDGET_CHARS
from snr.std_mods.io.console_protocol import Status
from tests.console_helpers import NodeInThread, wait_for


class TestProtectedComponents(unittest.TestCase):
    def test_remove_node_core_is_refused_and_pages_are_still_stored(self) -> None:
        with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run, run.console() as console:
            with self.assertLogs("snr.robot", logging.WARNING) as logs:
                reply = console.send("task event remove_component node_core")
            self.assertEqual(reply.status, Status.ERROR)
            self.assertIn("Refused: 'node_core' is the node's own core", reply.text)
            self.assertIn("Refused: 'node_core'", "\n".join(logs.output))
            for line in (
                "task event remove_component command_receiver",
                "task event remove_component timeout_loop command_receiver_commands",
                "reload node_core",
                "task reload node_core",
            ):
                reply = console.send(line)
                self.assertEqual(reply.status, Status.ERROR, line)
                self.assertIn("Refused", reply.text, line)
            self.assertIn("node_core", run.node.components)
            self.assertIn("timeout_loop", run.node.components)  # nothing was half-done
            self.assertEqual(console.send("task store_page depth_m 2.5").status, Status.OK)
            self.assertEqual(wait_for(lambda: run.node.get_data("depth_m")), 2.5)
            self.assertEqual(console.send("exit").status, Status.BYE)
            run.wait_stopped()  # `exit` still stops the node


class TestDumpDatastore(unittest.TestCase):
    def test_a_big_datastore_is_cut_with_a_note_and_keys_can_be_asked_for(self) -> None:
        with NodeInThread([]) as run, run.console() as console:
            for i in range(3000):
                run.node.store_data(f"key_{i:04d}", "x" * 200)
            run.node.store_data("big", list(range(100_000)))
            self.assertTrue(wait_for(lambda: run.node.get_data("big") is not None))
            text = console.send("dump datastore").text
            self.assertLessEqual(len(text), REPLY_BUDGET_CHARS)
            note = text.splitlines()[-1]
            self.assertIn("more keys not shown, from 'key_", note)
            self.assertIn("`dump datastore KEY`", note)
            self.assertRegex(text[:300], r"big +=( \[0, 1, 2,)")  # a cheap preview of big data

            one = console.send("dump datastore key_2999").text
            self.assertTrue(one.startswith("key_2999 (from 'robot',"), one[:100])
            self.assertTrue(one.endswith("x" * 200 + "'"), one[-100:])
            some = console.send("dump datastore key_299*").text
            self.assertIn("(10 keys starting with 'key_299')", some)
            cut = console.send("dump datastore big").text
            self.assertLessEqual(len(cut), REPLY_BUDGET_CHARS + 200)
            self.assertIn("node.get_data('big')", cut[-300:])
            missing = console.send("dump datastore bgi")
            self.assertEqual(missing.status, Status.ERROR)
            self.assertIn("Did you mean 'big'?", missing.text)
            usage = console.send("dump profiler big")
            self.assertIn("Usage: dump profiler|datastore [KEY|PREFIX*]", usage.text)


if __name__ == "__main__":
    unittest.main()
