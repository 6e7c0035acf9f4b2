"""Talking to an SNR node with nothing but `socket`, `json`, `hmac` and `hashlib`.

(docs/wire-format.md; `os.urandom` gives the challenge's random bytes.)

The node runs in a child process. The test's side of each conversation uses
only the functions below, written from the spec alone (no snr imports), the
way a program in another language would.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import random
import socket
import time
import unittest
from typing import Any, Dict, List, Optional

from snr import SocketsPair
from tests.comms_helpers import (
    LogForwarderFactory,
    NodeProcess,
    ReporterFactory,
    Reports,
    SendOnConnectFactory,
    context,
    pages_of,
)
from tests.helpers import free_port
from tests.optional import HealthCheck, given, needs, settings, st


# -- the foreign side: socket + json only -------------------------------------
def connect(port: int) -> socket.socket:
    for _ in range(250):
        try:
            sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        except ConnectionRefusedError:
            time.sleep(0.02)
            continue
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return sock
    raise AssertionError(f"nothing listens on port {port}")


def frame(body: bytes) -> bytes:
    return len(body).to_bytes(4, "big") + body


def send_json(sock: socket.socket, obj: Dict[str, Any]) -> None:
    body = json.dumps(obj, separators=(",", ":"), allow_nan=False).encode("utf-8")
    sock.sendall(frame(body))


def recv_exactly(sock: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError(f"closed after {len(data)} of {n} bytes")
        data += chunk
    return data


def recv_json(sock: socket.socket) -> Dict[str, Any]:
    n = int.from_bytes(recv_exactly(sock, 4), "big")
    obj: Dict[str, Any] = json.loads(recv_exactly(sock, n).decode("utf-8"))
    return obj


SYSTEM = "interop"
SECRET = "a secret the whole team shares"


def say_hello(
    sock: socket.socket, role: str = "foreign", secret: Optional[str] = None
) -> Dict[str, Any]:
    """The version 2 hello (docs/wire-format.md 3.1), and the proofs (3.5) with a secret.

    Returns the server's hello; with a secret, checks the server's proof too.
    """
    hello: Dict[str, Any] = {"v": 2, "kind": "hello", "role": role, "system": SYSTEM}
    nonce = os.urandom(32).hex()
    if secret is not None:
        hello["nonce"] = nonce
    send_json(sock, hello)
    theirs = recv_json(sock)
    if secret is None:
        return theirs
    key = secret.encode("utf-8")

    def mac(side: str, prover: str, verifier: str) -> str:
        text = f"snr-proof {side} {prover} {verifier}".encode("ascii")
        return hmac.new(key, text, hashlib.sha256).hexdigest()

    send_json(sock, {"v": 2, "kind": "proof", "mac": mac("client", nonce, theirs["nonce"])})
    proof = recv_json(sock)
    assert proof["kind"] == "proof", proof
    assert hmac.compare_digest(proof["mac"], mac("server", theirs["nonce"], nonce)), "not ours"
    return theirs


def page(key: str, data: Any, origin: str = "foreign", created: float = 42.5) -> Dict[str, Any]:
    return {
        "v": 1,
        "kind": "page",
        "key": key,
        "data": data,
        "origin": origin,
        "created_at_s": created,
        "process": True,
    }


def is_closed_by_peer(sock: socket.socket) -> bool:
    sock.settimeout(5)
    try:
        while sock.recv(4096):
            pass  # the hello, then end of stream
    except ConnectionResetError:
        pass
    return True


# -- bad frames for the barrage ------------------------------------------------
REQUIRED = ["v", "kind", "key", "data", "origin", "created_at_s"]
wrong_values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=2),
    st.text(max_size=5).filter(lambda s: s not in ("page", "hello")),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)


@st.composite
def broken_page(draw: Any) -> bytes:
    fields = page("bad", draw(st.integers()))
    name = draw(st.sampled_from([*REQUIRED, "process"]))
    if name == "data" or draw(st.booleans()):
        del fields[name]
        if name == "process":
            fields["v"] = 0  # an optional field missing is fine: break another
    else:
        value = draw(wrong_values)
        if name == "created_at_s" and isinstance(value, int) and not isinstance(value, bool):
            value = str(value)
        if name in ("key", "origin") and isinstance(value, str):
            value = ""
        if name == "process" and isinstance(value, bool):
            value = "yes"
        fields[name] = value
    return json.dumps(fields).encode("utf-8")


bad_bodies = st.one_of(
    broken_page(),
    st.binary(max_size=64),  # random bytes
    st.binary(min_size=1, max_size=32).map(lambda b: b"\xff" + b),  # never UTF-8
    st.sampled_from([b"[]", b"null", b'"page"', b"{", b'{"v":1,"kind":"page","data":NaN}']),
    # valid for a lax JSON reader, rejected by the strict one (docs/wire-format.md, section 5)
    st.sampled_from(
        [
            json.dumps(page("bad", 1)).replace('"data": 1', f'"data": {value}').encode()
            for value in ("1e999", "-1E400", "Infinity", '"\\ud800"', "[" * 100 + "]" * 100)
        ]
        + [json.dumps({**page("bad", 1), "v": 1.0}).encode()]
    ),
)


class InteropTest(unittest.TestCase):
    def setUp(self) -> None:
        self.ctx = context()
        self.reports = Reports(self.ctx)
        self.addCleanup(self.reports.close)
        self.port = free_port()
        self.pair = SocketsPair(server_tuple=("127.0.0.1", self.port), system=SYSTEM, secret=None)
        self.sockets: List[socket.socket] = []

    def start_server(self, *factories: Any) -> NodeProcess:
        node = NodeProcess(self.ctx, "snr_server", factories).start()
        self.addCleanup(node.interrupt)
        self.reports.nodes.append(node)  # a failure shows what it printed
        return node

    def connect(self) -> socket.socket:
        sock = connect(self.port)
        self.addCleanup(sock.close)
        return sock

    def wait_pages(self, key: str, count: int) -> List[Any]:
        if len(pages_of(self.reports.seen, "snr_server", key)) < count:
            self.reports.wait_for(
                lambda _: len(pages_of(self.reports.seen, "snr_server", key)) >= count
            )
        return pages_of(self.reports.seen, "snr_server", key)

    def test_a_foreign_program_sends_a_page(self) -> None:
        self.start_server(self.pair.server(), ReporterFactory(self.reports.writer, ["cmd"]))
        sock = self.connect()
        self.assertEqual(
            say_hello(sock),
            {"v": 2, "kind": "hello", "role": "snr_server", "beat_s": 1.0, "bye": True}
            | {"system": SYSTEM},
        )
        send_json(sock, page("cmd", {"A": 1, "stick": [0.5, -1]}))
        self.assertEqual(self.wait_pages("cmd", 1), [{"A": 1, "stick": [0.5, -1]}])
        self.assertEqual(self.reports.seen[0][3:], ("foreign", 42.5), "origin and time kept")

    def test_a_foreign_program_receives_pages(self) -> None:
        self.start_server(self.pair.server(["greeting"]), SendOnConnectFactory("greeting", 3))
        sock = self.connect()
        say_hello(sock)  # the server sends pages once the hello is judged
        received = [recv_json(sock) for _ in range(3)]
        self.assertEqual(
            received, [page("greeting", i, "snr_server", 1000.0 + i) for i in range(3)]
        )

    def test_a_foreign_program_with_the_secret_sends_a_page(self) -> None:
        pair = SocketsPair(("127.0.0.1", self.port), system=SYSTEM, secret=SECRET)
        self.start_server(pair.server(), ReporterFactory(self.reports.writer, ["cmd"]))
        sock = self.connect()
        self.assertEqual(len(say_hello(sock, secret=SECRET)["nonce"]), 64)
        send_json(sock, page("cmd", 7))
        self.assertEqual(self.wait_pages("cmd", 1), [7])

    @needs("hypothesis")
    def test_bad_input_barrage_then_good_pages_still_flow(self) -> None:
        self.barrage(None)

    @needs("hypothesis")
    def test_bad_input_barrage_with_a_secret_set(self) -> None:
        self.barrage(SECRET)

    def barrage(self, secret: Optional[str]) -> None:
        writer = self.reports.writer
        if secret is not None:
            self.pair = SocketsPair(("127.0.0.1", self.port), system=SYSTEM, secret=secret)
        server = self.start_server(
            self.pair.server(),
            ReporterFactory(writer, ["good", "bad"]),
            LogForwarderFactory(writer),
        )
        steady = self.connect()  # a good connection open during the whole barrage
        say_hello(steady, secret=secret)
        send_json(steady, page("good", 1))
        self.assertEqual(self.wait_pages("good", 1), [1])

        # Several hundred well-framed but malformed bodies on one connection:
        # each is dropped, and the frames after them are still read.
        barrage = self.connect()
        say_hello(barrage, secret=secret)

        @settings(
            max_examples=300,
            deadline=None,
            database=None,
            suppress_health_check=list(HealthCheck),
        )
        @given(bad_bodies)
        def send_bad(body: bytes) -> None:
            barrage.sendall(frame(body))

        send_bad()
        host, port = barrage.getsockname()[:2]
        barrage_label = f"{host}:{port}"
        send_json(barrage, page("good", 2))
        self.assertEqual(self.wait_pages("good", 2), [1, 2])

        # Connections that break the framing itself.
        rng = random.Random(3)
        for _ in range(20):  # unframed random bytes, then hang up
            with connect(self.port) as noise:
                noise.sendall(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 200))))
        with connect(self.port) as truncated:
            truncated.sendall(frame(json.dumps(page("good", 99)).encode())[:30])
        with connect(self.port) as oversized:
            oversized.sendall((2**31).to_bytes(4, "big") + b"{}")
            self.assertTrue(is_closed_by_peer(oversized), "the server reset that connection")

        send_json(steady, page("good", 3))  # the steady connection was not disturbed
        self.assertEqual(self.wait_pages("good", 3), [1, 2, 3])
        fresh = self.connect()
        say_hello(fresh, secret=secret)
        send_json(fresh, page("good", 4))
        self.assertEqual(self.wait_pages("good", 4), [1, 2, 3, 4])
        self.assertTrue(server.process.is_alive())
        self.assertEqual(pages_of(self.reports.seen, "snr_server", "bad"), [])
        logs = [r[3] for r in self.reports.seen if r[0] == "log"]
        self.assertTrue(any(line.startswith("Bad frame from 127.0.0.1:") for line in logs))
        self.assertTrue(any("maximum frame size" in line for line in logs))
        # 300 bad frames: the first five in full, then a count every few seconds
        from_barrage = [line for line in logs if f"'foreign' at {barrage_label}" in line]
        self.assertGreaterEqual(len(from_barrage), 5)
        self.assertLessEqual(len(from_barrage), 12, from_barrage)


if __name__ == "__main__":
    unittest.main()
