"""Comms faults as a robot meets them: a path that goes silent, a peer that stops
reading, too many connections, a connection that never speaks.

A relay in the test sits between client and server on 127.0.0.1 and can
"blackhole" the path: it keeps both connections open but passes nothing on,
as Wi-Fi out of range does (no FIN, no RST).
"""

from __future__ import annotations

import json
import logging
import selectors
import socket
import threading
import time
import unittest
from typing import Any, Dict, List, Optional

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    tasks,
)
from snr.std_mods.comms.comms_loop import CommsLoop
from snr.std_mods.comms.sockets import SocketsServerLoop
from snr.utils import MemoryLinkPair
from tests.helpers import free_port, settle_the_heap, wait_until
from tests.quiet import capture_test_logs
from tests.test_comms_local import LocalNodes, connect_when_listening


class Relay:
    """Forwards TCP between a listening port and a server; can blackhole the path."""

    def __init__(self, target_port: int) -> None:
        self.target_port = target_port
        self.listener = socket.socket()
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen()
        self.port = int(self.listener.getsockname()[1])
        self.blackhole = threading.Event()
        self.stop = threading.Event()
        self.connections = 0
        self.thread = threading.Thread(target=self._run, name="test-relay", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        selector = selectors.DefaultSelector()
        selector.register(self.listener, selectors.EVENT_READ, None)
        peers: Dict[socket.socket, socket.socket] = {}
        deadline = time.monotonic() + 30  # bounded, whatever the test does
        while not self.stop.is_set() and time.monotonic() < deadline:
            for key, _ in selector.select(0.02):
                sock = key.fileobj
                assert isinstance(sock, socket.socket)
                if sock is self.listener:
                    client, _ = self.listener.accept()
                    try:
                        server = socket.create_connection(("127.0.0.1", self.target_port))
                    except OSError:
                        client.close()
                        continue
                    self.connections += 1
                    peers[client], peers[server] = server, client
                    selector.register(client, selectors.EVENT_READ, None)
                    selector.register(server, selectors.EVENT_READ, None)
                    continue
                if self.blackhole.is_set():
                    continue  # read nothing, pass nothing on, close nothing
                try:
                    data = sock.recv(65536)
                except OSError:
                    data = b""
                other = peers.get(sock)
                if not data or other is None:
                    for end in (sock, other):
                        if end is not None and end in peers:
                            selector.unregister(end)
                            peers.pop(end)
                            end.close()
                    continue
                try:
                    other.sendall(data)
                except OSError:
                    pass
            if self.blackhole.is_set():
                time.sleep(0.01)  # the sockets stay readable: do not spin
        for sock in list(peers):
            sock.close()
        self.listener.close()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2.0)


class LogLines(logging.Handler):
    """Collects the messages logged under ``snr`` (from every thread), with times."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.lines: List[tuple[float, str]] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append((time.monotonic(), f"{record.name}: {record.getMessage()}"))

    def first(self, text: str, after: float = 0.0) -> Optional[float]:
        for when, line in list(self.lines):
            if when >= after and text in line:
                return when
        return None

    def matching(self, text: str) -> List[str]:
        return [line for _, line in list(self.lines) if text in line]


class Ticker(ThreadLoop):
    """Stores an increasing number under ``tick`` at ``hz``."""

    def __init__(self, factory: TickerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "ticker", max_tick_rate_hz=factory.hz)
        self.ticker_factory = factory

    def loop(self) -> None:
        self.store_data("tick", self.ticker_factory.sent, process=False)
        self.ticker_factory.sent += 1


class TickerFactory(LoopFactory):
    def __init__(self, hz: float) -> None:
        super().__init__()
        self.hz = hz
        self.sent = 0

    def get(self, parent: AbstractNode) -> Ticker:
        return Ticker(self, parent)


class Counter(Endpoint):
    """Counts the pages stored under a key (and can hold the node's thread once)."""

    def __init__(self, factory: CounterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counter")
        self.counter_factory = factory
        self.task_handlers = {(TaskType.store_page, factory.key): self.count}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        factory = self.counter_factory
        factory.seen.append(task.val_list[0].data)
        if factory.pause_s and len(factory.seen) == 1:
            time.sleep(factory.pause_s)  # the node is stuck: its queue fills
        return None


class CounterFactory(EndpointFactory):
    def __init__(self, key: str, pause_s: float = 0.0) -> None:
        super().__init__()
        self.key = key
        self.pause_s = pause_s
        self.seen: List[Any] = []

    def get(self, parent: AbstractNode) -> Counter:
        return Counter(self, parent)


class CommsFaultTest(unittest.TestCase):
    def setUp(self) -> None:
        capture_test_logs(self)  # the lines these tests read stay out of the run's output
        self.log = LogLines()
        snr_log = logging.getLogger("snr")
        snr_log.addHandler(self.log)
        self.addCleanup(snr_log.removeHandler, self.log)
        self.port = free_port()

    def run_nodes(self, config: Config, roles: List[str]) -> LocalNodes:
        for role in roles:  # TEST mode logs warnings only; these tests read INFO lines too
            node_log = logging.getLogger(f"snr.{role}")
            self.addCleanup(node_log.setLevel, node_log.level)
            node_log.setLevel(logging.INFO)
        nodes = LocalNodes(config, roles)
        self.addCleanup(nodes.stop)
        return nodes


class TestDeadPath(CommsFaultTest):
    def test_a_blackholed_path_is_found_on_both_sides_while_pages_flow(self) -> None:
        relay = Relay(self.port)
        self.addCleanup(relay.close)
        server = SocketsPair(("127.0.0.1", self.port), dead_after_s=0.25)
        via_relay = SocketsPair(("127.0.0.1", relay.port), dead_after_s=0.25)
        ticks = TickerFactory(hz=200)
        counter = CounterFactory("tick")
        config = Config(
            {"receiver": [server.server(), counter], "sender": [ticks, via_relay.client("tick")]},
            mode=Mode.TEST,
        )
        self.run_nodes(config, ["receiver", "sender"])
        self.assertTrue(wait_until(lambda: len(counter.seen) > 20, 5.0), "pages flow at first")

        relay.blackhole.set()
        cut = time.monotonic()
        lost = "nothing heard from it for"
        self.assertTrue(
            wait_until(lambda: len(self.log.matching(lost)) >= 2, 4.0),
            f"both sides notice; log: {self.log.matching('Lost')}",
        )
        for side in ("snr.receiver", "snr.sender"):
            line = next(line for line in self.log.matching(lost) if line.startswith(side))
            self.assertIn("pages sent since it was last heard from may be lost", line)
        found_s = max(when for when, line in self.log.lines if lost in line) - cut
        self.assertLess(found_s, 3.0, "declared lost within the bound (0.25 s of silence)")
        sender_line = next(line for line in self.log.matching(lost) if "snr.sender" in line)
        self.assertRegex(sender_line, r"; [1-9]\d* pages sent since")  # pages were in flight

        # The path comes back: the client reconnects with backoff and pages flow again.
        relay.blackhole.clear()
        before = len(counter.seen)
        self.assertTrue(wait_until(lambda: len(counter.seen) > before + 20, 6.0))
        self.assertGreaterEqual(relay.connections, 2)
        # Pages may flow before the server's hello reaches the sender, which then says so.
        self.assertTrue(
            wait_until(lambda: bool(self.log.matching("Reconnected to the sockets server")), 5.0),
            self.log.matching("sockets server"),
        )

    def test_beats_keep_a_quiet_link_alive(self) -> None:
        settle_the_heap(self)  # no collection of earlier tests' objects in the window
        pair = MemoryLinkPair(dead_after_s=0.15)  # a beat every 0.0375 s
        self.addCleanup(pair.close)
        config = Config({"a": [pair.first()], "b": [pair.second()]}, mode=Mode.TEST)
        nodes = self.run_nodes(config, ["a", "b"])
        self.assertTrue(wait_until(lambda: len(self.log.matching("Linked to node")) == 2, 5.0))
        cpu_before, wall_before = time.process_time(), time.monotonic()
        time.sleep(0.3)  # nothing is stored: only beats cross (twice the silence limit)
        cpu_share = (time.process_time() - cpu_before) / (time.monotonic() - wall_before)
        self.assertEqual(self.log.matching("Lost the link"), [])
        link = nodes.nodes[0].components["memory_link_a"]
        assert isinstance(link, CommsLoop)
        [stats] = link.stats()
        self.assertLess(stats["heard_s_ago"], 0.15)
        # Catches a spin (a whole core), not the idle figure, which bench_comms.py measures.
        self.assertLess(cpu_share, 0.15, "an idle pair with beats costs little CPU")


class TestCountersInTheProfile(CommsFaultTest):
    def test_the_profiler_dump_shows_every_link(self) -> None:
        pair = SocketsPair(("127.0.0.1", self.port), system=None)
        counter = CounterFactory("hello")
        config = Config(
            {"a": [pair.server(), counter], "b": [pair.client("hello")]}, mode=Mode.DEBUG
        )
        nodes = self.run_nodes(config, ["a", "b"])
        # Both ends linked: the client sends only once it has the server's hello.
        self.assertTrue(wait_until(lambda: bool(self.log.matching("Client node 'b'")), 5.0))
        client_linked = "onnected to the sockets server, node 'a'"
        self.assertTrue(wait_until(lambda: bool(self.log.matching(client_linked)), 5.0))
        nodes.nodes[1].store_data("hello", "world")
        self.assertTrue(wait_until(lambda: counter.seen == ["world"], 5.0))
        profiler = nodes.nodes[0].profiler
        assert profiler is not None
        dump = profiler.dump()
        self.assertIn(f"sockets_server_{self.port}:\n1 link", dump)
        self.assertRegex(dump, r"'b' at 127\.0\.0\.1:\d+ \(open\): sent 0, received 1, dropped 0")


class Flood(ThreadLoop):
    """Stores ``count`` big pages under ``flood`` as fast as it can, then ``last``."""

    def __init__(self, factory: FloodFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "flood")
        self.flood_factory = factory

    def loop(self) -> None:
        factory = self.flood_factory
        if not factory.started.is_set():
            self.wait_s(0.01)
            return
        if factory.sent == factory.count:
            self.store_data("flood", "last")
            self.set_terminate_flag("flooded")
            return
        self.store_data("flood", "x" * 20_000)
        factory.sent += 1


class FloodFactory(LoopFactory):
    def __init__(self, count: int) -> None:
        super().__init__()
        self.count = count
        self.sent = 0
        self.started = threading.Event()

    def get(self, parent: AbstractNode) -> Flood:
        return Flood(self, parent)


class BurstFlood(Endpoint):
    """Stores ``count`` big pages under ``flood``, a hundred a handler call, then ``last``.

    The pages of one call wait one behind the other: the comms link gets them
    as a burst (`CommsLoop.forward_burst`), and a full outbox must still drop
    and count them one by one.
    """

    def __init__(self, factory: BurstFloodFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "burst_flood")
        self.flood_factory = factory
        self.task_handlers = {(TaskType.event, "flood_more"): self.more}

    def begin(self) -> None:
        def start() -> None:
            self.flood_factory.started.wait(10)
            self.schedule(tasks.event("flood_more"))

        threading.Thread(target=start, daemon=True).start()

    def more(self, task: Task, key: TaskId) -> SomeTasks:
        factory = self.flood_factory
        if factory.sent == factory.count:
            return self.store_data_task("flood", "last")
        chunk = min(100, factory.count - factory.sent)
        factory.sent += chunk
        pages = [self.store_data_task("flood", "x" * 20_000) for _ in range(chunk)]
        return [*pages, tasks.event("flood_more")]


class BurstFloodFactory(FloodFactory):
    def get(self, parent: AbstractNode) -> BurstFlood:  # type: ignore[override]
        return BurstFlood(self, parent)


class Sender(ThreadLoop):
    """Stores 0, 1, 2, ... under ``tick``, ``count`` of them, once ``started`` is set."""

    def __init__(self, factory: SenderFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sender")
        self.sender_factory = factory

    def loop(self) -> None:
        factory = self.sender_factory
        if not factory.started.is_set() or factory.sent == factory.count:
            self.wait_s(0.01)
            return
        self.store_data("tick", factory.sent)
        factory.sent += 1


class SenderFactory(LoopFactory):
    def __init__(self, count: int) -> None:
        super().__init__()
        self.count = count
        self.sent = 0
        self.started = threading.Event()

    def get(self, parent: AbstractNode) -> Sender:
        return Sender(self, parent)


def frame(**fields: Any) -> bytes:
    """One frame as a plain program writes it: 4-byte big-endian length, then JSON."""
    body = json.dumps(fields).encode("utf-8")
    return len(body).to_bytes(4, "big") + body


def comms_of(node: Node) -> CommsLoop:
    """The node's one comms component."""
    [comms] = [part for part in node.components.values() if isinstance(part, CommsLoop)]
    return comms


def read_until_closed(sock: socket.socket, limit_s: float) -> bool:
    """Read (and drop) what comes until the peer closes; False if still open after ``limit_s``."""
    deadline = time.monotonic() + limit_s
    sock.settimeout(0.05)
    while time.monotonic() < deadline:
        try:
            if not sock.recv(65536):
                return True
        except socket.timeout:
            continue
        except OSError:  # reset: closed too
            return True
    return False


class TestSlowReader(CommsFaultTest):
    def test_a_paused_reader_costs_bounded_memory_and_every_drop_is_counted(self) -> None:
        self.check_a_paused_reader(FloodFactory(count=3000))

    def test_bursts_to_a_paused_reader_are_dropped_and_counted_page_by_page(self) -> None:
        self.check_a_paused_reader(BurstFloodFactory(count=3000))

    def check_a_paused_reader(self, flood: FloodFactory) -> None:
        original_quiet = CommsLoop.recovered_after_s
        CommsLoop.recovered_after_s = 0.15  # the default is 1 s
        self.addCleanup(setattr, CommsLoop, "recovered_after_s", original_quiet)
        pair = MemoryLinkPair(max_backlog_bytes=256 * 1024)
        self.addCleanup(pair.close)
        counter = CounterFactory("flood", pause_s=0.3)
        original = Node.max_queued_tasks
        Node.max_queued_tasks = 100
        self.addCleanup(setattr, Node, "max_queued_tasks", original)
        config = Config(
            {"receiver": [pair.first(), counter], "sender": [flood, pair.second("flood")]},
            mode=Mode.TEST,
        )
        nodes = self.run_nodes(config, ["receiver", "sender"])
        self.assertTrue(wait_until(lambda: len(self.log.matching("Linked to node")) == 2, 5))
        flood.started.set()
        self.assertTrue(wait_until(lambda: counter.seen[-1:] == ["last"], 15.0), "caught up")

        sender = nodes.nodes[1].components["memory_link_b"]
        assert isinstance(sender, CommsLoop)
        [stats] = sender.stats()
        dropped = stats["dropped"]
        self.assertGreater(dropped, 0, "the receiver paused for 0.3 s: some pages had to go")
        self.assertEqual(stats["dropped_by_key"], {"flood": dropped})
        self.assertEqual(len(counter.seen) + dropped, 3001, "every page arrived or was counted")
        drops = self.log.matching("Dropped")
        self.assertTrue(drops and "pages for memory-a" in drops[0], drops)
        self.assertLessEqual(len(drops), 5, "at most one line a second")
        self.assertTrue(
            wait_until(lambda: bool(self.log.matching("Recovered:")), 3.0),
            "a recovery line follows, once nothing was dropped for 0.15 s",
        )
        recovered = self.log.matching("Recovered:")
        self.assertEqual(len(recovered), 1, "one episode, one recovery line")
        self.assertIn(f"Recovered: {dropped} pages for", recovered[-1])


class TestConnectionLimits(CommsFaultTest):
    def test_connections_over_the_cap_are_refused_once_every_one_said_hello(self) -> None:
        pair = SocketsPair(("127.0.0.1", self.port), max_connections=3, system=None)
        nodes = self.run_nodes(Config({"server": [pair.server()]}, mode=Mode.TEST), ["server"])
        comms = comms_of(nodes.nodes[0])
        socks = [connect_when_listening(self.port) for _ in range(3)]
        for n, sock in enumerate(socks):
            self.addCleanup(sock.close)
            sock.settimeout(3.0)
            sock.sendall(frame(v=1, kind="hello", role=f"robot{n}"))
        said_hello = lambda: sum(1 for link in comms.links if link.peer_role) == 3  # noqa: E731
        self.assertTrue(wait_until(said_hello, 5.0), self.log.lines)
        late = [connect_when_listening(self.port) for _ in range(2)]
        for sock in late:
            self.addCleanup(sock.close)
            sock.settimeout(3.0)
        self.assertEqual([sock.recv(4) for sock in late], [b"", b""], "refused at once")
        self.assertTrue(all(sock.recv(4) for sock in socks), "the three nodes kept their links")
        refused = self.log.matching("Refused")
        self.assertTrue(refused, self.log.lines)
        self.assertIn("already has 3 clients", refused[0])
        self.assertEqual(self.log.matching("had not said hello"), [], "no node was closed")

    def test_a_node_gets_in_past_connections_that_never_said_hello(self) -> None:
        # A server held connections that never said hello and refused a real
        # node while they lasted, and the pages that node stored meanwhile
        # were lost. Now the oldest silent connection makes room for it.
        original = CommsLoop.hello_timeout_s
        CommsLoop.hello_timeout_s = 60.0  # none times out during the test: room must be made
        self.addCleanup(setattr, CommsLoop, "hello_timeout_s", original)
        cap, idle, count = 4, 12, 500
        pair = SocketsPair(("127.0.0.1", self.port), max_connections=cap, system=None)
        counter, sender = CounterFactory("tick"), SenderFactory(count)
        config = Config(
            {"server": [pair.server(), counter], "robot": [pair.client("tick"), sender]},
            mode=Mode.TEST,
        )
        server = comms_of(self.run_nodes(config, ["server"]).nodes[0])
        assert isinstance(server, SocketsServerLoop)
        holders = [connect_when_listening(self.port) for _ in range(idle)]
        for sock in holders:
            self.addCleanup(sock.close)
        self.assertTrue(wait_until(lambda: server.closed_silent.total == idle - cap, 5.0))
        robot = comms_of(self.run_nodes(config, ["robot"]).nodes[0])
        linked = lambda: any(link.peer_role == "server" for link in robot.links)  # noqa: E731
        self.assertTrue(wait_until(linked, 3.0), self.log.lines)
        sender.started.set()
        self.assertTrue(wait_until(lambda: len(counter.seen) == count, 10.0), len(counter.seen))
        self.assertEqual(counter.seen, list(range(count)), "every page, in order")
        self.assertEqual(server.closed_silent.total, idle - cap + 1, "one more made room")
        self.assertEqual(server.refused.total, 0)
        self.assertTrue(self.log.matching("connections that had not said hello"), self.log.lines)
        # Oldest first: the first holders were closed, the last ones still hold a slot.
        self.assertTrue(read_until_closed(holders[0], 2.0))
        self.assertFalse(read_until_closed(holders[-1], 0.2))

    def test_a_connection_that_never_speaks_is_closed(self) -> None:
        original = CommsLoop.hello_timeout_s
        CommsLoop.hello_timeout_s = 0.1
        self.addCleanup(setattr, CommsLoop, "hello_timeout_s", original)
        # A short silence limit makes the link check its peer every 0.025 s (else 0.25 s).
        pair = SocketsPair(("127.0.0.1", self.port), dead_after_s=0.4, system=None)
        self.run_nodes(Config({"server": [pair.server()]}, mode=Mode.TEST), ["server"])
        sock = connect_when_listening(self.port)
        self.addCleanup(sock.close)
        sock.settimeout(3.0)
        started = time.monotonic()
        received = b""
        while True:  # the hello, then the end of the stream
            chunk = sock.recv(4096)
            if not chunk:
                break
            received += chunk
        self.assertIn(b'"kind":"hello"', received)
        self.assertLess(time.monotonic() - started, 2.5)
        self.assertTrue(wait_until(lambda: bool(self.log.matching("not even a hello")), 2.0))

    def test_a_peer_that_promised_no_beats_may_stay_quiet(self) -> None:
        pair = SocketsPair(("127.0.0.1", self.port), dead_after_s=0.05, system=None)
        self.run_nodes(Config({"server": [pair.server()]}, mode=Mode.TEST), ["server"])
        sock = connect_when_listening(self.port)
        self.addCleanup(sock.close)
        body = b'{"v":1,"kind":"hello","role":"old_node"}'
        sock.sendall(len(body).to_bytes(4, "big") + body)
        time.sleep(0.12)  # over twice the silence limit
        self.assertEqual(self.log.matching("nothing heard"), [])
        sock.settimeout(0.05)
        try:
            self.assertNotEqual(sock.recv(4096), b"", "still open")
        except socket.timeout:
            pass  # nothing to read, and not closed: still open


if __name__ == "__main__":
    unittest.main()
