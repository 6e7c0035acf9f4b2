"""The remote console: commands, replies, protocol, security, and the client program."""

from __future__ import annotations

import functools
import io
import os
import pickle
import socket
import subprocess
import sys
import threading
import unittest
from typing import List, Optional
from unittest import mock

from snr import CommandReceiverFactory, Config, LocalConsoleFactory, Mode, Node, TimeoutLoopFactory
from snr.core import NodeState
from snr.prelude import CommsError, ConfigError
from snr.std_mods.io import RemoteConsole
from snr.std_mods.io.command_processor import CommandProcessorFactory
from snr.std_mods.io.command_receiver import MAX_CONSOLES, _TokenThrottle
from snr.std_mods.io.console_protocol import (
    MAX_LINE_BYTES,
    MAX_REPLY_BYTES,
    PROTOCOL,
    TOKEN_ENV_VAR,
    ConsoleConnectionError,
    Reply,
    ReplyDecoder,
    Status,
    check_listen_policy,
    is_loopback,
    parse_address,
    parse_values,
    tokens_match,
)
from snr.std_mods.io.remote_console import EXIT_CONNECTION, EXIT_OK, EXIT_USAGE, main
from snr.utils import MockNode
from tests.console_helpers import NodeInThread, read_replies
from tests.helpers import free_port, wait_until


class TestProtocol(unittest.TestCase):
    def test_reply_round_trip_in_pieces(self) -> None:
        frames = Reply(Status.OK, "héllo\nworld").encode() + Reply(Status.BYE, "").encode()
        decoder = ReplyDecoder()
        got: List[Reply] = []
        for i in range(len(frames)):  # one byte at a time: short reads are normal
            got += decoder.feed(frames[i : i + 1])
        self.assertEqual(got, [Reply(Status.OK, "héllo\nworld"), Reply(Status.BYE, "")])

    def test_header_names_protocol_status_and_length(self) -> None:
        self.assertEqual(Reply(Status.ERROR, "no").encode(), f"{PROTOCOL} error 2\nno".encode())

    def test_bad_header_is_a_wire_format_error(self) -> None:
        from snr.prelude import WireFormatError

        for junk in (b"HTTP/1.1 200 OK\r\n", b"snr-console/1 maybe 3\nabc", b"x" * 100):
            with self.assertRaises(WireFormatError, msg=junk):
                ReplyDecoder().feed(junk)
        with self.assertRaisesRegex(WireFormatError, "more than"):
            ReplyDecoder().feed(f"{PROTOCOL} ok {MAX_REPLY_BYTES * 2}\n".encode())

    def test_huge_reply_is_cut_with_a_note(self) -> None:
        frame = Reply(Status.OK, "é" * MAX_REPLY_BYTES).encode()
        (reply,) = ReplyDecoder().feed(frame)
        self.assertIn("reply cut", reply.text)
        self.assertLess(len(frame), MAX_REPLY_BYTES + 300)

    def test_values_are_json_or_words_never_python(self) -> None:
        self.assertEqual(
            parse_values('1 2.5 true null "a b" [1, 2] {"k": 3} hello 3abc'),
            [1, 2.5, True, None, "a b", [1, 2], {"k": 3}, "hello", "3abc"],
        )
        self.assertEqual(parse_values("__import__('os')"), ["__import__('os')"])
        self.assertEqual(parse_values("   "), [])

    def test_address_parsing(self) -> None:
        self.assertEqual(parse_address("robot.local:9000"), ("robot.local", 9000))
        self.assertEqual(parse_address("9000"), ("127.0.0.1", 9000))
        self.assertEqual(parse_address("[::1]:9000"), ("::1", 9000))
        for bad in ("robot", "host:0", "host:70000", "host:port"):
            with self.assertRaisesRegex(ValueError, "HOST:PORT", msg=bad):
                parse_address(bad)


class TestSecurityPolicy(unittest.TestCase):
    def test_loopback_detection(self) -> None:
        for host in ("127.0.0.1", "127.1.2.3", "::1", "localhost"):
            self.assertTrue(is_loopback(host), host)
        for host in ("0.0.0.0", "", "192.168.1.5", "::", "robot.local"):
            self.assertFalse(is_loopback(host), host)

    def test_non_loopback_needs_a_token(self) -> None:
        with mock.patch.dict(os.environ, {TOKEN_ENV_VAR: ""}):
            for host in ("0.0.0.0", "192.168.1.5", ""):
                with self.assertRaisesRegex(ConfigError, "token", msg=host):
                    CommandReceiverFactory(host=host)
            CommandReceiverFactory(host="0.0.0.0", token="long-random-word")  # allowed
            CommandReceiverFactory()  # loopback: no token needed

    def test_token_from_environment(self) -> None:
        with mock.patch.dict(os.environ, {TOKEN_ENV_VAR: "from-env"}):
            self.assertEqual(CommandReceiverFactory(host="0.0.0.0").token, "from-env")
            self.assertEqual(RemoteConsole().token, "from-env")

    def test_malformed_tokens_are_refused(self) -> None:
        for token in ("", "two words", "x" * 300, "line\nbreak"):
            with self.assertRaises(ConfigError, msg=repr(token)):
                check_listen_policy("0.0.0.0", token)

    def test_tokens_compare_exactly(self) -> None:
        self.assertTrue(tokens_match("s3cret", "s3cret"))
        self.assertFalse(tokens_match("s3cret", "s3cre"))
        self.assertFalse(tokens_match("s3cret", ""))


class TestCommands(unittest.TestCase):
    def test_every_command_replies(self) -> None:
        with NodeInThread([], profile=True) as run, run.console() as console:
            assert console.greeting is not None
            self.assertEqual(console.greeting.status, Status.HELLO)
            self.assertIn("'robot'", console.greeting.text)

            help_reply = console.send("help")
            self.assertEqual(help_reply.status, Status.OK)
            for word in ("exit", "task", "reload", "list", "dump", "help"):
                self.assertIn(word, help_reply.text)
            self.assertIn("keeps running", console.send("help reload").text)
            self.assertIn("task <type> <name>", console.send("list commands").text)

            endpoints = console.send("list endpoints").text
            for name in ("node_core", "command_receiver", "command_receiver_commands"):
                self.assertIn(name, endpoints)
            self.assertIn("loop      CommandReceiverLoop (running)", endpoints)

            self.assertIn("Times called", console.send("dump profiler").text)

            reply = console.send("task store_page depth_m 3.25")
            self.assertEqual(reply, Reply(Status.OK, "Scheduled (store_page, 'depth_m'): 3.25"))
            reply = console.send('task event beep A 2 [1, 2] "a b"')
            self.assertIn("(event, 'beep'): ['A', 2, [1, 2], 'a b']", reply.text)
            self.assertEqual(wait_until(lambda: run.node.get_data("depth_m")), 3.25)
            dump = console.send("dump datastore").text
            self.assertIn("depth_m = 3.25", dump)
            self.assertIn("from 'robot'", dump)
            self.assertEqual(console.send("").status, Status.OK)  # blank line: empty reply

    def test_unknown_commands_and_bad_arguments_suggest_a_fix(self) -> None:
        cases = {
            "relaod all": "Did you mean 'reload'?",
            "lst endpoints": "Did you mean 'list'?",
            "list endpoint": "Did you mean `list endpoints`?",
            "list": "Usage: list commands|endpoints",
            "dump profiler datastore": "Usage: dump profiler|datastore",
            "dump datastor": "Did you mean `dump datastore`?",
            "task": "Usage: task <type> <name>",
            "task evnt beep": "Did you mean 'event'?",
            "task store_page k 1 2": "needs exactly one value",
            "reload": "Usage: reload all|<component>",
            "reload timeout_lop": "Did you mean 'timeout_loop'?",
            "reload command_receiver": "part of the console",
            "task reload command_receiver_commands": "part of the console",
            "help relaod": "Did you mean 'reload'?",
            "exit now": "takes no arguments",
            "frobnicate": "Type 'help'",
        }
        with self.assertLogs("snr.robot", "WARNING") as logs:
            with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run:
                with run.console() as console:
                    for line, expected in cases.items():
                        reply = console.send(line)
                        self.assertEqual(reply.status, Status.ERROR, line)
                        self.assertIn(expected, reply.text, line)
                self.assertIs(run.node.state, NodeState.RUNNING)
        # The two refused reloads of the console itself are logged for the robot's keeper.
        cannot = [line for line in logs.output if "cannot reload itself" in line]
        self.assertEqual(len(cannot), 2, logs.output)

    def test_task_types(self) -> None:
        with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run, run.console() as console:
            self.assertIn("(reload, 'timeout_loop')", console.send("task reload timeout_loop").text)
            self.assertIn("'x'", console.send("task process_data x 1").text)
            self.assertIn("Rebuilt", console.send("reload timeout_loop").text)
            self.assertEqual(console.send("task terminate all done").status, Status.OK)
            run.wait_stopped()
        self.assertEqual(run.node.terminate_reason, "all done")

    def test_exit_terminates_the_node_and_closes_the_console(self) -> None:
        with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run:
            console = run.console()
            reply = console.send("exit")
            self.assertEqual(reply, Reply(Status.BYE, "Stopping node 'robot'. Bye."))
            self.assertFalse(console.is_connected())
            run.wait_stopped()
            self.assertIs(run.node.state, NodeState.TERMINATED)
            self.assertIn("exit command from console 127.0.0.1:", str(run.node.terminate_reason))

    def test_other_consoles_hear_when_the_node_stops(self) -> None:
        with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run:
            with socket.create_connection((run.host, run.port), timeout=5) as other:
                with run.console() as console:
                    console.send("exit")
                run.wait_stopped()
                replies = read_replies(other, 2)
        self.assertEqual(replies[0].status, Status.HELLO)
        self.assertEqual(replies[1], Reply(Status.BYE, "Node 'robot' is stopping."))


class TestStats(unittest.TestCase):
    def test_stats_shows_the_queue_and_every_link(self) -> None:
        from snr import SocketsPair

        pair = SocketsPair(("127.0.0.1", free_port()))
        with NodeInThread([pair.server()]) as run, run.console() as console:
            self.assertIn("0 links", console.send("stats").text)
            peer = Node("peer", Config({"peer": [pair.client("hello")]}, mode=Mode.TEST))
            thread = threading.Thread(target=peer.loop, daemon=True)
            thread.start()
            try:
                self.assertTrue(wait_until(lambda: "1 link" in console.send("stats").text))

                def arrived() -> bool:
                    # The server may see the link before the client has heard its
                    # hello (and a client sends nothing before): store until one arrives.
                    peer.store_data("hello", "world")
                    return run.node.get_data("hello") == "world"

                self.assertTrue(wait_until(arrived))
                text = console.send("stats").text
            finally:
                peer.set_terminate_flag("test over")
                thread.join(5)
        self.assertIn("Queue of node 'robot': ", text)
        self.assertIn("tasks dropped", text)
        self.assertRegex(
            text, r"'peer' at 127\.0\.0\.1:\d+ \(open\): sent 0, received [1-9]\d*, dropped 0"
        )
        self.assertIn("heard", text)


class TestRobustness(unittest.TestCase):
    def test_dead_and_rude_consoles_do_not_hurt_the_node(self) -> None:
        with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run:
            # One hangs up in the middle of a command.
            with socket.create_connection((run.host, run.port), timeout=5) as rude:
                rude.sendall(b"dump datastore\nhelp\n")
            # One sends bytes that are not UTF-8 and a line that is far too long,
            # between commands: every line still gets its reply, in order.
            with socket.create_connection((run.host, run.port), timeout=5) as noisy:
                too_long = b"x" * (MAX_LINE_BYTES * 3)
                noisy.sendall(b"help\n\xff\xfe\n" + too_long + b"\n\nlist commands\n")
                replies = read_replies(noisy, 6)
            self.assertEqual(replies[0].status, Status.HELLO)
            self.assertIn("Commands (type", replies[1].text)
            self.assertIn("not UTF-8", replies[2].text)
            self.assertIn("longer than", replies[3].text)
            self.assertEqual(replies[4], Reply(Status.OK, ""))
            self.assertIn("task <type> <name>", replies[5].text)
            with run.console() as console:
                self.assertEqual(console.send("help").status, Status.OK)
            self.assertIs(run.node.state, NodeState.RUNNING)

    def test_too_many_consoles_are_turned_away(self) -> None:
        with self.assertLogs("snr.robot", "WARNING") as logs, NodeInThread([]) as run:
            consoles = [run.console() for _ in range(MAX_CONSOLES)]
            try:
                with self.assertRaisesRegex(ConsoleConnectionError, "Too many consoles"):
                    run.console()
                consoles.pop().close()
                # The freed slot is usable again (the close may take a moment to be seen).
                self.assertTrue(wait_until(lambda: _try_connect(run)))
            finally:
                for console in consoles:
                    console.close()
        self.assertIn(f"{MAX_CONSOLES} are connected, the most", logs.output[0])


def _try_connect(run: NodeInThread, token: Optional[str] = None) -> bool:
    try:
        run.console(token).close()
    except ConsoleConnectionError:
        return False
    return True


class TestReceiverSetup(unittest.TestCase):
    def test_port_in_use_is_explained(self) -> None:
        with NodeInThread([]) as run:
            clash = Config({"b": [CommandReceiverFactory(port=run.port)]}, mode=Mode.TEST)
            with self.assertRaisesRegex(CommsError, "is in use.*CommandReceiverFactory"):
                Node("b", clash).loop()

    def test_port_in_use_when_deployed_keeps_the_node_running(self) -> None:
        with NodeInThread([]) as run:
            factories = [CommandReceiverFactory(port=run.port), TimeoutLoopFactory(ms=20)]
            node = Node("b", Config({"b": factories}, mode=Mode.DEPLOYED))
            with self.assertLogs("snr.b", "ERROR") as logs:
                node.loop()
            self.assertEqual(node.terminate_reason, "Timeout")
            self.assertIn("runs on without a console", "\n".join(logs.output))

    def test_factories_survive_pickling(self) -> None:
        receiver = pickle.loads(pickle.dumps(CommandReceiverFactory(port=0)))
        with self.assertRaisesRegex(CommsError, "not listening"):
            receiver.wait_until_listening(0.01)
        local = pickle.loads(pickle.dumps(LocalConsoleFactory(io.StringIO("help"))))
        self.assertIsNone(local.stream)

    def test_processor_runs_commands_without_a_real_node(self) -> None:
        node = MockNode()
        processor = CommandProcessorFactory("commands", "console_command:test").get(node)
        node.components["commands"] = processor
        self.assertIn(
            "commands  endpoint  CommandProcessorEndpoint", processor.execute("list endpoints").text
        )
        reply = processor.execute("reload all")
        self.assertEqual(reply.status, Status.ERROR)
        self.assertIn("needs a running snr.Node", reply.text)
        self.assertEqual(processor.execute("task event go 1").status, Status.OK)
        self.assertEqual([str(t) for t in node.scheduled], ["(event, 'go'): [1]"])


class TestToken(unittest.TestCase):
    def test_token_required_and_checked(self) -> None:
        quick = functools.partial(_TokenThrottle, first_delay_s=0.05)  # 0.25 s by default
        with (
            mock.patch.dict(os.environ, {TOKEN_ENV_VAR: ""}),
            mock.patch("snr.std_mods.io.command_receiver._TokenThrottle", quick),
        ):
            with self.assertLogs("snr.robot", "WARNING") as logs:
                with NodeInThread([], token="s3cret-word") as run:
                    with self.assertRaisesRegex(ConsoleConnectionError, "needs a console token"):
                        run.console()
                    with self.assertRaisesRegex(ConsoleConnectionError, "Wrong or missing"):
                        run.console(token="guess")
                    # The wrong guess makes this address wait a moment before its next try.
                    with self.assertRaisesRegex(ConsoleConnectionError, "next one is checked in"):
                        run.console(token="s3cret-word")
                    self.assertTrue(wait_until(lambda: _try_connect(run, "s3cret-word")))
                    with run.console(token="s3cret-word") as console:
                        self.assertEqual(console.send("help").status, Status.OK)
        self.assertIn("gave a wrong token (1 in a row from 127.0.0.1)", logs.output[0])
        self.assertIn("too soon after wrong ones", logs.output[1])

    def test_commands_before_the_token_are_not_run(self) -> None:
        with mock.patch.dict(os.environ, {TOKEN_ENV_VAR: ""}):
            with self.assertLogs("snr.robot", "WARNING") as logs:
                with NodeInThread([], token="s3cret-word") as run:
                    with socket.create_connection((run.host, run.port), timeout=5) as sneaky:
                        sneaky.sendall(b"exit\n")
                        replies = read_replies(sneaky, 3)
                    self.assertEqual([r.status for r in replies], [Status.AUTH, Status.BYE])
                    self.assertIs(run.node.state, NodeState.RUNNING)
        self.assertIn("sent a command before its token; disconnected it", logs.output[0])


class TestRemoteConsoleProgram(unittest.TestCase):
    def test_connection_refused_is_explained(self) -> None:
        port = free_port()
        with self.assertRaises(ConsoleConnectionError) as caught:
            RemoteConsole("127.0.0.1", port, timeout_s=2).connect()
        message = str(caught.exception)
        self.assertIn("the connection was refused", message)
        self.assertIn(f"CommandReceiverFactory(port={port})", message)

        err = io.StringIO()
        code = main([f"127.0.0.1:{port}", "-c", "help"], stdout=io.StringIO(), stderr=err)
        self.assertEqual(code, EXIT_CONNECTION)
        self.assertIn("the connection was refused", err.getvalue())

    def test_bad_address_is_a_usage_error(self) -> None:
        err = io.StringIO()
        self.assertEqual(main(["not-an-address"], stderr=err), EXIT_USAGE)
        self.assertIn("HOST:PORT", err.getvalue())

    def test_commands_from_arguments_and_from_a_pipe(self) -> None:
        with NodeInThread([TimeoutLoopFactory(seconds=30)]) as run:
            out = io.StringIO()
            address = f"{run.host}:{run.port}"
            code = main([address, "-c", "list endpoints", "-c", "help"], stdout=out)
            self.assertEqual(code, EXIT_OK)
            self.assertIn("timeout_loop", out.getvalue())
            self.assertEqual(main([address, "-c", "relaod"], stdout=io.StringIO()), 1)

            out = io.StringIO()
            code = main([address], stdin=io.StringIO("help\n\nexit\nhelp\n"), stdout=out)
            self.assertEqual(code, EXIT_OK)
            self.assertIn("Stopping node 'robot'", out.getvalue())
            run.wait_stopped()

    def test_interactive_session(self) -> None:
        with NodeInThread([]) as run, run.console() as console:
            typed = iter(["help", "", "quit"])
            out = io.StringIO()
            self.assertEqual(console.interact(lambda prompt: next(typed), out), EXIT_OK)
            self.assertIn("Commands", out.getvalue())
            self.assertEqual(run.node.state, NodeState.RUNNING)  # quit leaves the node running

    def test_python_dash_m_snr_console(self) -> None:
        port = free_port()
        result = subprocess.run(
            [sys.executable, "-m", "snr.console", f"127.0.0.1:{port}", "-c", "help"],
            capture_output=True,
            text=True,
            timeout=30,
            cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
        )
        self.assertEqual(result.returncode, EXIT_CONNECTION)
        self.assertIn("the connection was refused", result.stderr)


if __name__ == "__main__":
    unittest.main()
