"""Who may link to a node: the system name and the secret (docs/comms.md, "Who may connect").

Each foreign peer here is a plain socket on 127.0.0.1 that speaks the
documented frames (docs/wire-format.md, section 3.1 and 3.5) with nothing but
`json`, `hmac` and `hashlib`; the node under test is a real SNR sockets server.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import socket
import time
import unittest
from typing import Any, Callable, Dict, List, Optional
from unittest import mock

from snr import Config, Mode, SocketsPair
from snr.prelude import ConfigError, WireFormatError
from snr.std_mods.codec import HEADER_BYTES, Hello, Proof, decode_body, encode_hello
from snr.std_mods.comms.comms_loop import CommsLoop
from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, find_secret, proof_mac, resolve_system
from tests.helpers import free_port, wait_until
from tests.test_comms_liveness import CommsFaultTest, CounterFactory, frame, read_until_closed
from tests.test_comms_local import connect_when_listening

SECRET = "correct horse battery staple"
SYSTEM = "team7"


def page(key: str, data: Any) -> bytes:
    return frame(v=1, kind="page", key=key, data=data, origin="tool", created_at_s=1.0)


def recv_frame(sock: socket.socket) -> Dict[str, Any]:
    def exactly(n: int) -> bytes:
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise ConnectionError(f"closed after {len(data)} of {n} bytes")
            data += chunk
        return data

    obj: Dict[str, Any] = json.loads(exactly(int.from_bytes(exactly(4), "big")))
    return obj


def more_than(counter: CounterFactory, n: int) -> Callable[[], bool]:
    return lambda: len(counter.seen) > n


def restore_secret(old: Optional[str]) -> None:
    if old is not None:
        os.environ["SNR_SECRET"] = old


def mac(secret: str, side: str, prover: str, verifier: str) -> str:
    text = f"snr-proof {side} {prover} {verifier}".encode("ascii")
    return hmac.new(secret.encode("utf-8"), text, hashlib.sha256).hexdigest()


class TrustTest(CommsFaultTest):
    def serve(self, counter: CounterFactory, **options: Any) -> None:
        pair = SocketsPair(("127.0.0.1", self.port), **{"system": SYSTEM, **options})
        self.nodes = self.run_nodes(
            Config({"server": [pair.server(), counter]}, mode=Mode.TEST), ["server"]
        )

    def connect(self) -> socket.socket:
        sock = connect_when_listening(self.port)
        sock.settimeout(5)
        self.addCleanup(sock.close)
        return sock

    def hello(
        self, sock: socket.socket, nonce: Optional[str], system: str = SYSTEM, role: str = "tool"
    ) -> None:
        # (a refusal is logged once per host, role and reason: each peer here is another role)
        fields: Dict[str, Any] = {"v": 2, "kind": "hello", "role": role, "system": system}
        if nonce is not None:
            fields["nonce"] = nonce
        sock.sendall(frame(**fields))

    def refused_lines(self) -> List[str]:
        return self.log.matching("Refused client")


class TestAccidents(TrustTest):
    def test_a_node_of_another_system_is_refused_without_any_secret(self) -> None:
        counter = CounterFactory("tick")
        self.serve(counter, secret=None)
        for _ in range(3):  # it retries: one line for the peer, each time counted
            sock = self.connect()
            self.hello(sock, None, system="team3")
            sock.sendall(page("tick", 1))
            self.assertTrue(read_until_closed(sock, 5.0), "the server closes the connection")
        self.assertTrue(wait_until(lambda: len(self.refused_lines()) == 1, 5.0), self.log.lines)
        [line] = self.refused_lines()
        for part in ("127.0.0.1:", "'team3'", "'team7'", "'tool'"):
            self.assertIn(part, line)
        comms = self.nodes.nodes[0].components[f"sockets_server_{self.port}"]
        self.assertTrue(wait_until(lambda: comms.closed_totals["refused"] == 3, 5.0))  # type: ignore[attr-defined]
        self.assertEqual(counter.seen, [], "nothing it sent was stored")

    def test_a_program_that_names_no_system_is_refused_unless_the_server_names_none(self) -> None:
        counter = CounterFactory("tick")
        self.serve(counter, secret=None)
        sock = self.connect()
        sock.sendall(frame(v=1, kind="hello", role="tool") + page("tick", 1))
        self.assertTrue(read_until_closed(sock, 5.0))
        self.assertTrue(wait_until(lambda: len(self.refused_lines()) == 1, 5.0), self.log.lines)
        self.assertIn("names no system", self.refused_lines()[0])
        self.assertIn("system=None", self.refused_lines()[0])
        self.assertEqual(counter.seen, [])

    def test_the_same_system_gets_in_with_no_set_up(self) -> None:
        counter = CounterFactory("tick")
        self.serve(counter, secret=None)
        sock = self.connect()
        self.hello(sock, None)
        sock.sendall(page("tick", 1))
        self.assertTrue(wait_until(lambda: counter.seen == [1], 5.0), self.log.lines)
        self.assertEqual(recv_frame(sock)["system"], SYSTEM)

    def test_two_snr_nodes_of_different_systems_both_say_so_once(self) -> None:
        counter = CounterFactory("tick")
        server = SocketsPair(("127.0.0.1", self.port), system="team7", secret=None)
        client = SocketsPair(("127.0.0.1", self.port), system="team3", secret=None)
        from tests.test_comms_liveness import TickerFactory

        config = Config(
            {
                "receiver": [server.server(), counter],
                "sender": [TickerFactory(hz=100), client.client("tick")],
            },
            mode=Mode.TEST,
        )
        self.run_nodes(config, ["receiver", "sender"])
        time.sleep(1.5)  # the client retries meanwhile (backoff up to 1 s)
        self.assertEqual(counter.seen, [])
        self.assertEqual(len(self.log.matching("Refused client")), 1, self.log.lines)
        self.assertEqual(len(self.log.matching("Refused sockets server")), 1, self.log.lines)


class TestMalice(TrustTest):
    def test_no_secret_wrong_secret_and_a_replayed_hello_store_nothing(self) -> None:
        counter = CounterFactory("tick")
        self.serve(counter, secret=SECRET)

        no_secret = self.connect()
        self.hello(no_secret, None)
        no_secret.sendall(page("tick", 1))
        self.assertTrue(read_until_closed(no_secret, 5.0))

        wrong = self.connect()
        nonce = os.urandom(32).hex()
        self.hello(wrong, nonce, role="guesser")
        server_nonce = recv_frame(wrong)["nonce"]
        wrong.sendall(frame(v=2, kind="proof", mac=mac("guess", "client", nonce, server_nonce)))
        wrong.sendall(page("tick", 2))
        self.assertTrue(read_until_closed(wrong, 5.0))

        # A right conversation, recorded; then replayed word for word on a new connection.
        right = self.connect()
        nonce = os.urandom(32).hex()
        self.hello(right, nonce)
        server_hello = recv_frame(right)
        proof = frame(v=2, kind="proof", mac=mac(SECRET, "client", nonce, server_hello["nonce"]))
        right.sendall(proof + page("tick", 3))
        self.assertTrue(wait_until(lambda: counter.seen == [3], 5.0), self.log.lines)
        replay = self.connect()
        self.hello(replay, nonce, role="replayer")
        replay.sendall(proof + page("tick", 4))
        self.assertTrue(read_until_closed(replay, 5.0))

        pages_first = self.connect()  # a page before the proof: refused, not stored
        self.hello(pages_first, os.urandom(32).hex())
        pages_first.sendall(page("tick", 5))
        self.assertTrue(read_until_closed(pages_first, 5.0))

        # The server logs each refusal as it closes the connection: on a loaded machine the
        # last line may come a moment after the client saw the close.
        wait_until(lambda: len(self.refused_lines()) >= 4, 5.0)
        time.sleep(0.2)
        self.assertEqual(counter.seen, [3], "only the right secret stored a page")
        lines = "\n".join(self.refused_lines())
        self.assertIn("it has no secret", lines)
        self.assertIn("the two secrets differ", lines)
        self.assertIn("before the handshake ended", lines)
        self.assertEqual(len(self.refused_lines()), 4, lines)

    def test_the_server_proves_itself_too(self) -> None:
        counter = CounterFactory("tick")
        self.serve(counter, secret=SECRET)
        sock = self.connect()
        nonce = os.urandom(32).hex()
        self.hello(sock, nonce)
        server_hello = recv_frame(sock)
        server_proof = recv_frame(sock)
        self.assertEqual(server_proof["kind"], "proof")
        self.assertEqual(server_proof["mac"], mac(SECRET, "server", server_hello["nonce"], nonce))
        self.assertNotIn(SECRET, json.dumps(server_hello) + json.dumps(server_proof))

    def test_snr_nodes_with_the_same_secret_link_and_with_another_do_not(self) -> None:
        from tests.test_comms_liveness import TickerFactory

        for client_secret, flows in ((SECRET, True), ("another", False), (None, False)):
            with self.subTest(client_secret=client_secret):
                self.port = free_port()  # a fresh port for each pair of nodes
                refusals = len(self.log.matching("Refused"))
                counter = CounterFactory("tick")
                pair = SocketsPair(("127.0.0.1", self.port), system=SYSTEM, secret=SECRET)
                other = SocketsPair(("127.0.0.1", self.port), system=SYSTEM, secret=client_secret)
                nodes = self.run_nodes(
                    Config(
                        {
                            "receiver": [pair.server(), counter],
                            "sender": [TickerFactory(hz=100), other.client("tick")],
                        },
                        mode=Mode.TEST,
                    ),
                    ["receiver", "sender"],
                )
                if flows:
                    self.assertTrue(wait_until(more_than(counter, 5), 5.0))
                else:

                    def refused(before: int = refusals) -> bool:
                        return len(self.log.matching("Refused")) > before

                    # Once refused, 0.2 s more: a link that let ticks (100 Hz) through shows them.
                    self.assertTrue(wait_until(refused, 5.0), self.log.lines)
                    time.sleep(0.2)
                    self.assertEqual(counter.seen, [])
                nodes.stop()
        self.assertTrue(self.log.matching("Refused sockets server"), "the client says so too")


class TestIdleConnectionsWithASecret(TrustTest):
    """The idle-connection fault tests (tests/test_comms_liveness.py) with a secret set."""

    def serve_briefly(self) -> None:
        original = CommsLoop.hello_timeout_s
        CommsLoop.hello_timeout_s = 0.1
        self.addCleanup(setattr, CommsLoop, "hello_timeout_s", original)
        # A short silence limit makes the link check its peer every 0.025 s (else 0.25 s).
        self.serve(CounterFactory("tick"), secret=SECRET, dead_after_s=0.4)

    def test_a_connection_that_never_speaks_is_closed(self) -> None:
        self.serve_briefly()
        sock = self.connect()
        started = time.monotonic()
        self.assertEqual(recv_frame(sock)["kind"], "hello", "the server's hello, with its nonce")
        self.assertTrue(read_until_closed(sock, 3.0), "then it closes the connection")
        self.assertLess(time.monotonic() - started, 2.5)
        self.assertTrue(wait_until(self.closed_unfinished, 2.0), self.log.lines)

    def test_a_peer_that_says_hello_and_never_proves_it_is_closed(self) -> None:
        self.serve_briefly()
        sock = self.connect()
        started = time.monotonic()
        self.hello(sock, os.urandom(32).hex(), role="mute")
        self.assertTrue(read_until_closed(sock, 3.0), self.log.lines)
        self.assertLess(time.monotonic() - started, 2.5)
        self.assertTrue(wait_until(self.closed_unfinished, 2.0), self.log.lines)

    def closed_unfinished(self) -> bool:
        return bool(self.log.matching("did not finish the hello (and proof) within 0.1 s"))


class TestSecretSetting(unittest.TestCase):
    def setUp(self) -> None:
        # Whatever a test sets, the environment is as before after it (tests/__init__.py).
        environment = mock.patch.dict(os.environ)
        environment.start()
        self.addCleanup(environment.stop)

    def test_the_environment_and_the_option(self) -> None:
        old = os.environ.pop("SNR_SECRET", None)
        self.addCleanup(restore_secret, old)
        os.environ["SNR_SECRET_FILE"] = os.devnull + ".missing"
        self.assertIsNone(find_secret(FROM_ENVIRONMENT, "test"))
        os.environ["SNR_SECRET"] = " abc \n"
        self.addCleanup(os.environ.pop, "SNR_SECRET")
        self.assertEqual(find_secret(FROM_ENVIRONMENT, "test"), b"abc")
        self.assertEqual(find_secret("xyz", "test"), b"xyz")
        self.assertIsNone(find_secret(None, "test"))
        with self.assertRaises(ConfigError):
            find_secret("  ", "test")
        with self.assertRaises(ConfigError):
            resolve_system("", None, "test")

    def test_the_proof_is_the_documented_hmac(self) -> None:
        self.assertEqual(
            proof_mac(b"k", "client", "ab" * 32, "cd" * 32),
            mac("k", "client", "ab" * 32, "cd" * 32),
        )

    def test_hellos_of_each_version(self) -> None:
        v1 = decode_body(encode_hello("r")[HEADER_BYTES:])
        self.assertEqual(v1, Hello("r"))
        v2 = decode_body(encode_hello("r", system="s", nonce="0" * 64)[HEADER_BYTES:])
        self.assertEqual(v2, Hello("r", system="s", nonce="0" * 64))
        self.assertEqual(
            decode_body(b'{"v":2,"kind":"proof","mac":"%s"}' % (b"a" * 64)), Proof("a" * 64)
        )
        for bad in (
            b'{"v":2,"kind":"proof","mac":"xyz"}',
            b'{"v":1,"kind":"proof","mac":"%s"}' % (b"a" * 64),
        ):
            with self.subTest(bad=bad), self.assertRaises(WireFormatError):
                decode_body(bad)

    def test_secret_new_writes_a_file_only_its_owner_reads(self) -> None:
        import contextlib
        import io
        import tempfile

        from snr.__main__ import main

        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "snr", "secret")
            os.environ["SNR_SECRET_FILE"] = path
            with contextlib.redirect_stdout(io.StringIO()) as out:
                self.assertEqual(main(["secret", "new"]), 0)
            self.assertIn(path, out.getvalue())
            self.assertEqual(os.stat(path).st_mode & 0o777, 0o600)
            old = os.environ.pop("SNR_SECRET", None)
            self.addCleanup(restore_secret, old)
            secret = find_secret(FROM_ENVIRONMENT, "test")
            self.assertIsNotNone(secret)
            with contextlib.redirect_stderr(io.StringIO()) as err:
                self.assertEqual(main(["secret", "new"]), 1, "it does not overwrite")
            self.assertIn("--force", err.getvalue())
            self.assertEqual(find_secret(FROM_ENVIRONMENT, "test"), secret)


if __name__ == "__main__":
    unittest.main()
