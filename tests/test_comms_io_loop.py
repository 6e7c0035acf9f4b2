"""One I/O thread per node: threads stay constant however many peers connect.

A server with hundreds of idle peers used to cost two threads per peer; now
every link of a node is served by its one ``snr-<role>-io`` thread.
"""

from __future__ import annotations

import functools
import logging
import multiprocessing
import socket
import sys
import threading
import time
import unittest
from typing import Any, Callable, Dict, List, Tuple, cast
from unittest import mock

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    PipeLoopFactory,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.prelude import ConfigError
from snr.std_mods.codec import encode_hello
from snr.std_mods.comms.comms_loop import CommsLoop
from snr.std_mods.comms.io_loop import IOLoop
from snr.std_mods.comms.pipe import PipeTransport
from tests.helpers import free_port, wait_until
from tests.test_comms_local import LocalNodes, connect_when_listening

IDLE_PEERS = 300

if sys.platform != "win32":  # Windows has no descriptor limit to raise
    import resource


def threads_of(role: str) -> List[str]:
    prefix = f"snr-{role}-"
    return sorted(t.name for t in threading.enumerate() if t.name.startswith(prefix))


def ensure_open_files(needed: int) -> None:
    """Raise the soft descriptor limit to ``needed``, or skip the test."""
    if sys.platform == "win32":
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft >= needed:
        return
    if hard != resource.RLIM_INFINITY and hard < needed:
        raise unittest.SkipTest(f"needs {needed} open files; the hard limit is {hard}")
    resource.setrlimit(resource.RLIMIT_NOFILE, (needed, hard))


class Latency(Endpoint):
    """Records how long each page took from being stored to arriving here."""

    def __init__(self, factory: LatencyFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "latency")
        self.latency_factory = factory
        self.task_handlers = {(TaskType.store_page, factory.key): self.arrived}

    def arrived(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        self.latency_factory.seen.append((page.data, time.time() - page.created_at_s))
        return None


class LatencyFactory(EndpointFactory):
    def __init__(self, key: str) -> None:
        super().__init__()
        self.key = key
        self.seen: List[Tuple[int, float]] = []

    def get(self, parent: AbstractNode) -> Latency:
        return Latency(self, parent)


class ErrorLines(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.lines: List[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(record.getMessage())


class TestOneIOThreadPerNode(unittest.TestCase):
    def setUp(self) -> None:
        self.errors = ErrorLines()
        logging.getLogger("snr").addHandler(self.errors)
        self.addCleanup(logging.getLogger("snr").removeHandler, self.errors)
        self.addCleanup(lambda: self.assertEqual(self.errors.lines, [], "no errors logged"))

    def test_300_idle_peers_cost_no_thread_and_pages_still_arrive_on_time(self) -> None:
        ensure_open_files(2 * IDLE_PEERS + 200)  # both ends live in this process
        port = free_port()
        pair = SocketsPair(("127.0.0.1", port), max_connections=IDLE_PEERS + 10, system=None)
        latency = LatencyFactory("tick")
        config = Config(
            {"receiver": [pair.server(), latency], "sender": [pair.client("tick")]},
            mode=Mode.TEST,
        )
        nodes = LocalNodes(config, ["receiver", "sender"])
        self.addCleanup(nodes.stop)
        receiver, sender = nodes.nodes
        server = receiver.components[f"sockets_server_{port}"]
        assert isinstance(server, CommsLoop)
        self.assertTrue(wait_until(lambda: len(server.links) == 1, 5.0), "the sender connected")
        before = threads_of("receiver")
        self.assertIn("snr-receiver-io", before)

        idle: List[socket.socket] = []
        for i in range(IDLE_PEERS):
            sock = connect_when_listening(port)
            self.addCleanup(sock.close)
            sock.sendall(encode_hello(f"idle{i}"))  # promises no beats: may stay quiet
            idle.append(sock)
            if len(idle) % 100 == 0:  # within the listen backlog (128): no SYN waits 1 s
                wait_until(lambda: len(server.links) > len(idle), 10.0)
        self.assertTrue(
            wait_until(lambda: len(server.links) == IDLE_PEERS + 1, 10.0), len(server.links)
        )
        self.assertEqual(threads_of("receiver"), before, "no thread per peer")

        for i in range(10):
            sender.schedule(tasks.store_data("tick", i))
            time.sleep(0.005)  # a pause (bursts join within 0.2 ms): each page goes alone
        self.assertTrue(wait_until(lambda: len(latency.seen) == 10, 5.0), latency.seen)
        self.assertEqual([data for data, _ in latency.seen], list(range(10)))
        slowest = max(took for _, took in latency.seen)
        self.assertLess(slowest, 1.0, "every page arrived within a second")
        for sock in idle[:5]:  # the idle peers were served too: each got the server's hello
            sock.settimeout(2.0)
            self.assertIn(b'"kind":"hello"', sock.recv(200))

        nodes.stop()
        self.assertEqual(threads_of("receiver"), [], "every thread of the node ended")
        self.assertEqual(threads_of("sender"), [])

    def test_reload_and_terminate_never_leave_a_second_io_thread(self) -> None:
        port = free_port()
        pair = SocketsPair(("127.0.0.1", port), system=None)
        config = Config({"both": [pair.server("a"), pair.client("b")]}, mode=Mode.TEST)
        # A reload of a link's component waits on the node's thread while the old
        # link says goodbye (0.25 s): LocalNodes' threshold (tests/quiet.py) allows it.
        nodes = LocalNodes(config, ["both"])
        self.addCleanup(nodes.stop)
        [node] = nodes.nodes
        server = node.components[f"sockets_server_{port}"]
        assert isinstance(server, CommsLoop)
        self.assertTrue(wait_until(lambda: len(server.links) == 1, 5.0))

        def io_threads() -> List[str]:
            return [n for n in threads_of("both") if n.endswith("-io")]

        self.assertEqual(io_threads(), ["snr-both-io"], "two comms components share one")
        most = [0]
        done = threading.Event()

        def sample() -> None:  # the most I/O threads alive at any moment of the reloads
            while not done.is_set():
                most[0] = max(most[0], len(io_threads()))
                done.wait(0.002)

        sampler = threading.Thread(target=sample, name="test-sampler")
        sampler.start()
        self.addCleanup(sampler.join)
        self.addCleanup(done.set)  # first: a failing wait must not leave it running
        names = [f"sockets_server_{port}", f"sockets_client_{port}"]

        def reconnected(old: Dict[str, Any], reloaded: List[str]) -> bool:
            now = node.components[names[0]]
            return (
                all(node.components[name] is not old[name] for name in reloaded)
                and isinstance(now, CommsLoop)
                and len(now.links) == 1
            )

        for reload in (names[0], names[1], "all"):
            old = dict(node.components)
            node.schedule(tasks.reload_component(reload))
            # "all" rebuilds only components with modules to reload: none here.
            reloaded = [] if reload == "all" else [reload]
            self.assertTrue(
                wait_until(functools.partial(reconnected, old, reloaded), 5.0),
                f"the link is up again after reloading {reload}",
            )
        done.set()
        sampler.join()
        self.assertEqual(most[0], 1, "never a second I/O thread")
        self.assertEqual(io_threads(), ["snr-both-io"])
        nodes.stop()
        self.assertEqual(threads_of("both"), [], "the I/O thread ended with its node")


class QuietNode:
    """Just what an `IOLoop` asks of its node."""

    role = "quiet"

    def wait_for_room(self, timeout_s: float) -> bool:
        return True


class RingsWhileDrained:
    """The loop's wake-up socket; runs ``during`` once, in the middle of a drain."""

    def __init__(self, sock: socket.socket, during: Callable[[], None]) -> None:
        self.sock = sock
        self.during: Callable[[], None] = during

    def recv(self, size: int) -> bytes:
        during, self.during = self.during, lambda: None
        during()
        return self.sock.recv(size)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.sock, name)


class TestWakingTheIOThread(unittest.TestCase):
    """A call from another thread runs at once, however it meets the loop's wake-up."""

    def new_loop(self) -> IOLoop:
        loop = IOLoop(cast(AbstractNode, QuietNode()))  # no links, so no timers
        self.addCleanup(loop.stop)
        return loop

    def test_a_call_made_while_the_loop_drains_its_wake_ups_does_not_mute_later_calls(
        self,
    ) -> None:
        # The interleaving a reconnecting client met: another thread rings
        # just as the loop drains the wake-up socket. Every later call must
        # still wake the loop (it has no timer to wake it otherwise).
        loop = self.new_loop()
        ran: List[str] = []
        loop._wake_r = RingsWhileDrained(  # type: ignore[assignment]
            loop._wake_r, lambda: loop.call_soon(lambda: ran.append("during the drain"))
        )
        loop._thread.start()
        loop.call_soon(lambda: ran.append("first"))
        self.assertTrue(wait_until(lambda: len(ran) == 2, 1.0), ran)
        for n in range(3):
            done = threading.Event()
            loop.call_soon(done.set)
            self.assertTrue(done.wait(1.0), f"call {n} after the drain ran within 1 s")

    def test_calls_from_many_threads_each_run_within_a_second(self) -> None:
        loop = self.new_loop()
        loop._thread.start()
        late: List[int] = []

        def caller() -> None:
            for n in range(2000):
                done = threading.Event()
                loop.call_soon(done.set)
                if not done.wait(1.0):
                    late.append(n)
                    return

        callers = [threading.Thread(target=caller) for _ in range(4)]
        for thread in callers:
            thread.start()
        for thread in callers:
            thread.join(30.0)
        self.assertEqual(late, [], "calls that waited over 1 s for the I/O thread")


class TestCtrlCWhileIdle(unittest.TestCase):
    def test_ctrl_c_in_the_idle_wait_gives_the_read_role_back(self) -> None:
        # Ctrl-C lands while the node's thread sleeps in wait(), holding the
        # read role: woken() does not come, yet the I/O thread must still get
        # the role to close the links, or the node's stop hangs.
        loop = IOLoop(cast(AbstractNode, QuietNode()))
        self.addCleanup(loop.stop)
        if not loop.node_reads:
            self.skipTest("the node's thread reads only where epoll is")
        loop._thread.start()

        def ctrl_c(epoll: Any, timeout_s: float) -> List[Tuple[int, int]]:
            raise KeyboardInterrupt

        with mock.patch("snr.std_mods.comms.io_loop._poll", ctrl_c):
            with self.assertRaises(KeyboardInterrupt):
                loop.wait(1.0)
        loop.woken()  # as the queue's finally calls it
        got = threading.Event()

        def close_a_link() -> None:
            with loop.read_role():
                got.set()

        threading.Thread(target=close_a_link, daemon=True).start()
        self.assertTrue(got.wait(2.0), "another thread took the read role")


class TestPipeTransport(unittest.TestCase):
    def test_the_bridge_for_pipes_that_are_not_sockets_carries_bytes_both_ways(self) -> None:
        here, there = multiprocessing.Pipe()
        ends = PipeTransport(here, bridge=True), PipeTransport(there, bridge=True)
        self.assertTrue(all(end.bridged for end in ends))
        for sender, receiver in (ends, ends[::-1]):
            self.assertEqual(sender.send(b"frame bytes"), 11)
            buffer = bytearray(64)
            got = b""
            deadline = time.monotonic() + 2.0
            while got != b"frame bytes" and time.monotonic() < deadline:
                try:
                    got += buffer[: receiver.recv_into(buffer)]
                except BlockingIOError:
                    time.sleep(0.01)
            self.assertEqual(got, b"frame bytes")
        for end in ends:
            end.close()
        self.assertEqual([t for t in threading.enumerate() if t.name.startswith("snr-pipe")], [])

    def test_a_duplex_pipe_is_served_as_a_socket(self) -> None:
        here, there = multiprocessing.Pipe()
        end = PipeTransport(here)
        self.addCleanup(there.close)
        self.addCleanup(end.close)
        self.assertFalse(end.bridged)

    def test_a_one_way_pipe_is_refused_with_the_fix(self) -> None:
        reader, writer = multiprocessing.Pipe(duplex=False)
        self.addCleanup(reader.close)
        self.addCleanup(writer.close)
        with self.assertRaises(ConfigError) as ctx:
            PipeLoopFactory(reader, "a")
        self.assertIn("multiprocessing.Pipe()", str(ctx.exception))


if __name__ == "__main__":
    unittest.main()
