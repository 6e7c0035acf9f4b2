"""`LocalConsole`: the console commands typed on the node's own stdin."""

from __future__ import annotations

import io
import os
import threading
import unittest

from snr import Config, LocalConsoleFactory, Mode, Node, SNRTestCase, ThreadLoop
from snr.core import LoopState, NodeState
from tests.helpers import wait_until


class TestLocalConsole(SNRTestCase):
    def test_commands_from_a_stream_until_exit(self) -> None:
        typed = io.StringIO("help\nlist endpoints\n\nfrobnicate\nexit\nhelp\n")
        out = io.StringIO()
        node = self.run_test_node([LocalConsoleFactory(typed, out)], timeout_s=5)
        text = out.getvalue()
        self.assertIn("Console for node 'test'", text)
        self.assertIn("Commands (type `help <command>` for details)", text)
        self.assertIn("local_console_commands", text)
        self.assertIn("Unknown command 'frobnicate'", text)
        self.assertIn("Stopping node 'test'. Bye.", text)
        self.assertEqual(text.count("Commands (type"), 1)  # nothing ran after exit
        self.assertEqual(node.terminate_reason, "exit command from local console")

    def test_end_of_input_stops_the_console_not_the_node(self) -> None:
        typed = io.StringIO("task store_page k 1")  # no newline, then end of input
        # The node must still be running when its time limit stops it.
        node = self.run_test_node(
            [LocalConsoleFactory(typed, io.StringIO())], timeout_s=0.1, expect_timeout=True
        )
        self.assertEqual(node.get_data("k"), 1)
        console = node.components["local_console"]
        assert isinstance(console, ThreadLoop)
        self.assertIs(console.state, LoopState.STOPPED)

    def test_a_real_pipe_as_stdin(self) -> None:
        read_fd, write_fd = os.pipe()
        with open(read_fd, encoding="utf-8") as stdin, open(write_fd, "w") as keyboard:
            out = io.StringIO()
            node = Node("robot", Config({"robot": [LocalConsoleFactory(stdin, out)]}, Mode.TEST))
            thread = threading.Thread(target=node.loop, daemon=True)
            thread.start()
            keyboard.write("task event ")  # half a line: nothing runs yet
            keyboard.flush()
            keyboard.write("go\nlist endpoints\n")
            keyboard.flush()
            self.assertTrue(wait_until(lambda: "local_console_commands" in out.getvalue()))
            self.assertIn("Scheduled (event, 'go'): []", out.getvalue())
            keyboard.write("exit\n")
            keyboard.flush()
            thread.join(5)
        self.assertFalse(thread.is_alive())
        self.assertIs(node.state, NodeState.TERMINATED)

    def test_a_closed_terminal_does_not_stop_the_node(self) -> None:
        out = io.StringIO()
        out.close()  # writing raises ValueError: the console must swallow it
        # The node must still be running when its time limit stops it.
        self.run_test_node(
            [LocalConsoleFactory(io.StringIO("help\n"), out)], timeout_s=0.1, expect_timeout=True
        )


if __name__ == "__main__":
    unittest.main()
