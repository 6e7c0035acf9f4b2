"""A node that stops in order says goodbye, so its peers do not report a lost link.

The bye frame (docs/wire-format.md, section 3.4) goes only to a peer whose
hello said it understands one: an older node sees just the connection close.
"""

from __future__ import annotations

import logging
import socket
import unittest
from typing import List

from snr import Config, Mode, SocketsPair
from snr.prelude import WireFormatError
from snr.std_mods.codec import HEADER_BYTES, Bye, Hello, decode_body, encode_bye
from snr.std_mods.comms.comms_loop import CommsLoop
from tests.helpers import free_port, wait_until
from tests.test_comms_local import LocalNodes, connect_when_listening


def read_to_end(sock: socket.socket) -> bytes:
    """Everything the peer sends until it closes (bounded by the socket's timeout)."""
    sock.settimeout(5)
    received = b""
    for _ in range(1000):
        chunk = sock.recv(4096)
        if not chunk:
            break
        received += chunk
    return received


def frame(body: bytes) -> bytes:
    return len(body).to_bytes(4, "big") + body


class TestByeFrame(unittest.TestCase):
    def test_bye_and_the_hello_field_round_trip(self) -> None:
        self.assertEqual(encode_bye()[HEADER_BYTES:], b'{"v":1,"kind":"bye"}')
        self.assertEqual(decode_body(encode_bye()[HEADER_BYTES:]), Bye())
        hello = decode_body(b'{"v":1,"kind":"hello","role":"r","beat_s":1.0,"bye":true}')
        self.assertEqual(hello, Hello("r", 1.0, bye=True))
        self.assertEqual(decode_body(b'{"v":1,"kind":"hello","role":"r"}'), Hello("r"))

    def test_a_bye_field_that_is_not_a_bool_is_rejected(self) -> None:
        for value in [b"1", b'"yes"', b"null"]:
            with self.subTest(value=value), self.assertRaises(WireFormatError) as ctx:
                decode_body(b'{"v":1,"kind":"hello","role":"r","bye":%s}' % value)
            self.assertIn("'bye'", str(ctx.exception))


class TestGoodbyeBetweenNodes(unittest.TestCase):
    """Two real nodes, urov (server) and topside (client), on threads over 127.0.0.1."""

    def setUp(self) -> None:
        pair = SocketsPair(("127.0.0.1", free_port()))
        self.server = pair.server()
        self.client = pair.client()
        config = Config({"urov": [self.server], "topside": [self.client]}, mode=Mode.TEST)
        self.nodes = LocalNodes(config, ["urov", "topside"])
        self.addCleanup(self.nodes.stop)
        urov, topside = self.nodes.nodes
        server_loop = urov.components[self.server.name]
        client_loop = topside.components[self.client.name]
        assert isinstance(server_loop, CommsLoop)
        assert isinstance(client_loop, CommsLoop)
        self.server_loop, self.client_loop = server_loop, client_loop

    def linked(self) -> bool:
        return all(
            loop.links and all(link.peer_role for link in loop.links)
            for loop in (self.server_loop, self.client_loop)
        )

    def test_an_orderly_stop_is_no_warning_on_the_other_side(self) -> None:
        self.assertTrue(wait_until(self.linked), "the nodes never linked")
        link = self.client_loop.links[0]
        with self.assertLogs("snr.topside", logging.INFO) as logs:
            self.nodes.nodes[0].set_terminate_flag("done")  # urov stops in order
            self.nodes.threads[0].join(5)
            self.assertTrue(wait_until(link.is_closed), "the link did not end")
            self.assertTrue(wait_until(lambda: bool(goodbyes(logs.output))))
        self.assertTrue(link.peer_said_bye)
        warnings = [line for line in logs.output if not line.startswith(("INFO", "DEBUG"))]
        self.assertEqual(warnings, [])
        self.assertIn("The sockets server 'urov'", goodbyes(logs.output)[0])
        self.assertFalse(self.nodes.nodes[1].is_terminated(), "topside keeps running")

    def test_an_abrupt_end_still_warns(self) -> None:
        self.assertTrue(wait_until(self.linked), "the nodes never linked")
        link = self.client_loop.links[0]
        with self.assertLogs("snr.topside", logging.WARNING) as logs:
            self.server_loop.links[0].abort()  # no goodbye: as if urov had crashed
            self.assertTrue(wait_until(link.is_closed), "the link did not end")
        self.assertFalse(link.peer_said_bye)
        self.assertIn("Lost the link to the sockets server 'urov'", logs.output[0])


def goodbyes(lines: List[str]) -> List[str]:
    return [line for line in lines if "said goodbye" in line]


class TestGoodbyeToOtherPrograms(unittest.TestCase):
    def test_only_a_peer_that_understands_bye_is_sent_one(self) -> None:
        port = free_port()
        server = SocketsPair(("127.0.0.1", port), system=None).server()
        nodes = LocalNodes(Config({"urov": [server]}, mode=Mode.TEST), ["urov"])
        self.addCleanup(nodes.stop)
        old = connect_when_listening(port)  # an older SNR node: its hello has no "bye"
        new = connect_when_listening(port)
        for sock in (old, new):
            self.addCleanup(sock.close)
        old.sendall(frame(b'{"v":1,"kind":"hello","role":"old"}'))
        new.sendall(frame(b'{"v":1,"kind":"hello","role":"new","bye":true}'))
        loop = nodes.nodes[0].components[server.name]
        assert isinstance(loop, CommsLoop)
        heard = wait_until(
            lambda: sorted(str(link.peer_role) for link in loop.links) == ["new", "old"]
        )
        self.assertTrue(heard, "the server never read both hellos")
        nodes.stop()
        to_old, to_new = read_to_end(old), read_to_end(new)
        self.assertTrue(to_old.startswith(b"\x00\x00\x00"), to_old)  # its hello
        self.assertNotIn(b'"kind":"bye"', to_old)
        self.assertTrue(to_new.endswith(encode_bye()), to_new)  # the last frame, then the end


if __name__ == "__main__":
    unittest.main()
