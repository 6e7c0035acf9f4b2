"""Sockets comms inside one process: errors, shutdown, page fidelity, listing 5.3."""

from __future__ import annotations

import enum
import socket
import threading
import time
import unittest
from typing import Any, List, Optional, Sequence
from unittest import mock

from snr import (
    COMMS_CONNECTED,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    Node,
    Page,
    SNRTestCase,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    TimeoutLoopFactory,
    tasks,
)
from snr.prelude import CommsError, ConfigError
from tests.comms_helpers import StopAfterFactory
from tests.helpers import free_port
from tests.quiet import SLOW_HANDLER_S, capture_test_logs

PAGE = Page("pose", {"x": 1.5, "tags": ["a", "b"]}, "robot", 1234.5, process=False)


class StoreOnConnect(Endpoint):
    """Returns the factory's tasks the first time a link opens."""

    def __init__(self, factory: StoreOnConnectFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "store_on_connect")
        self.to_store = factory.to_store
        self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.on_connected}

    def on_connected(self, task: Task, key: TaskId) -> SomeTasks:
        out, self.to_store = self.to_store, []
        return out


class StoreOnConnectFactory(EndpointFactory):
    def __init__(self, to_store: List[Task]) -> None:
        super().__init__()
        self.to_store = to_store

    def get(self, parent: AbstractNode) -> StoreOnConnect:
        return StoreOnConnect(self, parent)


def snr_threads() -> List[str]:
    return [t.name for t in threading.enumerate() if t.name.startswith("snr-") and t.is_alive()]


def connect_when_listening(port: int) -> socket.socket:
    for _ in range(100):
        try:
            return socket.create_connection(("127.0.0.1", port), timeout=5)
        except ConnectionRefusedError:
            time.sleep(0.02)
    raise AssertionError(f"nothing listens on port {port}")


class LocalNodes:
    """Runs nodes on threads of this process; stops and joins them all."""

    def __init__(self, config: Config, roles: Sequence[str]) -> None:
        self.nodes = [Node(role, config) for role in roles]
        for node in self.nodes:  # quick handlers, but on a busy machine (tests/quiet.py)
            node.slow_handler_s = SLOW_HANDLER_S
        self.errors: List[BaseException] = []
        self.threads = [
            threading.Thread(target=self._run, args=(node,), name=f"test-{node.role}")
            for node in self.nodes
        ]
        for thread in self.threads:
            thread.start()

    def _run(self, node: Node) -> None:
        try:
            node.loop()
        except BaseException as error:
            self.errors.append(error)

    def wait_first(self, timeout_s: float = 8.0) -> Node:
        """Wait for the first node (the receiver) to stop by itself."""
        self.threads[0].join(timeout_s)
        return self.nodes[0]

    def stop(self) -> None:
        for node in self.nodes:
            node.set_terminate_flag("test over")
        deadline = time.monotonic() + 8.0
        for thread in self.threads:
            thread.join(max(0.0, deadline - time.monotonic()))


class TestLocalSockets(SNRTestCase):
    def setUp(self) -> None:
        self.port = free_port()
        self.pair = SocketsPair(server_tuple=("127.0.0.1", self.port))
        # The receiver stops first: the sender may warn that it lost the link.
        capture_test_logs(self, "snr.sender")

    def run_pair(
        self, receiver: Sequence[Any], sender: Sequence[Any], mode: Mode = Mode.TEST
    ) -> LocalNodes:
        safety = TimeoutLoopFactory(seconds=8)
        config = Config(
            {"receiver": [*receiver, safety], "sender": [*sender, safety]},
            mode=mode,
        )
        nodes = LocalNodes(config, ["receiver", "sender"])
        self.addCleanup(nodes.stop)
        return nodes

    def test_the_stored_page_arrives_exactly_with_its_fields(self) -> None:
        nodes = self.run_pair(
            [self.pair.server(), StopAfterFactory("pose", on_store=True)],
            [self.pair.client(["pose"]), StoreOnConnectFactory([tasks.store_page(PAGE)])],
        )
        receiver = nodes.wait_first()
        self.assertEqual(receiver.terminate_reason, "got pose")
        self.assertEqual(receiver.get_page("pose"), PAGE)
        nodes.stop()
        self.assertEqual(nodes.errors, [])

    def test_data_that_is_not_json_is_logged_and_dropped(self) -> None:
        bad = tasks.store_page(Page("pose", {1, 2}, "robot", 1.0))
        with self.assertLogs("snr.sender", "ERROR") as logs:
            nodes = self.run_pair(
                [self.pair.server(), StopAfterFactory("pose", on_store=True)],
                [self.pair.client("pose"), StoreOnConnectFactory([bad, tasks.store_page(PAGE)])],
            )
            nodes.wait_first()
        self.assertEqual(nodes.nodes[0].get_page("pose"), PAGE, "the next page still went")
        message = "\n".join(logs.output)
        self.assertIn("'pose'", message)
        self.assertIn("set", message)
        nodes.stop()
        self.assertEqual(nodes.errors, [], "neither node died")

    def test_shutdown_closes_every_socket_and_thread(self) -> None:
        nodes = self.run_pair(
            [self.pair.server(["b"]), StopAfterFactory("a", on_store=True)],
            [self.pair.client(["a"]), StoreOnConnectFactory([tasks.store_data("a", 1)])],
        )
        self.assertTrue(nodes.wait_first().is_terminated())
        nodes.stop()
        self.assertEqual(snr_threads(), [])
        with socket.socket() as again:  # the port is free again at once
            again.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            again.bind(("127.0.0.1", self.port))

    def test_stopping_does_not_wait_on_a_silent_peer(self) -> None:
        # A raw client that connects and then never sends nor closes.
        config = Config({"receiver": [self.pair.server()]}, mode=Mode.TEST)
        nodes = LocalNodes(config, ["receiver"])
        self.addCleanup(nodes.stop)
        with connect_when_listening(self.port) as raw:
            self.assertEqual(len(raw.recv(4)), 4)  # the hello's header
            started = time.monotonic()
            nodes.stop()
            self.assertFalse(nodes.threads[0].is_alive())
            self.assertLess(time.monotonic() - started, 4.0)
            raw.settimeout(5)
            rest = raw.recv(1000)
            self.assertTrue(rest.startswith(b'{"v":2,"kind":"hello"'))
            self.assertEqual(raw.recv(1000), b"", "the node closed its end")
        self.assertEqual(snr_threads(), [])

    def test_port_in_use_names_the_port_and_the_role(self) -> None:
        with socket.socket() as squatter:
            squatter.bind(("127.0.0.1", self.port))
            squatter.listen()
            config = Config({"receiver": [self.pair.server()]}, mode=Mode.TEST)
            with self.assertRaises(CommsError) as ctx:
                Node("receiver", config).loop()
        message = str(ctx.exception)
        self.assertIn(str(self.port), message)
        self.assertIn("'receiver'", message)
        self.assertIn("in use", message)
        self.assertEqual(snr_threads(), [])

    def test_listing_5_3_config_shape(self) -> None:
        # Listing 5.3: SocketsPair on localhost, the client given a key list.
        capture_test_logs(self, "snr.input_device")  # may warn that the receiver is gone
        sockets = SocketsPair(server_tuple=("localhost", self.port))
        named = {"A": 1, "left_stick_x": 0.5}
        config = Config(
            {
                "input_device": [
                    StoreOnConnectFactory([tasks.store_data("controller_data", named)]),
                    sockets.client(["controller_data"]),
                    TimeoutLoopFactory(seconds=8),
                ],
                "receiver": [
                    sockets.server(),
                    StopAfterFactory("controller_data", on_store=True),
                    TimeoutLoopFactory(seconds=8),
                ],
            },
            mode=Mode.TEST,
        )
        nodes = LocalNodes(config, ["receiver", "input_device"])
        self.addCleanup(nodes.stop)
        page: Optional[Page] = nodes.wait_first().get_page("controller_data")
        self.assertPage(page, "controller_data", named, origin="input_device")


class TestServerSockets(SNRTestCase):
    def test_the_listener_is_closed_when_the_stop_pair_cannot_be_made(self) -> None:
        server = SocketsPair(server_tuple=("127.0.0.1", free_port())).server().get(self.mock_node())
        too_many = OSError(24, "Too many open files")
        with mock.patch("socket.socketpair", side_effect=too_many), self.assertRaises(OSError):
            server.begin()
        listener = server._listener
        assert listener is not None, "begin() made the listener before the pair"
        server.terminate()
        self.assertEqual(listener.fileno(), -1, "terminate() left the listener open")


class TestConfigErrors(unittest.TestCase):
    def test_bad_server_tuple(self) -> None:
        bads = [
            ("localhost",),
            ("localhost", "9000"),
            ("localhost", 0),
            ("h", True),
            ["h", 1],
            None,
        ]
        for bad in bads:
            with self.subTest(bad=bad), self.assertRaises(ConfigError) as ctx:
                SocketsPair(server_tuple=bad)  # type: ignore[arg-type]
            self.assertIn("(host, port)", str(ctx.exception))

    def test_an_int_enum_port_is_a_port(self) -> None:
        class Port(enum.IntEnum):
            ROBOT = 9000

        self.assertEqual(SocketsPair(server_tuple=("localhost", Port.ROBOT)).server_tuple[1], 9000)

    def test_bad_keys(self) -> None:
        pair = SocketsPair(server_tuple=("localhost", 9000))
        for bad in [5, [""], ["a", None], {"a"}]:
            with self.subTest(bad=bad), self.assertRaises(ConfigError) as ctx:
                pair.client(bad)  # type: ignore[arg-type]
            self.assertIn("key", str(ctx.exception))
        self.assertEqual(pair.client("a").keys, ("a",))
        self.assertEqual(pair.client(["a", "b", "a"]).keys, ("a", "b"))
        self.assertEqual(pair.server().keys, ())


if __name__ == "__main__":
    unittest.main()
