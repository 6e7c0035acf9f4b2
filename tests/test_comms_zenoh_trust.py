"""Zenoh with a secret: only sessions with the same secret hear the system or speak into it.

The node under test is a real SNR node with `ZenohCommsFactory(secret=...)`;
the others are plain Zenoh sessions set up by `zenoh_config`, with the secret,
with another one, and with none. Everything runs on 127.0.0.1 with multicast
scouting off, explicit endpoints and ports chosen at run time. Skipped when
the Zenoh extra is not installed.
"""

from __future__ import annotations

import argparse
import importlib.util
import io
import json
import os
import stat
import sys
import threading
import time
import unittest
from typing import Any, List, Optional, Tuple
from unittest import mock

from snr import Config, Mode, TimeoutLoopFactory
from snr.extras.zenoh import router as router_command
from tests.helpers import free_port, wait_until
from tests.optional import reason
from tests.quiet import capture_test_logs
from tests.test_comms_liveness import CommsFaultTest, CounterFactory, TickerFactory
from tests.test_comms_local import LocalNodes

HAVE_ZENOH = importlib.util.find_spec("zenoh") is not None
SECRET = "correct horse battery staple"
SYSTEM = "team7"

if HAVE_ZENOH:
    from snr import ZenohCommsFactory
    from snr.extras.zenoh.comms import (
        MEET_ENDPOINTS_S,
        _zenoh_module,
        zenoh_config,
        zenoh_credentials,
    )


class Session:
    """A plain Zenoh session that listens to the system's pages and can put one."""

    def __init__(self, test: unittest.TestCase, endpoint: str, secret: Optional[bytes]) -> None:
        zenoh = _zenoh_module()
        self.session = zenoh.open(zenoh_config(connect=[endpoint], scouting=False, secret=secret))
        test.addCleanup(self.session.close)
        self.heard: List[Any] = []
        self._lock = threading.Lock()
        self.session.declare_subscriber(f"snr/{SYSTEM}/tick", self._on_sample)

    def _on_sample(self, sample: Any) -> None:
        with self._lock:
            self.heard.append(json.loads(sample.payload.to_bytes())["data"])

    def put(self, data: int) -> None:
        self.session.put(f"snr/{SYSTEM}/cmd", json.dumps({"data": data}).encode())


def only_the_friend_talks(test: unittest.TestCase, endpoint: str, commands: CounterFactory) -> None:
    """Sessions with the secret, another one and none at ``endpoint``: only the first talks.

    The friend hears the node and is heard by it: the link is up, the others have had
    as long to link, and only then do they all put (each its own numbers).
    """
    friend = Session(test, endpoint, SECRET.encode())
    wrong = Session(test, endpoint, b"a guess")
    stranger = Session(test, endpoint, None)
    test.assertTrue(wait_until(lambda: len(friend.heard) > 5, 10.0), "the friend hears")
    deadline = time.monotonic() + 1.0
    while time.monotonic() < deadline:
        friend.put(1)
        wrong.put(2)
        stranger.put(3)
        time.sleep(0.05)
    test.assertTrue(wait_until(lambda: 1 in commands.seen, 5.0), "the node hears the friend")
    time.sleep(0.3)
    test.assertEqual(set(commands.seen), {1}, "only the friend's pages were stored")
    test.assertEqual(wrong.heard, [], "a session with another secret hears nothing")
    test.assertEqual(stranger.heard, [], "a session without a secret hears nothing")


def robot_with_the_secret(test: CommsFaultTest, **where: Any) -> Tuple[CounterFactory, LocalNodes]:
    """Run a robot with SECRET that publishes ``tick`` and stores ``cmd``; where it meets others
    is ``where`` (``listen=[...]``, or ``mode="client", connect=[...]``). What it stored, its nodes.
    """
    commands = CounterFactory("cmd")
    comms = ZenohCommsFactory(
        SYSTEM, publish="tick", subscribe="cmd", scouting=False, secret=SECRET, **where
    )
    config = Config({"robot": [TickerFactory(hz=50), comms, commands]}, mode=Mode.TEST)
    nodes = test.run_nodes(config, ["robot"])
    test.addCleanup(nodes.stop)
    return commands, nodes


@unittest.skipUnless(HAVE_ZENOH, reason("zenoh"))
class TestZenohSecret(CommsFaultTest):
    def test_only_a_session_with_the_secret_hears_the_system_or_speaks_into_it(self) -> None:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        commands, _ = robot_with_the_secret(self, listen=[endpoint])
        only_the_friend_talks(self, endpoint, commands)

    def test_the_password_file_is_private_and_holds_no_secret(self) -> None:
        config = zenoh_config(scouting=False, secret=SECRET.encode())
        path = json.loads(config.get_json("transport/auth/usrpwd/dictionary_file"))
        user, password = zenoh_credentials(SECRET.encode())
        with open(path, encoding="ascii") as file:
            self.assertEqual(file.read(), f"{user}:{password}\n")
        self.assertNotIn("horse", password)
        self.assertEqual(stat.S_IMODE(os.stat(path).st_mode), 0o600)
        self.assertEqual(stat.S_IMODE(os.stat(os.path.dirname(path)).st_mode), 0o700)


@unittest.skipUnless(HAVE_ZENOH, reason("zenoh"))
class TestZenohRouterSecret(CommsFaultTest):
    """Through a router set up from the secret (zenohd's part: a Zenoh session in router mode)."""

    def start_router(self, secret: Optional[bytes]) -> str:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        config = zenoh_config(mode="router", listen=[endpoint], scouting=False, secret=secret)
        router = _zenoh_module().open(config)
        self.addCleanup(router.close)
        return endpoint

    def client_node(self, endpoint: str) -> Tuple[CounterFactory, LocalNodes]:
        """A robot in client mode with SECRET behind the router: what it stored of ``cmd``."""
        return robot_with_the_secret(self, mode="client", connect=[endpoint])

    def test_a_router_with_the_secret_forwards_only_between_sessions_with_it(self) -> None:
        endpoint = self.start_router(SECRET.encode())
        commands, _ = self.client_node(endpoint)
        only_the_friend_talks(self, endpoint, commands)

    def test_a_router_without_the_secret_refuses_the_node_and_the_node_says_why(self) -> None:
        endpoint = self.start_router(None)
        _, nodes = self.client_node(endpoint)
        # A client must reach its router when it starts, so the node stops with the reason.
        self.assertTrue(wait_until(lambda: nodes.errors, 10.0), self.log.lines)
        said = str(nodes.errors[0])
        self.assertIn("Node 'robot' could not open its Zenoh session", said)
        self.assertIn(endpoint, said)
        self.assertIn("the router has another secret, or only one side has one", said)
        self.assertIn("(this node has one)", said)


@unittest.skipUnless(HAVE_ZENOH, reason("zenoh"))
class TestZenohUnmetEndpoint(CommsFaultTest):
    """Zenoh says nothing when it refuses a session: the node that connects says it instead."""

    def connect_to_a_listener(self, listener_secret: bytes) -> Any:
        """A node with SECRET, connecting to a session that listens with ``listener_secret``."""
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        listener = _zenoh_module().open(
            zenoh_config(listen=[endpoint], scouting=False, secret=listener_secret)
        )
        self.addCleanup(listener.close)
        comms = ZenohCommsFactory(
            SYSTEM, publish="tick", connect=[endpoint], scouting=False, secret=SECRET
        )
        config = Config({"robot": [comms, TimeoutLoopFactory(seconds=15)]}, mode=Mode.TEST)
        nodes = self.run_nodes(config, ["robot"])
        return nodes, endpoint, listener

    def test_another_secret_is_said_naming_the_role_the_endpoint_and_the_fix(self) -> None:
        started = time.monotonic()
        _, endpoint, _ = self.connect_to_a_listener(b"another team's secret")
        said = f"has met no Zenoh node at {endpoint}"
        self.assertTrue(wait_until(lambda: self.log.matching(said), 10.0), self.log.lines)
        # Not before the bound: Zenoh takes a moment to link even when all is well.
        self.assertGreaterEqual(self.log.first(said) or 0.0, started + MEET_ENDPOINTS_S)
        (line,) = self.log.matching(said)
        self.assertIn("'robot'", line)
        self.assertIn("both sides need the same SNR_SECRET", line)
        self.assertIn("nothing listens there", line)

    def test_the_same_secret_links_and_says_nothing(self) -> None:
        nodes, _, listener = self.connect_to_a_listener(SECRET.encode())
        self.assertTrue(wait_until(lambda: list(listener.info.peers_zid()), 10.0), "linked")
        time.sleep(MEET_ENDPOINTS_S + 0.5)  # past the bound: a warning would be out by now
        self.assertEqual(self.log.matching("has met no Zenoh node"), [])
        self.assertTrue(nodes.threads[0].is_alive())


@unittest.skipUnless(HAVE_ZENOH, reason("zenoh"))
class TestZenohConsoleSecret(unittest.TestCase):
    def test_exit_from_a_console_without_the_secret_does_not_stop_the_node(self) -> None:
        from snr.extras.zenoh.console import ZenohConsole, ZenohConsoleFactory
        from snr.std_mods.io.console_protocol import ConsoleConnectionError, Status

        capture_test_logs(self, "snr")
        no_secret = {"SNR_SECRET_FILE": os.devnull + ".missing", "SNR_CONSOLE_TOKEN": ""}
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        # The node finds its secret when it starts (its Zenoh session) and when it is built
        # (its console token): this process's environment has it until the test ends.
        node_environment = mock.patch.dict(os.environ, {**no_secret, "SNR_SECRET": SECRET})
        node_environment.start()
        self.addCleanup(node_environment.stop)
        factory = ZenohConsoleFactory(SYSTEM, listen=[endpoint], scouting=False)
        nodes = LocalNodes(
            Config({"urov": [factory, TimeoutLoopFactory(seconds=15)]}, mode=Mode.TEST), ["urov"]
        )
        self.addCleanup(nodes.stop)

        def console(secret: Optional[str], timeout_s: float = 1.0) -> ZenohConsole:
            with mock.patch.dict(os.environ, no_secret):
                os.environ.pop("SNR_SECRET", None)
                if secret is not None:
                    os.environ["SNR_SECRET"] = secret
                made = ZenohConsole(
                    SYSTEM, "urov", connect=[endpoint], scouting=False, timeout_s=timeout_s
                )
            self.addCleanup(made.close)
            return made

        friend = console(SECRET)
        self.assertTrue(wait_until(lambda: _greets(friend), 10.0), "the node is up")
        for secret in (None, "a guess"):
            with self.subTest(secret=secret):
                # (Half the friend's timeout: a node that took its command would stop
                # all the same, and the check below would say so.)
                stranger = console(secret, timeout_s=0.5)
                # Its session links to nothing: no node answers it, and `exit` goes nowhere.
                with self.assertRaisesRegex(ConsoleConnectionError, "No node"):
                    stranger.connect()
                with self.assertRaises(ConsoleConnectionError):
                    stranger.send("exit")
        self.assertTrue(nodes.threads[0].is_alive(), "the node runs on")
        self.assertIs(friend.send("exit").status, Status.BYE)
        nodes.threads[0].join(5.0)
        self.assertFalse(nodes.threads[0].is_alive(), "the console with the secret stopped it")


def _greets(console: Any) -> bool:
    from snr.std_mods.io.console_protocol import ConsoleConnectionError

    try:
        console.connect()
    except ConsoleConnectionError:
        return False
    return True


@unittest.skipUnless(HAVE_ZENOH, reason("zenoh"))
class TestRouterCommand(unittest.TestCase):
    """``python -m snr router``: a classroom's router, linking only sessions with the secret."""

    def test_the_router_links_a_client_with_the_secret_and_refuses_one_without(self) -> None:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        out = io.StringIO()
        # The secret stays set until the test ends: the router's thread reads it when it starts.
        secret_set = mock.patch.dict(os.environ, {"SNR_SECRET": SECRET})
        secret_set.start()
        self.addCleanup(secret_set.stop)
        args = argparse.Namespace(listen=[endpoint], seconds=2.5, zenohd=False)
        serving = threading.Thread(target=router_command.run, args=(args, out))
        serving.start()
        self.addCleanup(serving.join, 10.0)
        self.assertTrue(wait_until(lambda: "listening on" in out.getvalue(), 5.0), out.getvalue())
        self.assertIn("only nodes with this computer's secret link to it", out.getvalue())
        zenoh = _zenoh_module()
        # A client must reach its router when its session opens: it opens, or it fails.
        friend = zenoh.open(
            zenoh_config("client", connect=[endpoint], scouting=False, secret=SECRET.encode())
        )
        self.assertTrue(wait_until(lambda: "1 session(s) linked" in out.getvalue(), 5.0))
        friend.close()
        for secret in (None, b"a guess"):
            with self.subTest(secret=secret), self.assertRaises(zenoh.ZError):
                zenoh.open(
                    zenoh_config("client", connect=[endpoint], scouting=False, secret=secret)
                )
        # Refused by the router, not by its absence (the body takes about 0.5 s).
        self.assertTrue(serving.is_alive(), "the router still serves")
        serving.join(10.0)
        self.assertTrue(out.getvalue().endswith("Zenoh router stopped.\n"), out.getvalue())

    def test_zenohd_settings_hold_the_password_made_from_the_secret_not_the_secret(self) -> None:
        out = io.StringIO()
        with mock.patch.dict(os.environ, {"SNR_SECRET": SECRET}):
            args = argparse.Namespace(listen=None, seconds=None, zenohd=True)
            self.assertEqual(router_command.run(args, out), 0)
        user, password = zenoh_credentials(SECRET.encode())
        self.assertIn(f"\n{user}:{password}\n", out.getvalue())
        self.assertIn(f'password: "{password}"', out.getvalue())
        self.assertNotIn("horse", out.getvalue())


class TestRouterWithoutZenoh(unittest.TestCase):
    def test_the_router_says_how_to_install_zenoh(self) -> None:
        args = argparse.Namespace(listen=None, seconds=0.0, zenohd=False)
        said = io.StringIO()
        with mock.patch.dict(sys.modules, {"zenoh": None}), mock.patch("sys.stderr", said):
            self.assertEqual(router_command.run(args, io.StringIO()), 1)
        self.assertIn("a router needs the Zenoh library: pip install", said.getvalue())
        self.assertIn("[zenoh]", said.getvalue())


if __name__ == "__main__":
    unittest.main()
