"""Comms against peers that misbehave on purpose: odd hellos, trickled bytes,
a server that hangs up at once, a reader that stops and then vanishes.

Each peer here is a raw socket on 127.0.0.1 written by the test, so it can say
what no SNR node would; the node under test must lose nothing it was given,
close what only holds a connection, and log it all briefly.
"""

from __future__ import annotations

import re
import socket
import threading
import time
import unittest
from typing import Any, List

from snr import Config, Mode, Node, SocketsPair
from snr.std_mods.comms.comms_loop import CommsLoop, shown_role
from snr.std_mods.comms.io_loop import unread_bytes
from tests.helpers import wait_until
from tests.test_comms_liveness import (
    CommsFaultTest,
    CounterFactory,
    FloodFactory,
    comms_of,
    frame,
    read_until_closed,
)
from tests.test_comms_local import connect_when_listening


def page(key: str, data: Any) -> bytes:
    return frame(v=1, kind="page", key=key, data=data, origin="tool", created_at_s=1.0)


def connect_with_small_buffer(port: int) -> socket.socket:
    """A client whose receive buffer is small, so that a peer's frames soon back up."""
    for _ in range(100):
        sock = socket.socket()
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        try:
            sock.connect(("127.0.0.1", port))
            return sock
        except ConnectionRefusedError:
            sock.close()
            time.sleep(0.02)
    raise AssertionError(f"nothing listens on port {port}")


class Trickler:
    """Sends one byte every 0.02 s on ``sock`` until stopped or the socket breaks (at most 5 s)."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="test-trickler", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        for _ in range(250):
            if self.stop.wait(0.02):
                return
            try:
                self.sock.send(b"x")
            except OSError:
                return

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2.0)


class TestOddHellos(CommsFaultTest):
    def serve(self, counter: CounterFactory, **options: Any) -> socket.socket:
        pair = SocketsPair(("127.0.0.1", self.port), **{"system": None, **options})
        self.nodes = self.run_nodes(
            Config({"server": [pair.server(), counter]}, mode=Mode.TEST), ["server"]
        )
        sock = connect_when_listening(self.port)
        self.addCleanup(sock.close)
        return sock

    def server_links(self) -> List[Any]:
        return list(comms_of(self.nodes.nodes[0]).links)

    def test_a_hello_with_a_huge_beat_is_a_bad_frame_and_the_pages_behind_it_arrive(self) -> None:
        counter = CounterFactory("tick")
        sock = self.serve(counter)
        hello = frame(v=1, kind="hello", role="tool", beat_s=10**400)
        sock.sendall(hello + page("tick", 0) + page("tick", 1) + page("tick", 2))
        self.assertTrue(wait_until(lambda: len(counter.seen) == 3, 5.0), self.log.lines)
        self.assertEqual(counter.seen, [0, 1, 2])
        [bad] = self.log.matching("Bad frame")
        self.assertIn("'beat_s' is a whole number too large for a double", bad)
        sock.sendall(page("tick", 3))  # the connection is still open
        self.assertTrue(wait_until(lambda: len(counter.seen) == 4, 5.0))

    def test_the_pages_before_a_bad_length_header_are_stored_then_the_link_resets(self) -> None:
        counter = CounterFactory("tick")
        sock = self.serve(counter)
        too_long = (2**31).to_bytes(4, "big") + b"{}"
        # One chunk: the link cuts the two pages, then meets the length it cannot trust.
        sock.sendall(
            frame(v=1, kind="hello", role="tool") + page("tick", 0) + page("tick", 1) + too_long
        )
        self.assertTrue(wait_until(lambda: len(counter.seen) == 2, 5.0), self.log.lines)
        self.assertEqual(counter.seen, [0, 1])
        self.assertTrue(read_until_closed(sock, 5.0), "the node reset the connection")
        [reset] = self.log.matching("Bad frame")
        self.assertIn("over the 16,777,216-byte maximum frame size (reset the connection", reset)

    def test_a_second_hello_changes_nothing_and_is_logged_briefly(self) -> None:
        counter = CounterFactory("tick")
        sock = self.serve(counter)
        hellos = [frame(v=1, kind="hello", role="tool")]
        hellos += [frame(v=1, kind="hello", role="intruder")] * 30
        hellos += [frame(v=1, kind="hello", role="tool")] * 30
        sock.sendall(b"".join(hellos) + page("tick", "after"))
        self.assertTrue(wait_until(lambda: counter.seen == ["after"], 5.0), self.log.lines)
        [link] = self.server_links()
        self.assertEqual(link.peer_role, "tool", "the first hello names the connection")
        self.assertEqual(link.bad_frames, 30, "each hello naming another role is a bad frame")
        self.assertEqual(len(self.log.matching("Client node")), 1, "one line for the hello")
        said = self.log.matching("a second hello, from role 'intruder'")
        self.assertTrue(1 <= len(said) <= 5, said)

    def test_a_huge_role_is_cut_short_in_every_log_line(self) -> None:
        counter = CounterFactory("tick")
        sock = self.serve(counter)
        role = "r" * 1_000_000
        sock.sendall(frame(v=1, kind="hello", role=role) + page("tick", 1))
        self.assertTrue(wait_until(lambda: bool(self.log.matching("Client node")), 5.0))
        [link] = self.server_links()
        self.assertEqual(link.peer_role, role, "the role itself is kept whole")
        longest = max(len(line) for _, line in self.log.lines)
        self.assertLess(longest, 400, "no log line copies the megabyte")
        self.assertIn("(1,000,000 characters)", self.log.matching("Client node")[0])

    def test_a_flood_of_connections_is_logged_in_brief(self) -> None:
        counter = CounterFactory("tick")
        sock = self.serve(counter)
        sock.close()
        for n in range(40):  # hello, goodbye, forty times
            with connect_when_listening(self.port) as client:
                client.sendall(frame(v=1, kind="hello", role=f"churn{n}"))
                read_until_closed(client, 0.0)  # no wait: close at once
        comms = comms_of(self.nodes.nodes[0])
        self.assertTrue(wait_until(lambda: comms.closed_totals["links"] == 41, 5.0))
        self.nodes.stop()  # the node's last words count what was not said
        connected = self.log.matching("Client node")
        self.assertEqual(len(connected), 20, "twenty in 10 s in full, then counted")
        [count] = self.log.matching("Clients connected:")
        self.assertIn("Clients connected: 20 more in the last", count)
        self.assertLessEqual(len(self.log.matching("disconnected")), 22)

    def test_bad_frames_from_many_connections_are_logged_in_brief(self) -> None:
        counter = CounterFactory("tick")
        first = self.serve(counter)
        clients = [first] + [connect_when_listening(self.port) for _ in range(29)]
        for client in clients[1:]:
            self.addCleanup(client.close)
        junk = b"".join(len(b).to_bytes(4, "big") + b for b in (b"{", b"[1]", b'{"v":9}'))
        for client in clients:
            client.sendall(junk)
        comms = comms_of(self.nodes.nodes[0])
        self.assertTrue(wait_until(lambda: sum(link.bad_frames for link in comms.links) == 90, 5.0))
        self.nodes.stop()
        in_full = self.log.matching("Bad frame from")
        self.assertEqual(len(in_full), 5, "five in full for the whole component, not per link")
        [count] = self.log.matching("Bad frames:")
        self.assertIn("Bad frames: 85 more in the last", count)

    def test_a_class_of_robots_connecting_is_logged_robot_by_robot(self) -> None:
        counter = CounterFactory("tick")
        first = self.serve(counter)
        robots = [first] + [connect_when_listening(self.port) for _ in range(11)]
        for n, robot in enumerate(robots):
            self.addCleanup(robot.close)
            robot.sendall(frame(v=1, kind="hello", role=f"robot{n}"))
        self.assertTrue(wait_until(lambda: len(self.log.matching("Client node")) == 12, 5.0))
        for n in range(12):
            self.assertTrue(self.log.matching(f"Client node 'robot{n}' connected"), n)

    def test_shown_role_quotes_short_roles_as_they_are(self) -> None:
        self.assertEqual(shown_role("urov"), "'urov'")
        self.assertEqual(shown_role("x" * 61), f"{'x' * 60!r}… (61 characters)")


class TestConnectionsThatOnlyHoldASlot(CommsFaultTest):
    def serve(self, dead_after_s: float) -> socket.socket:
        original = CommsLoop.hello_timeout_s
        CommsLoop.hello_timeout_s = 0.1
        self.addCleanup(setattr, CommsLoop, "hello_timeout_s", original)
        pair = SocketsPair(("127.0.0.1", self.port), dead_after_s=dead_after_s, system=None)
        self.run_nodes(Config({"server": [pair.server()]}, mode=Mode.TEST), ["server"])
        sock = connect_when_listening(self.port)
        self.addCleanup(sock.close)
        return sock

    def test_bytes_that_never_make_a_frame_are_no_hello(self) -> None:
        sock = self.serve(dead_after_s=0.4)
        sock.sendall((1000).to_bytes(4, "big"))  # a frame of 1,000 bytes is coming...
        trickle = Trickler(sock)  # ...one byte at a time
        self.addCleanup(trickle.close)
        self.assertTrue(read_until_closed(sock, 3.0), "the server closed the connection")
        self.assertTrue(wait_until(lambda: bool(self.log.matching("not even a hello")), 2.0))

    def test_a_trickle_after_the_hello_is_no_sign_of_life(self) -> None:
        sock = self.serve(dead_after_s=0.25)
        sock.sendall(frame(v=1, kind="hello", role="trickler", beat_s=0.05))
        sock.sendall((1000).to_bytes(4, "big"))
        trickle = Trickler(sock)
        self.addCleanup(trickle.close)
        self.assertTrue(read_until_closed(sock, 3.0), "the server closed the connection")
        heard = "nothing heard from it for"
        self.assertTrue(wait_until(lambda: self.log.matching(heard), 2.0), self.log.lines)
        self.assertIn("'trickler'", self.log.matching(heard)[0])


class TestAReceiverThatIsBehind(CommsFaultTest):
    def test_a_peer_that_falls_silent_is_found_while_the_node_is_still_behind(self) -> None:
        original = Node.max_queued_tasks
        Node.max_queued_tasks = 2  # two waiting tasks and the link stops reading
        self.addCleanup(setattr, Node, "max_queued_tasks", original)
        counter = CounterFactory("tick", pause_s=1.5)  # the first page holds the node
        pair = SocketsPair(("127.0.0.1", self.port), dead_after_s=0.25, system=None)
        nodes = self.run_nodes(
            Config({"server": [pair.server(), counter]}, mode=Mode.TEST), ["server"]
        )
        sock = connect_when_listening(self.port)
        self.addCleanup(sock.close)
        sock.sendall(frame(v=1, kind="hello", role="sender", beat_s=0.05) + page("tick", 0))
        self.assertTrue(wait_until(lambda: counter.seen == [0], 5.0), "the node is stuck")
        sock.sendall(b"".join(page("tick", n) for n in range(1, 6)))  # the queue fills
        [link] = comms_of(nodes.nodes[0]).links
        self.assertTrue(wait_until(lambda: link.pages_received == 6, 5.0))
        sock.sendall(page("tick", 6))  # read, held: the link pauses
        self.assertTrue(wait_until(lambda: bool(link._held), 5.0))
        silent_since = time.monotonic()  # and the peer says nothing more, beats included
        heard = "nothing heard from it for"
        self.assertTrue(wait_until(lambda: self.log.matching(heard), 1.2), self.log.lines)
        self.assertLess(self.log.first(heard) or 0.0, silent_since + 1.2, "within the bound")
        self.assertEqual(counter.seen, [0], "found while the node was still behind")


class SlowWriter:
    """Writes ``data`` in 8 KiB pieces every 0.03 s (about 270 KiB/s, slow Wi-Fi) on a thread."""

    def __init__(self, sock: socket.socket, data: bytes) -> None:
        self.sock, self.data = sock, data
        self.thread = threading.Thread(target=self._run, name="test-slow-writer", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        for start in range(0, len(self.data), 8192):  # bounded by the data
            try:
                self.sock.sendall(self.data[start : start + 8192])
            except OSError:
                return
            time.sleep(0.03)


class TestABigPageOnASlowLink(CommsFaultTest):
    """A frame that takes many silence limits to arrive is still a live peer's."""

    def serve(self, counter: CounterFactory) -> socket.socket:
        original = CommsLoop.hello_timeout_s
        CommsLoop.hello_timeout_s = 0.25
        self.addCleanup(setattr, CommsLoop, "hello_timeout_s", original)
        pair = SocketsPair(("127.0.0.1", self.port), dead_after_s=0.25, system=None)
        self.run_nodes(Config({"server": [pair.server(), counter]}, mode=Mode.TEST), ["server"])
        sock = connect_when_listening(self.port)
        self.addCleanup(sock.close)
        return sock

    def test_a_big_page_after_the_hello_arrives(self) -> None:
        counter = CounterFactory("image")
        sock = self.serve(counter)
        hello = frame(v=1, kind="hello", role="camera", beat_s=0.05)
        writer = SlowWriter(sock, hello + page("image", "x" * 300_000))  # about 1.1 s
        self.assertTrue(wait_until(lambda: len(counter.seen) == 1, 5.0), self.log.lines)
        writer.thread.join(2.0)
        self.assertEqual(self.log.matching("nothing heard"), [])

    def test_a_big_first_page_without_a_hello_arrives(self) -> None:
        counter = CounterFactory("image")
        sock = self.serve(counter)
        writer = SlowWriter(sock, page("image", "x" * 300_000))
        self.assertTrue(wait_until(lambda: len(counter.seen) == 1, 5.0), self.log.lines)
        writer.thread.join(2.0)
        self.assertEqual(self.log.matching("not even a hello"), [])


class TestAServerThatHangsUp(CommsFaultTest):
    def test_a_client_backs_off_from_a_server_that_hangs_up_at_once(self) -> None:
        listener = socket.socket()
        listener.bind(("127.0.0.1", 0))
        listener.listen(64)
        listener.settimeout(0.05)
        self.addCleanup(listener.close)
        accepted = 0
        window_s = 0.8

        def hang_up_on_everyone() -> None:
            nonlocal accepted
            deadline = time.monotonic() + window_s
            while time.monotonic() < deadline:
                try:
                    sock, _ = listener.accept()
                except socket.timeout:
                    continue
                accepted += 1
                sock.close()

        pair = SocketsPair(("127.0.0.1", int(listener.getsockname()[1])), system=None)
        server = threading.Thread(target=hang_up_on_everyone, daemon=True)
        server.start()
        self.run_nodes(Config({"client": [pair.client()]}, mode=Mode.TEST), ["client"])
        server.join(window_s + 2.0)
        # Tries at 0, 0.05, 0.15, 0.35 and 0.75 s; without backoff it was thousands.
        self.assertGreaterEqual(accepted, 2)
        self.assertLessEqual(accepted, 8)


class TestDropsBeforeALinkEnds(CommsFaultTest):
    def test_drops_just_before_a_link_ends_are_said_and_kept(self) -> None:
        pair = SocketsPair(("127.0.0.1", self.port), max_backlog_bytes=64 * 1024, system=None)
        flood = FloodFactory(count=600)  # 12 MB of pages for a reader that takes none
        nodes = self.run_nodes(
            Config({"server": [pair.server("flood"), flood]}, mode=Mode.TEST), ["server"]
        )
        sock = connect_with_small_buffer(self.port)
        self.addCleanup(sock.close)
        sock.sendall(frame(v=1, kind="hello", role="slow_tool"))
        self.assertTrue(wait_until(lambda: bool(self.log.matching("Client node")), 5.0))
        flood.started.set()
        self.assertTrue(wait_until(lambda: bool(self.log.matching("Dropped")), 10.0))
        sock.close()  # unread bytes: the server's side sees a reset
        said = "before the link ended"
        self.assertTrue(wait_until(lambda: bool(self.log.matching(said)), 5.0), self.log.lines)
        [line] = self.log.matching(said)
        pattern = r"Dropped (\d+) more pages for 127.0.0.1:\d+ before the link ended \((\d+) over"
        match = re.search(pattern, line)
        assert match is not None, line
        comms = comms_of(nodes.nodes[0])
        self.assertTrue(wait_until(lambda: comms.closed_totals["links"] == 1, 2.0))
        # The drops not yet said, then the episode; the closed link's counters are kept.
        said_before = sum(
            int(m.group(1))
            for m in map(re.compile(r"Dropped (\d+) pages").search, self.log.matching("Dropped"))
            if m is not None
        )
        self.assertEqual(said_before + int(match.group(1)), int(match.group(2)))
        self.assertEqual(comms.closed_totals["dropped"], int(match.group(2)))
        self.assertIn(f"1 closed: sent {comms.closed_totals['pages_sent']:,}", comms.stats_text())


class TestUnreadBytes(unittest.TestCase):
    def test_it_counts_what_waits_in_the_os(self) -> None:
        one, other = socket.socketpair()
        self.addCleanup(one.close)
        self.addCleanup(other.close)
        if unread_bytes(one.fileno()) is None:
            self.skipTest("this OS cannot say how many bytes wait")
        self.assertEqual(unread_bytes(one.fileno()), 0)
        other.sendall(b"hello")
        self.assertTrue(wait_until(lambda: unread_bytes(one.fileno()) == 5, 2.0))
        one.recv(5)
        self.assertEqual(unread_bytes(one.fileno()), 0)


if __name__ == "__main__":
    unittest.main()
