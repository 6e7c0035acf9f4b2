"""The console uses the node's secret as its token unless a token is given (docs/console.md).

A node with ``SNR_SECRET`` needs it from every console, and a console with
the same secret gets in with no ``--token``. The environment is set for each
test alone (as in tests/test_comms_trust.py): never the secret of whoever
runs the suite.
"""

from __future__ import annotations

import contextlib
import os
import socket
import unittest
from typing import Any, ContextManager, Dict, Iterator
from unittest import mock

from snr import CommandReceiverFactory, TimeoutLoopFactory
from snr.core import NodeState
from snr.prelude import ConfigError
from snr.std_mods.comms.handshake import derived_word
from snr.std_mods.io import RemoteConsole
from snr.std_mods.io.console_protocol import (
    SECRET_TOKEN_PURPOSE,
    TOKEN_ENV_VAR,
    ConsoleConnectionError,
    Status,
    default_token,
)
from tests.console_helpers import NodeInThread, read_replies

SECRET = "correct horse battery staple"
NO_SECRET_FILE = os.path.join(os.devnull + ".missing", "secret")


def environment(**variables: str) -> ContextManager[Any]:
    """The environment of a node or console: of SNR's variables, only these set."""
    values: Dict[str, str] = {"SNR_SECRET_FILE": NO_SECRET_FILE, TOKEN_ENV_VAR: ""}
    values.update(variables)
    if "SNR_SECRET" not in variables:
        values["SNR_SECRET"] = ""  # taken out again on entry, below
    return _without_empty(mock.patch.dict(os.environ, values))


@contextlib.contextmanager
def _without_empty(patch: Any) -> Iterator[None]:
    with patch:
        if not os.environ.get("SNR_SECRET"):
            del os.environ["SNR_SECRET"]
        yield


class TestTheDefaultToken(unittest.TestCase):
    def setUp(self) -> None:
        context = environment()
        context.__enter__()
        self.addCleanup(context.__exit__, None, None, None)

    def test_no_secret_and_no_token_is_no_token(self) -> None:
        self.assertIsNone(default_token(None, "test"))
        self.assertIsNone(CommandReceiverFactory(port=0).token)
        self.assertIsNone(RemoteConsole().token)

    def test_the_secret_makes_a_word_that_is_not_the_secret(self) -> None:
        os.environ["SNR_SECRET"] = SECRET
        word = derived_word(SECRET.encode(), SECRET_TOKEN_PURPOSE)
        self.assertEqual(default_token(None, "test"), word)
        self.assertEqual(CommandReceiverFactory(port=0).token, word)
        self.assertEqual(RemoteConsole().token, word)
        self.assertNotIn("horse", word)
        self.assertEqual(len(word), 64)
        # The word is a valid token even on a shared address.
        self.assertEqual(CommandReceiverFactory(host="0.0.0.0", port=0).token, word)

    def test_a_token_given_wins_over_the_secret(self) -> None:
        os.environ["SNR_SECRET"] = SECRET
        self.assertEqual(CommandReceiverFactory(port=0, token="given-word").token, "given-word")
        os.environ[TOKEN_ENV_VAR] = "from-env"
        self.assertEqual(CommandReceiverFactory(port=0).token, "from-env")
        self.assertEqual(RemoteConsole().token, "from-env")

    def test_an_empty_secret_is_explained(self) -> None:
        os.environ["SNR_SECRET"] = "  "
        with self.assertRaisesRegex(ConfigError, "CommandReceiverFactory: the secret in"):
            CommandReceiverFactory(port=0)


class TestExitNeedsTheSecret(unittest.TestCase):
    def test_exit_without_the_secret_is_refused_and_with_it_stops_the_node(self) -> None:
        with environment(SNR_SECRET=SECRET):
            run = NodeInThread([TimeoutLoopFactory(seconds=30)])
        with self.assertLogs("snr.robot", "WARNING") as logs, run:
            # A program without the secret types `exit`: refused, in words, and the node runs on.
            with socket.create_connection((run.host, run.port), timeout=5) as stranger:
                stranger.sendall(b"exit\n")
                replies = read_replies(stranger, 3)
            self.assertEqual([r.status for r in replies], [Status.AUTH, Status.BYE])
            self.assertIn("Wrong or missing console token", replies[1].text)
            self.assertIn("$SNR_SECRET", replies[1].text)
            self.assertIs(run.node.state, NodeState.RUNNING)

            # snr-console without the secret: told what the node needs, before it sends anything.
            with environment(), self.assertRaises(ConsoleConnectionError) as refused:
                run.console()
            self.assertIn("needs a console token", str(refused.exception))
            self.assertIn("$SNR_SECRET", str(refused.exception))
            self.assertIs(run.node.state, NodeState.RUNNING)

            # The same secret, and no --token: it gets in, and `exit` stops the node.
            with environment(SNR_SECRET=SECRET):
                console = run.console()
            self.assertEqual(console.send("exit").status, Status.BYE)
            run.wait_stopped()
            self.assertIs(run.node.state, NodeState.TERMINATED)
        self.assertIn("sent a command before its token", logs.output[0])


if __name__ == "__main__":
    unittest.main()
