"""The console's graph, echo and hz commands, against a node on 127.0.0.1."""

from __future__ import annotations

import io
import re
import socket
import threading
import unittest
from typing import List
from unittest import mock

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
)
from snr.extras.console_tools.watches import watches_of
from snr.std_mods.io.command_processor import (
    COMMANDS,
    CommandProcessorEndpoint,
    CommandProcessorFactory,
)
from snr.std_mods.io.console_protocol import Status
from snr.utils.mock_node import MockNode
from tests.console_helpers import NodeInThread, read_replies
from tests.helpers import free_port, wait_until


class Counter(ThreadLoop):
    """Stores 0, 1, 2, ... under ``key``, ``hz`` times a second."""

    def __init__(self, factory: CounterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, f"{factory.key}_counter", max_tick_rate_hz=factory.hz)
        self.key = factory.key
        self.count = 0

    def loop(self) -> None:
        self.store_data(self.key, self.count)
        self.count += 1


class CounterFactory(LoopFactory):
    def __init__(self, key: str = "depth", hz: float = 200.0) -> None:
        super().__init__()
        self.key, self.hz = key, hz

    def get(self, parent: AbstractNode) -> Counter:
        return Counter(self, parent)


class Misspelt(Endpoint):
    """Waits for pages of 'depht', which nothing stores."""

    def __init__(self, factory: MisspeltFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "misspelt")
        self.task_handlers = {(TaskType.store_page, "depht"): self.on_page}

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class MisspeltFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Misspelt:
        return Misspelt(self, parent)


def values(text: str) -> List[int]:
    """The values of ``depth = N  (from ...)`` lines of an echo reply."""
    return [
        int(v) for v in re.findall(r"^depth = (\d+)  \(from 'robot', \d+ ms old\)$", text, re.M)
    ]


class ConsoleTopicsTest(unittest.TestCase):
    def processor(self, node: Node) -> CommandProcessorEndpoint:
        found = wait_until(lambda: node.components.get("command_receiver_commands"))
        assert isinstance(found, CommandProcessorEndpoint)
        return found

    def test_graph_of_a_running_node_flags_the_orphaned_keys(self) -> None:
        with NodeInThread([CounterFactory(), MisspeltFactory()]) as running:
            with running.console() as console:
                text = console.send("graph").text
                self.assertIn("Node 'robot' (4 components):", text)
                self.assertIn("depth_counter (Counter): stores depth", text)
                self.assertIn("misspelt (Misspelt): handles depht", text)
                self.assertIn("'depht' is read by misspelt, but nothing on the node stores", text)
                self.assertIn("'depth' is stored by depth_counter, but nothing on the node", text)
                mermaid = console.send("graph mermaid")
                self.assertEqual(mermaid.status, Status.OK)
                self.assertIn('["(!) depht<br/>never produced"]', mermaid.text)
                self.assertTrue(console.send("graph dot").text.startswith("digraph snr {"))
                wrong = console.send("graph png")
                self.assertEqual(wrong.status, Status.ERROR)
                self.assertIn("Usage: graph text|mermaid|dot.", wrong.text)

    def test_echo_shows_every_page_across_replies(self) -> None:
        with NodeInThread([CounterFactory()]) as running:
            with running.console() as console:
                first = values(console.send("echo depth 5").text)
                second = values(console.send("echo depth 5").text)
        self.assertEqual(len(first), 5)
        # Pages that came between the two requests waited for the second one.
        self.assertEqual(first + second, list(range(first[0], first[0] + len(first + second))))

    def test_echo_of_a_missing_key_says_so_and_guesses(self) -> None:
        with NodeInThread([CounterFactory()]) as running:
            processor = self.processor(running.node)
            watches = watches_of(processor)
            watches.echo_wait_s = watches.echo_keep_s = 0.05
            with running.console() as console:
                wait_until(lambda: "depth" in running.node.datastore)
                reply = console.send("echo dept")
                self.assertEqual(reply.status, Status.OK)
                self.assertIn("No page under 'dept' in the last 0.05 s.", reply.text)
                self.assertIn("Did you mean 'depth'?", reply.text)
                # The watch ends (its handler is removed) once nobody asks again.
                watched = (TaskType.store_page, "dept")
                self.assertTrue(wait_until(lambda: watched not in processor.task_handlers))
                bad = console.send("echo depth 0")
                self.assertEqual(bad.status, Status.ERROR)
                self.assertIn("`echo` takes N from 1 to 100; got '0'", bad.text)

    def test_hz_measures_rate_and_jitter(self) -> None:
        with NodeInThread([CounterFactory(hz=100.0)]) as running:
            processor = self.processor(running.node)
            with running.console() as console:
                reply = console.send("hz depth 0.3")
                nothing = console.send("hz nothing 0.1")
                refused = console.send("hz depth 100")
            # The reply comes after the window, which `hz` declares in COMMANDS:
            # a console waits that much longer than its own timeout.
            with running.console(timeout_s=1.0) as quick:
                late = quick.send("hz nothing 1.2")
            # On the wire, still one reply frame per request line.
            with socket.create_connection((running.host, running.port), 5.0) as sock:
                sock.sendall(b"hz nothing 0.1\nhelp hz\n")
                frames = read_replies(sock, 3)
        self.assertIn("nothing: no page in 1.2 s.", late.text)
        self.assertEqual([f.status for f in frames], [Status.HELLO, Status.OK, Status.OK])
        self.assertTrue(frames[1].text.startswith("nothing: no page in 0.1 s."), frames[1].text)
        self.assertTrue(frames[2].text.startswith("hz KEY [WINDOW_S]"), frames[2].text)
        self.assertEqual(reply.status, Status.OK)
        match = re.fullmatch(
            r"depth: ([\d.]+) Hz over 0\.3 s \((\d+) pages\); period mean ([\d.]+) ms, "
            r"min ([\d.]+) ms, max ([\d.]+) ms, std ([\d.]+) ms \(jitter\)",
            reply.text,
        )
        assert match is not None, reply.text
        rate, pages, mean, low, high = (float(v) for v in match.groups()[:5])
        self.assertGreater(pages, 1)
        self.assertLessEqual(low, mean)
        self.assertLessEqual(mean, high)
        self.assertAlmostEqual(rate, 1000.0 / mean, delta=rate * 0.01)
        self.assertIn("nothing: no page in 0.1 s.", nothing.text)
        self.assertEqual(refused.status, Status.ERROR)
        self.assertNotIn((TaskType.store_page, "depth"), processor.task_handlers)

    def test_hz_declares_that_its_reply_comes_after_its_window(self) -> None:
        after = COMMANDS["hz"].reply_after_s
        assert after is not None
        words: List[List[str]] = [
            ["depth"],
            ["depth", "1.5"],
            ["depth", "100"],
            ["depth", "soon"],
            [],
            ["a", "1", "2"],
        ]
        self.assertEqual([after(w) for w in words], [2.0, 1.5, 0.0, 0.0, 0.0, 0.0])
        self.assertIsNone(COMMANDS["stats"].reply_after_s, "a command that replies at once")

    def test_snr_console_streams_echo_until_stopped(self) -> None:
        with NodeInThread([CounterFactory()]) as running:
            with running.console() as console:
                out = io.StringIO()
                code = console.stream("echo depth 3", out, replies=2)
                self.assertEqual(code, 0)
                self.assertEqual(len(values(out.getvalue())), 6)
                # Ctrl-C while waiting: the reply still on its way is not taken
                # for the answer to the next command.
                out = io.StringIO()
                with mock.patch.object(console, "_receive", side_effect=KeyboardInterrupt):
                    self.assertEqual(console.run_command("echo depth", out), 0)
                self.assertIn("(Ctrl-C) Stopped `echo depth`.", out.getvalue())
                self.assertTrue(console.send("help hz").text.startswith("hz KEY [WINDOW_S]"))

    def test_echo_needs_a_console_to_reply_to(self) -> None:
        processor = CommandProcessorFactory("commands", "console:test").get(MockNode())
        for line in ("echo depth", "hz depth"):
            reply = processor.execute(line)
            self.assertEqual(reply.status, Status.ERROR)
            self.assertIn("need a console to reply to", reply.text)


class LiveLinkGraphTest(unittest.TestCase):
    def test_graph_shows_the_open_link_and_what_came_over_it(self) -> None:
        pair = SocketsPair(("127.0.0.1", free_port()))
        peer = Node(
            "sub",
            Config({"sub": [pair.server(["sonar"]), CounterFactory("sonar")]}, mode=Mode.TEST),
        )
        thread = threading.Thread(target=peer.loop, name="peer-node", daemon=True)
        thread.start()
        try:
            with NodeInThread([pair.client(["depth"]), CounterFactory()]) as running:
                wait_until(lambda: "sonar" in running.node.datastore)
                with running.console() as console:
                    text = console.send("graph").text
        finally:
            peer.set_terminate_flag("test finished")
            thread.join(5)
        self.assertIn(
            f"robot.sockets_client_{pair.server_tuple[1]} <-> sub (TCP 127.0.0.1:"
            f"{pair.server_tuple[1]}): sends depth; receives sonar",
            text,
        )
        self.assertIn("'sonar' is stored by sockets_client", text)  # nobody reads it here
        self.assertNotIn("'depth' is stored by", text)  # the link sends it on


if __name__ == "__main__":
    unittest.main()
