"""The console over Zenoh: a node found by system and role answers the console's commands.

On 127.0.0.1 with multicast scouting off, explicit endpoints and a port chosen
at run time. Skipped when the Zenoh extra is not installed.
"""

from __future__ import annotations

import io
import unittest

from snr import Config, Mode, TimeoutLoopFactory
from tests.helpers import free_port
from tests.optional import needs
from tests.quiet import capture_test_logs
from tests.test_comms_local import LocalNodes

SYSTEM = "lab"


@needs("zenoh")
class TestZenohConsole(unittest.TestCase):
    """One node with a Zenoh console on a thread; consoles reach it by its role."""

    def setUp(self) -> None:
        from snr.std_mods.io.zenoh_console import ZenohConsoleFactory

        capture_test_logs(self, "snr")
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        factories = [
            ZenohConsoleFactory(SYSTEM, listen=[self.endpoint], scouting=False, token="sesame"),
            TimeoutLoopFactory(seconds=15),
        ]
        self.nodes = LocalNodes(Config({"urov": factories}, mode=Mode.TEST), ["urov"])
        self.addCleanup(self.nodes.stop)

    def console(self, role: str = "urov", token: str = "sesame", system: str = SYSTEM) -> object:
        from snr.std_mods.io.zenoh_console import ZenohConsole

        console = ZenohConsole(
            system, role, connect=[self.endpoint], scouting=False, token=token, timeout_s=5.0
        )
        self.addCleanup(console.close)
        return console

    def test_commands_by_role_with_the_token_and_refusals_without(self) -> None:
        from snr.std_mods.io.console_protocol import ConsoleConnectionError, Status
        from snr.std_mods.io.zenoh_console import ZenohConsole

        console = self.console()
        assert isinstance(console, ZenohConsole)
        self.assertIs(console.connect().status, Status.HELLO)
        self.assertEqual(console.roles(), ["urov"])
        listing = console.send("list endpoints")
        self.assertIs(listing.status, Status.OK)
        self.assertIn("zenoh_console", listing.text)
        self.assertIs(console.send("relaod all").status, Status.ERROR)

        wrong = self.console(token="guess")
        assert isinstance(wrong, ZenohConsole)
        with self.assertRaisesRegex(ConsoleConnectionError, "token"):
            wrong.connect()
        nobody = self.console(role="camera")
        assert isinstance(nobody, ZenohConsole)
        nobody.timeout_s = 0.2
        with self.assertRaisesRegex(ConsoleConnectionError, "No node 'camera'"):
            nobody.connect()

    def test_the_command_line_lists_roles_runs_commands_and_exit_stops_the_node(self) -> None:
        import snr.console

        where = ["--connect", self.endpoint, "--no-scouting", "--token", "sesame"]
        out, err = io.StringIO(), io.StringIO()
        self.assertEqual(snr.console.main(["--zenoh", SYSTEM, *where], stdout=out, stderr=err), 0)
        self.assertIn("urov", out.getvalue())
        out = io.StringIO()
        code = snr.console.main(
            ["--zenoh", SYSTEM, "urov", *where, "-c", "help", "-c", "exit"], stdout=out, stderr=err
        )
        self.assertEqual(code, 0, err.getvalue())
        self.assertIn("dump", out.getvalue())
        node = self.nodes.wait_first(8.0)
        self.assertTrue(node.is_terminated(), "`exit` over Zenoh stops the node")


if __name__ == "__main__":
    unittest.main()
