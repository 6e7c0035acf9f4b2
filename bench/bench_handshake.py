"""What a secret adds to a connect: the hello alone vs. hello and proofs, on 127.0.0.1.

A plain socket client (as docs/wire-format.md describes) connects to a real SNR
sockets server N times each way and reports the median time from connect to
the server's hello (system only) or to the server's proof checked (secret).

    python bench/bench_handshake.py
"""

from __future__ import annotations

import hashlib
import hmac
import json
import logging
import os
import socket
import statistics
import threading
import time
from typing import Any, Dict, List, Optional

from snr import Config, Mode, Node, SocketsPair

__all__ = ["main"]

SYSTEM, SECRET, ROUNDS = "bench", "bench secret", 200


def _frame(obj: Dict[str, Any]) -> bytes:
    body = json.dumps(obj, separators=(",", ":")).encode()
    return len(body).to_bytes(4, "big") + body


def _recv(sock: socket.socket) -> Dict[str, Any]:
    def exactly(n: int) -> bytes:
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise ConnectionError("closed")
            data += chunk
        return data

    result: Dict[str, Any] = json.loads(exactly(int.from_bytes(exactly(4), "big")))
    return result


def _connect_once(port: int, secret: Optional[str]) -> float:
    started = time.perf_counter()
    with socket.create_connection(("127.0.0.1", port)) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        hello: Dict[str, Any] = {"v": 2, "kind": "hello", "role": "bench", "system": SYSTEM}
        nonce = os.urandom(32).hex()
        if secret is not None:
            hello["nonce"] = nonce
        sock.sendall(_frame(hello))
        theirs = _recv(sock)
        if secret is not None:
            key = secret.encode()
            mine = f"snr-proof client {nonce} {theirs['nonce']}".encode()
            sock.sendall(
                _frame(
                    {
                        "v": 2,
                        "kind": "proof",
                        "mac": hmac.new(key, mine, hashlib.sha256).hexdigest(),
                    }
                )
            )
            proof = _recv(sock)
            expected = f"snr-proof server {theirs['nonce']} {nonce}".encode()
            assert proof["mac"] == hmac.new(key, expected, hashlib.sha256).hexdigest()
        elapsed = time.perf_counter() - started
    return elapsed


def _measure(secret: Optional[str]) -> List[float]:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = int(probe.getsockname()[1])
    pair = SocketsPair(("127.0.0.1", port), system=SYSTEM, secret=secret, max_connections=1000)
    node = Node("server", Config({"server": [pair.server()]}, mode=Mode.DEPLOYED))
    thread = threading.Thread(target=node.loop, daemon=True)
    thread.start()
    for _ in range(200):
        try:
            _connect_once(port, secret)
            break
        except OSError:
            time.sleep(0.02)
    times = [_connect_once(port, secret) for _ in range(ROUNDS)]
    node.set_terminate_flag("bench done")
    thread.join(5)
    return times


def main() -> None:
    """Print the median connect-to-ready time with and without a secret."""
    logging.getLogger("snr").setLevel(logging.WARNING)  # 400 connects: no line each
    plain = statistics.median(_measure(None)) * 1000
    secret = statistics.median(_measure(SECRET)) * 1000
    print(
        f"connect to ready, median of {ROUNDS}: system only {plain:.3f} ms, "
        f"with a secret {secret:.3f} ms (+{secret - plain:.3f} ms)"
    )


if __name__ == "__main__":
    main()
