"""The console over Zenoh: a node found by system and role answers the console's commands.

On 127.0.0.1 with multicast scouting off, explicit endpoints and a port chosen
at run time. Skipped when the Zenoh extra is not installed.
"""

from __future__ import annotations

import io
import threading
import time
import unittest
from typing import List, Optional

from snr import Config, Mode, SomeTasks, Task, TaskId, TaskType, TimeoutLoopFactory
from tests.helpers import RecorderFactory, free_port, wait_until
from tests.optional import needs
from tests.quiet import capture_test_logs
from tests.test_comms_local import LocalNodes

SYSTEM = "lab"


@needs("zenoh")
class TestZenohConsole(unittest.TestCase):
    """One node with a Zenoh console on a thread; consoles reach it by its role."""

    def setUp(self) -> None:
        from snr.extras.zenoh.console import ZenohConsoleFactory

        capture_test_logs(self, "snr")
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        factories = [
            ZenohConsoleFactory(SYSTEM, listen=[self.endpoint], scouting=False, token="sesame"),
            TimeoutLoopFactory(seconds=15),
        ]
        self.nodes = LocalNodes(Config({"urov": factories}, mode=Mode.TEST), ["urov"])
        self.addCleanup(self.nodes.stop)

    def console(self, role: str = "urov", token: str = "sesame", system: str = SYSTEM) -> object:
        from snr.extras.zenoh.console import ZenohConsole

        console = ZenohConsole(
            system, role, connect=[self.endpoint], scouting=False, token=token, timeout_s=5.0
        )
        self.addCleanup(console.close)
        return console

    def test_commands_by_role_with_the_token_and_refusals_without(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import ConsoleConnectionError, Status

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

    def test_every_node_refusing_turns_a_console_to_every_node_away(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import ConsoleConnectionError

        every = self.console(role="*", token="guess")
        assert isinstance(every, ZenohConsole)
        with self.assertRaisesRegex(
            ConsoleConnectionError, r"Every node lab/\* .*\[urov\] refused"
        ):
            every.connect()
        self.assertFalse(every.is_connected())

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


@needs("zenoh")
class TestZenohConsoleLateReply(unittest.TestCase):
    """A late reply (``hz``) over Zenoh: the query lasts as much longer as ``hz`` declares.

    The event ``block`` keeps the node's thread in a handler until the test
    ends (at most 10 s): a node that is there but silent.
    """

    def setUp(self) -> None:
        import snr.extras.console_tools.watches  # noqa: F401  (the node's `hz`)
        from snr.extras.zenoh.console import ZenohConsole, ZenohConsoleFactory

        capture_test_logs(self, "snr")
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        self.release = threading.Event()
        blocker = RecorderFactory("blocker", [(TaskType.event, "block")], [], self.block)
        factories = [
            ZenohConsoleFactory(SYSTEM, listen=[endpoint], scouting=False),
            blocker,
            TimeoutLoopFactory(seconds=15),
        ]
        self.nodes = LocalNodes(Config({"urov": factories}, mode=Mode.TEST), ["urov"])
        self.addCleanup(self.nodes.stop)
        self.addCleanup(self.release.set)  # (cleanups run last first: before the stop)
        self.console = ZenohConsole(
            SYSTEM, "urov", connect=[endpoint], scouting=False, timeout_s=1.0
        )
        self.addCleanup(self.console.close)
        self.console.connect()

    def block(self, task: Task, key: TaskId) -> SomeTasks:
        self.release.wait(10.0)
        return None

    def test_hz_with_a_window_longer_than_the_timeout_gets_its_reply(self) -> None:
        from snr.std_mods.io.console_protocol import Status

        started = time.monotonic()
        reply = self.console.send("hz depth 1.5")
        self.assertIs(reply.status, Status.OK, reply.text)
        self.assertIn("depth: no page in 1.5 s.", reply.text)
        self.assertGreater(time.monotonic() - started, 1.4)
        self.assertIs(self.console.send("list endpoints").status, Status.OK, "and the next one")

    def test_a_silent_node_is_given_up_after_the_timeout(self) -> None:
        from snr.std_mods.io.console_protocol import ConsoleConnectionError, Status

        self.assertIs(self.console.send("task event block").status, Status.OK)
        started = time.monotonic()
        with self.assertRaisesRegex(ConsoleConnectionError, "No node 'urov' .* within 1 s"):
            self.console.send("stats")
        self.assertLess(time.monotonic() - started, 3.0, "the console's timeout, not the query's")


@needs("zenoh")
class TestZenohConsoleEveryNode(unittest.TestCase):
    """Two nodes; a console whose role is "*" reaches both, but only to read.

    The event ``block`` keeps urov's thread in a handler until the test ends
    (at most 10 s), as a slow handler would.
    """

    def setUp(self) -> None:
        from snr.extras.zenoh.console import ZenohConsoleFactory

        capture_test_logs(self, "snr")
        self.endpoints = [f"tcp/127.0.0.1:{free_port()}" for _ in range(2)]
        urov, camera = (
            [
                ZenohConsoleFactory(SYSTEM, listen=[ep], scouting=False),
                TimeoutLoopFactory(seconds=15),
            ]
            for ep in self.endpoints
        )
        self.release = threading.Event()
        blocker = RecorderFactory("blocker", [(TaskType.event, "block")], [], self.block)
        config = Config({"urov": [*urov, blocker], "camera": camera}, mode=Mode.TEST)
        self.nodes = LocalNodes(config, ["urov", "camera"])
        self.addCleanup(self.nodes.stop)
        self.addCleanup(self.release.set)  # (cleanups run last first: before the stop)

    def block(self, task: Task, key: TaskId) -> SomeTasks:
        self.release.wait(10.0)
        return None

    def every_node(self) -> object:
        """A console to "*" that has met both nodes."""
        from snr.extras.zenoh.console import ZenohConsole

        console = ZenohConsole(SYSTEM, connect=self.endpoints, scouting=False, timeout_s=5.0)
        self.addCleanup(console.close)
        self.assertTrue(wait_until(lambda: console.roles() == ["camera", "urov"]), "both answer")
        return console

    def test_read_only_commands_show_every_reply_and_exit_is_refused(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        console = ZenohConsole(SYSTEM, connect=self.endpoints, scouting=False, timeout_s=5.0)
        self.addCleanup(console.close)
        self.assertTrue(wait_until(lambda: console.roles() == ["camera", "urov"]), "both answer")
        greeting = console.connect()
        self.assertIs(greeting.status, Status.HELLO)
        self.assertIn("only help, list, stats", greeting.text)
        listing = console.send("list endpoints")
        self.assertIs(listing.status, Status.OK)
        self.assertIn("[camera]", listing.text)
        self.assertIn("[urov]", listing.text)
        refused = console.send("exit")
        self.assertIs(refused.status, Status.ERROR)
        self.assertIn("Not sent: `exit` changes a node", refused.text)
        self.assertIn("--zenoh lab ROLE", refused.text)
        for streaming in ("echo", "hz"):
            not_sent = console.send(f"{streaming} depth 1")
            self.assertIs(not_sent.status, Status.ERROR)
            self.assertIn(f"Not sent: `{streaming}` streams from one node", not_sent.text)
            self.assertIn("Name the node to stream from", not_sent.text)
            self.assertNotIn("changes a node", not_sent.text)
        typo = console.send("relaod all")
        self.assertIn("Not sent: `relaod` is not a console command", typo.text)
        self.assertFalse(any(node.is_terminated() for node in self.nodes.nodes), "none stopped")

    def test_a_new_console_meets_its_endpoints_before_it_asks(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole

        # Zenoh connects in the background: a query sent at once could miss a node.
        console = ZenohConsole(SYSTEM, connect=self.endpoints, scouting=False, timeout_s=5.0)
        self.addCleanup(console.close)
        console._open()  # what connect() and roles() do first
        self.assertEqual(len(list(console.session.info.peers_zid())), 2, "met both at once")
        # An endpoint nobody listens on holds a console up for its timeout at most.
        nobody = f"tcp/127.0.0.1:{free_port()}"
        lonely = ZenohConsole(SYSTEM, connect=[nobody], scouting=False, timeout_s=0.3)
        self.addCleanup(lonely.close)
        started = time.monotonic()
        self.assertEqual(lonely.roles(timeout_s=0.1), [])
        self.assertLess(time.monotonic() - started, 5.0, "bounded by the console's timeout")

    def test_a_console_through_a_router_meets_it_at_once_in_either_mode(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole, ZenohConsoleFactory
        from tests.test_comms_zenoh import start_router

        router_ep = start_router(self)
        arm = [
            ZenohConsoleFactory(SYSTEM, mode="client", connect=[router_ep], scouting=False),
            TimeoutLoopFactory(seconds=15),
        ]
        arm_node = LocalNodes(Config({"arm": arm}, mode=Mode.TEST), ["arm"])
        self.addCleanup(arm_node.stop)
        for mode in ("client", "peer"):  # a peer meets the router as a router, not a peer
            console = ZenohConsole(
                SYSTEM, "arm", mode=mode, connect=[router_ep], scouting=False, timeout_s=5.0
            )
            self.addCleanup(console.close)
            started = time.monotonic()
            console._open()
            self.assertLess(time.monotonic() - started, 1.0, f"{mode}: met, not timed out")
            self.assertEqual(len(list(console.session.info.routers_zid())), 1, mode)
            self.assertTrue(wait_until(lambda: console.roles() == ["arm"]), mode)  # noqa: B023

    def test_a_node_that_does_not_reply_in_time_is_named_and_the_command_fails(self) -> None:
        import snr.console
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        every = self.every_node()
        assert isinstance(every, ZenohConsole)
        every.connect()
        with ZenohConsole(SYSTEM, "urov", connect=self.endpoints, scouting=False) as urov:
            self.assertIs(urov.send("task event block").status, Status.OK)
        every.timeout_s = 0.5
        stats = every.send("stats")
        self.assertIs(stats.status, Status.ERROR, stats.text)
        self.assertIn("[camera]\nQueue of node 'camera'", stats.text)
        self.assertIn("[urov] no reply within 0.5 s", stats.text)

        where = [arg for ep in self.endpoints for arg in ("--connect", ep)] + ["--no-scouting"]
        out, err = io.StringIO(), io.StringIO()
        code = snr.console.main(
            ["--zenoh", SYSTEM, *where, "--timeout", "1", "-c", "stats"], stdout=out, stderr=err
        )
        self.assertNotEqual(code, 0, "a node that did not answer fails the command")
        self.assertIn("[urov] no reply within 1 s", out.getvalue())

    def test_a_node_that_needs_a_token_is_named_and_the_others_still_answer(self) -> None:
        import snr.console
        from snr.extras.zenoh.console import ZenohConsole, ZenohConsoleFactory
        from snr.std_mods.io.console_protocol import Status

        arm_endpoint = f"tcp/127.0.0.1:{free_port()}"
        arm = [
            ZenohConsoleFactory(SYSTEM, listen=[arm_endpoint], scouting=False, token="sesame"),
            TimeoutLoopFactory(seconds=15),
        ]
        arm_node = LocalNodes(Config({"arm": arm}, mode=Mode.TEST), ["arm"])
        self.addCleanup(arm_node.stop)
        endpoints = [*self.endpoints, arm_endpoint]
        console = ZenohConsole(SYSTEM, connect=endpoints, scouting=False, timeout_s=5.0)
        self.addCleanup(console.close)
        roles = ["arm", "camera", "urov"]
        self.assertTrue(wait_until(lambda: console.roles() == roles), "all three answer")

        greeting = console.connect()
        self.assertIs(greeting.status, Status.HELLO)
        refused = "[arm] refused: this node needs its console token (give it: --token,"
        self.assertIn(refused, greeting.text)
        self.assertIn("[urov] Connected to node 'urov'", greeting.text)
        stats = console.send("stats")
        self.assertIs(stats.status, Status.OK, stats.text)
        self.assertIn(refused, stats.text)
        self.assertIn("[camera]\nQueue of node 'camera'", stats.text)

        where = [arg for ep in endpoints for arg in ("--connect", ep)] + ["--no-scouting"]
        out, err = io.StringIO(), io.StringIO()
        code = snr.console.main(["--zenoh", SYSTEM, *where, "-c", "stats"], stdout=out, stderr=err)
        self.assertEqual(code, 0, err.getvalue())
        self.assertIn(refused, out.getvalue())
        self.assertIn("[urov]\nQueue of node 'urov'", out.getvalue())

    def start_arm(self, endpoint: str, token: Optional[str] = None) -> LocalNodes:
        """A third node, 'arm', with a Zenoh console listening on ``endpoint`` (and ``block``)."""
        from snr.extras.zenoh.console import ZenohConsoleFactory

        factories = [
            ZenohConsoleFactory(SYSTEM, listen=[endpoint], scouting=False, token=token),
            TimeoutLoopFactory(seconds=15),
            RecorderFactory("blocker", [(TaskType.event, "block")], [], self.block),
        ]
        arm = LocalNodes(Config({"arm": factories}, mode=Mode.TEST), ["arm"])
        self.addCleanup(arm.stop)
        return arm

    def every_node_with_arm(self, arm_endpoint: str, roles: List[str]) -> object:
        """A console to "*" that also connects to arm's endpoint, once ``roles`` answer."""
        from snr.extras.zenoh.console import ZenohConsole

        endpoints = [*self.endpoints, arm_endpoint]
        console = ZenohConsole(SYSTEM, connect=endpoints, scouting=False, timeout_s=5.0)
        self.addCleanup(console.close)
        self.assertTrue(wait_until(lambda: console.roles() == roles), f"{roles} answer")
        console.connect()
        return console

    def test_a_node_that_left_is_named_as_gone_and_does_not_fail_the_command(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        endpoint = f"tcp/127.0.0.1:{free_port()}"
        arm = self.start_arm(endpoint)
        every = self.every_node_with_arm(endpoint, ["arm", "camera", "urov"])
        assert isinstance(every, ZenohConsole)
        arm.stop()
        self.assertTrue(wait_until(lambda: every.roles() == ["camera", "urov"]), "arm is gone")
        for command in ("stats", "list endpoints"):
            reply = every.send(command)
            self.assertIs(reply.status, Status.OK, reply.text)
            self.assertIn("[arm] left the system (its console is gone)", reply.text)
            self.assertEqual(reply.text.count("[arm]"), 1, reply.text)
            self.assertIn("[camera]\n", reply.text)
            self.assertIn("[urov]\n", reply.text)

    def test_a_node_without_a_liveliness_token_is_not_said_to_have_left(self) -> None:
        from unittest import mock

        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        endpoint = f"tcp/127.0.0.1:{free_port()}"
        arm = self.start_arm(endpoint)
        # As with nodes of an older SNR: no console says it is alive.
        with mock.patch.object(ZenohConsole, "_alive_roles", staticmethod(lambda _: set())):
            every = self.every_node_with_arm(endpoint, ["arm", "camera", "urov"])
            assert isinstance(every, ZenohConsole)
            arm.stop()
            self.assertTrue(wait_until(lambda: every.roles() == ["camera", "urov"]), "arm gone")
            every.timeout_s = 0.5
            stats = every.send("stats")
        self.assertIs(stats.status, Status.ERROR, stats.text)
        self.assertIn("[arm] no reply within 0.5 s: the node does not say whether", stats.text)
        self.assertNotIn("busy in a slow handler", stats.text)
        self.assertIn("[camera]\nQueue of node 'camera'", stats.text)
        self.assertIn("[urov]\nQueue of node 'urov'", stats.text)

    def test_a_node_that_joins_later_and_needs_a_token_is_named_as_refusing(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        endpoint = f"tcp/127.0.0.1:{free_port()}"
        every = self.every_node_with_arm(endpoint, ["camera", "urov"])  # arm is not up yet
        assert isinstance(every, ZenohConsole)
        self.start_arm(endpoint, token="sesame")
        self.assertTrue(wait_until(lambda: "arm" in every.roles()), "arm joined")
        refused = "[arm] refused: this node needs its console token (give it: --token,"
        for command in ("stats", "help"):
            reply = every.send(command)
            self.assertIs(reply.status, Status.OK, reply.text)
            self.assertIn(refused, reply.text)
            self.assertEqual(reply.text.count("[arm]"), 1, reply.text)
            self.assertIn("[urov]\n", reply.text)

    def test_a_node_that_joins_later_is_reached_then_named_when_it_leaves(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        endpoint = f"tcp/127.0.0.1:{free_port()}"
        every = self.every_node_with_arm(endpoint, ["camera", "urov"])  # arm is not up yet
        assert isinstance(every, ZenohConsole)
        arm = self.start_arm(endpoint)
        self.assertTrue(wait_until(lambda: "arm" in every.roles()), "arm joined")
        stats = every.send("stats")
        self.assertIs(stats.status, Status.OK, stats.text)
        self.assertIn("[arm]\nQueue of node 'arm'", stats.text)
        self.assertIn("[camera]\nQueue of node 'camera'", stats.text)

        arm.stop()
        self.assertTrue(wait_until(lambda: every.roles() == ["camera", "urov"]), "arm is gone")
        stats = every.send("stats")
        self.assertIs(stats.status, Status.OK, stats.text)
        self.assertIn("[arm] left the system (its console is gone)", stats.text)

    def test_a_node_that_joins_later_busy_is_named_and_the_command_fails(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole
        from snr.std_mods.io.console_protocol import Status

        endpoint = f"tcp/127.0.0.1:{free_port()}"
        every = self.every_node_with_arm(endpoint, ["camera", "urov"])  # arm is not up yet
        assert isinstance(every, ZenohConsole)
        self.start_arm(endpoint)
        self.addCleanup(self.release.set)  # before arm stops (cleanups run last first)
        self.assertTrue(wait_until(lambda: "arm" in every.roles()), "arm joined")
        with ZenohConsole(SYSTEM, "arm", connect=[endpoint], scouting=False) as arm:
            self.assertIs(arm.send("task event block").status, Status.OK)
        every.timeout_s = 0.5
        stats = every.send("stats")  # arm never answered a command of this console
        self.assertIs(stats.status, Status.ERROR, stats.text)
        self.assertIn("[arm] no reply within 0.5 s: the node may be busy", stats.text)
        self.assertIn("[camera]\nQueue of node 'camera'", stats.text)

    def test_the_command_line_without_a_role_never_stops_every_node(self) -> None:
        import snr.console

        where = [arg for ep in self.endpoints for arg in ("--connect", ep)] + ["--no-scouting"]
        out, err = io.StringIO(), io.StringIO()
        code = snr.console.main(
            ["--zenoh", SYSTEM, *where, "-c", "stats", "-c", "exit"], stdout=out, stderr=err
        )
        self.assertNotEqual(code, 0, "a refused command fails")
        self.assertIn("Not sent: `exit`", out.getvalue())
        self.assertFalse(any(node.is_terminated() for node in self.nodes.nodes), "none stopped")


if __name__ == "__main__":
    unittest.main()
