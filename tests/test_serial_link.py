"""The serial link, over pyserial's loop:// URL and over a pseudo-terminal pair."""

from __future__ import annotations

import errno
import json
import logging
import os
import select
import sys
import threading
import time
import unittest
from typing import Any, List, Optional, Sequence
from unittest import mock

from snr import (
    AbstractFactory,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    Mode,
    Node,
    SerialLinkFactory,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.core import TestRunner
from snr.prelude import CommsError, ConfigError
from snr.prelude.install import install_hint
from tests.helpers import StopWhenTrueFactory
from tests.optional import reason
from tests.page_collector import PageCollectorFactory
from tests.quiet import capture_test_logs, captured_logs

try:
    import serial
except ImportError:  # pragma: no cover - pyserial is a dev dependency
    serial = None

QUICK = 0.02
"""``read_timeout_s`` for links whose stopping time is not what a test checks:
a link stops within one read (0.1 s by default)."""

needs_pyserial = unittest.skipIf(serial is None, reason("serial"))
needs_pty = unittest.skipUnless(sys.platform.startswith(("linux", "darwin")), "needs a pty")


def serial_threads() -> List[threading.Thread]:
    """The live threads of serial links (reader and writer), by their names."""
    return [t for t in threading.enumerate() if "serial_link" in t.name and t.is_alive()]


class Ticker(Endpoint):
    """Handles ``count`` unrelated tasks, storing a page for the device on each."""

    def __init__(self, factory: TickerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "ticker")
        self.ticks = factory
        self.task_handlers = {(TaskType.event, "tick"): self.tick}

    def begin(self) -> None:
        self.ticks.started_s = time.monotonic()
        self.schedule(tasks.event("tick"))

    def tick(self, task: Task, key: TaskId) -> SomeTasks:
        self.ticks.handled += 1
        self.store_data("cmd", self.ticks.payload)
        if self.ticks.handled < self.ticks.count:
            return tasks.event("tick")
        self.ticks.took_s = time.monotonic() - self.ticks.started_s
        self.ticks.done.set()
        return None


class TickerFactory(EndpointFactory):
    def __init__(self, count: int, payload: str) -> None:
        super().__init__()
        self.count = count
        self.payload = payload
        self.handled = 0
        self.started_s = 0.0
        self.took_s = 0.0
        self.done = threading.Event()

    def get(self, parent: AbstractNode) -> Ticker:
        return Ticker(self, parent)


class Reloader(Endpoint):
    """Reloads the serial link once (on the node's thread), noting the threads before and after."""

    def __init__(self, factory: ReloaderFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "reloader")
        self.record = factory
        self.task_handlers = {(TaskType.event, "reload"): self.reload}

    def begin(self) -> None:
        self.schedule(tasks.event("reload"))

    def reload(self, task: Task, key: TaskId) -> SomeTasks:
        node: Any = self.parent
        old = node.components["serial_link"]
        self.record.before = serial_threads()
        self.record.reloaded = node.reload_component("serial_link")
        self.record.old_alive = old.is_alive()
        self.record.after = serial_threads()
        self.record.new_is_other = node.components["serial_link"] is not old
        return tasks.terminate("reloaded")


class ReloaderFactory(EndpointFactory):
    def __init__(self) -> None:
        super().__init__()
        self.before: List[threading.Thread] = []
        self.after: List[threading.Thread] = []
        self.reloaded: List[str] = []
        self.old_alive = True
        self.new_is_other = False

    def get(self, parent: AbstractNode) -> Reloader:
        return Reloader(self, parent)


def run_role(role: str, factories: Sequence[AbstractFactory], timeout_s: float = 5.0) -> Node:
    runner = TestRunner(role, Config({role: list(factories)}, mode=Mode.TEST), timeout_s)
    runner.run()
    assert not runner.timed_out, f"node {role!r} did not stop by itself"
    assert runner.node is not None
    return runner.node


@needs_pyserial
class TestLoopback(SNRTestCase):
    def test_lines_mode_writes_data_and_stores_the_lines_read(self) -> None:
        received = PageCollectorFactory(["from_mcu"], stop_after=4)
        run_role(
            "robot",
            [
                ListReplayerFactory(["hello", 42, [1, 2.5], {"a": None}], "to_mcu"),
                SerialLinkFactory(
                    "loop://",
                    send_keys=["to_mcu"],
                    receive_key="from_mcu",
                    mode="lines",
                    read_timeout_s=QUICK,
                ),
                received,
            ],
        )
        self.assertEqual(received.data(), ["hello", "42", "[1,2.5]", '{"a":null}'])

    def test_pages_mode_sends_pages_and_stores_what_comes_back_once(self) -> None:
        collected = PageCollectorFactory(["ping"], stop_after=6)
        run_role(
            "robot",
            [
                ListReplayerFactory([1, "two", [3]], "ping"),
                SerialLinkFactory("loop://", send_keys=["ping"], read_timeout_s=QUICK),
                collected,
            ],
        )
        # each page is stored once locally and once more when it comes back;
        # the link does not send back what it received: an echo of the first
        # page back would come before the third page's return, and be caught here
        sent = collected.pages[:3]
        self.assertEqual(collected.pages[3:], sent)  # key, data, origin, created_at_s
        self.assertEqual({p.origin for p in sent}, {"robot"})

    def test_a_line_with_a_line_break_inside_is_not_sent(self) -> None:
        received = PageCollectorFactory(["in"], stop_after=1)
        with self.assertLogs("snr.robot.serial_link", "ERROR") as logs:
            run_role(
                "robot",
                [
                    ListReplayerFactory(["two\nlines", "fine"], "out"),
                    SerialLinkFactory(
                        "loop://",
                        send_keys=["out"],
                        receive_key="in",
                        mode="lines",
                        read_timeout_s=QUICK,
                    ),
                    received,
                ],
            )
        self.assertEqual(received.data(), ["fine"])
        self.assertIn("line break", logs.output[0])

    def test_the_link_stops_quickly_with_its_node(self) -> None:
        # Stopped once both its threads run; it then stops within a read (0.1 s).
        both_run = StopWhenTrueFactory(lambda: len(serial_threads()) == 2, within_s=2.0)
        node = run_role("robot", [SerialLinkFactory("loop://"), both_run])
        link: Any = node.components["serial_link"]
        self.assertFalse(link.is_alive())
        self.assertIsNone(link.port)
        self.assertEqual(serial_threads(), [])  # the reader and the writer both ended

    def test_a_reload_never_leaves_a_second_live_link(self) -> None:
        record = ReloaderFactory()
        link = SerialLinkFactory("loop://", send_keys=["ping"], read_timeout_s=QUICK)
        # The reload joins the old link's threads in a handler: it may be called slow.
        with captured_logs("snr.robot"):
            run_role("robot", [link, record])
        self.assertEqual(record.reloaded, ["serial_link"])
        self.assertEqual(len(record.before), 2)  # one reader, one writer
        self.assertTrue(record.new_is_other)
        self.assertFalse(record.old_alive)
        self.assertEqual(len(record.after), 2)  # the new link's two, and no more
        self.assertFalse(set(record.before) & set(record.after))
        self.assertEqual(serial_threads(), [])


class PtyPair:
    """A pseudo-terminal: the node opens ``path``; the test uses ``master``."""

    def __init__(self) -> None:
        import tty  # POSIX only (imports termios)

        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)  # no echo, no line editing, even before pyserial opens it
        self.path = os.ttyname(self.slave)
        self.buffer = b""

    def write(self, data: bytes) -> None:
        os.write(self.master, data)

    def read_lines(self, count: int, timeout_s: float = 5.0) -> List[str]:
        """``count`` lines written by the node (bounded by ``timeout_s``)."""
        deadline = time.monotonic() + timeout_s
        while self.buffer.count(b"\n") < count and time.monotonic() < deadline:
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if ready:
                self.buffer += os.read(self.master, 4096)
        lines = self.buffer.split(b"\n")
        taken, rest = lines[:count], lines[count:]
        self.buffer = b"\n".join(rest)
        return [line.decode() for line in taken]

    def close_master(self) -> None:
        if self.master >= 0:
            os.close(self.master)
            self.master = -1

    def close(self) -> None:
        self.close_master()
        os.close(self.slave)


class NodeThread:
    """Runs a node on a thread, so the test can talk to its serial port."""

    def __init__(self, factories: Sequence[AbstractFactory], timeout_s: float = 5.0) -> None:
        self.runner = TestRunner(
            "robot", Config({"robot": list(factories)}, mode=Mode.TEST), timeout_s
        )
        self.error: Optional[BaseException] = None
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            self.runner.run()
        except BaseException as error:  # handed to the test in join()
            self.error = error

    def stop(self) -> None:
        deadline = time.monotonic() + 2.0
        while self.runner.node is None and time.monotonic() < deadline:
            time.sleep(0.01)
        if self.runner.node is not None:
            self.runner.node.set_terminate_flag("test is done")

    def join(self) -> None:
        self.thread.join(6.0)
        assert not self.thread.is_alive(), "the node did not stop"
        if self.error is not None:
            raise self.error


@needs_pyserial
@needs_pty
class TestPseudoTerminal(SNRTestCase):
    def setUp(self) -> None:
        self.pty = PtyPair()
        self.addCleanup(self.pty.close)

    def test_pages_mode_talks_to_a_device(self) -> None:
        # stops once both motor pages went out and both device lines came in
        logs = capture_test_logs(self, "snr.robot.serial_link")
        collected = PageCollectorFactory(["temp_c", "serial_text", "motor"], stop_after=4)
        node = NodeThread(
            [
                SerialLinkFactory(
                    self.pty.path,
                    send_keys=["motor"],
                    receive_key="serial_text",
                    read_timeout_s=QUICK,
                ),
                ListReplayerFactory([0.5, -0.25], "motor", period_s=0.05),
                collected,
            ]
        )
        header = self.pty.read_lines(1)  # the port is open once the header is out
        self.assertEqual(json.loads(header[0]), {"format": "snr-pages", "version": 1})
        self.pty.write(b'{"format":"snr-pages","version":1}\r\n{"key":"temp_c","data":21.5}\r\n')
        self.pty.write(b"Booting v1.2\r\n")
        sent = [json.loads(line) for line in self.pty.read_lines(2)]
        node.join()

        self.assertEqual(
            [(p["key"], p["data"], p["origin"]) for p in sent],
            [
                ("motor", 0.5, "robot"),
                ("motor", -0.25, "robot"),
            ],
        )
        temp, text = [p for p in collected.pages if p.key != "motor"]
        self.assertEqual((temp.key, temp.data, temp.origin), ("temp_c", 21.5, "serial_link"))
        self.assertEqual((text.key, text.data), ("serial_text", "Booting v1.2"))
        self.assertIn("is not a page: 'Booting v1.2'", "\n".join(logs))

    def test_pages_mode_rejects_what_the_strict_codec_rejects(self) -> None:
        # Each bad line is stored as text, as any line that is not a page is.
        bad = [
            b'{"key":"temp_c","data":1e999}',
            b'{"key":"temp_c","data":NaN}',
            b'{"key":"temp_c","data":Infinity}',
            b'{"key":"temp_c","data":"\\ud800"}',
            b'{"key":"temp_c","data":' + b"[" * 100 + b"]" * 100 + b"}",
            b'{"format":"snr-pages","version":1.0}',
        ]
        collected = PageCollectorFactory(["temp_c", "serial_text"], stop_after=len(bad) + 1)
        with self.assertLogs("snr.robot.serial_link", "WARNING") as logs:
            node = NodeThread(
                [
                    SerialLinkFactory(
                        self.pty.path, receive_key="serial_text", read_timeout_s=QUICK
                    ),
                    collected,
                ]
            )
            self.pty.read_lines(1)  # the header: the link is up
            self.pty.write(b"\r\n".join(bad) + b'\r\n{"key":"temp_c","data":21.5}\r\n')
            node.join()
        self.assertIn("is not a page", logs.output[0])
        stored = [(p.key, p.data) for p in collected.pages]
        self.assertEqual(stored[-1], ("temp_c", 21.5))
        self.assertEqual([key for key, _ in stored[:-1]], ["serial_text"] * len(bad))

    def test_lines_mode_talks_to_a_device(self) -> None:
        collected = PageCollectorFactory(["arduino"], stop_after=2)
        node = NodeThread(
            [
                SerialLinkFactory(
                    self.pty.path, 9600, ["speed"], "arduino", mode="lines", read_timeout_s=QUICK
                ),
                ListReplayerFactory([120], "speed", period_s=0.05),
                collected,
            ]
        )
        self.assertEqual(self.pty.read_lines(1), ["120"])
        self.pty.write(b"ok 120\r\nbad \xff\n")
        node.join()
        self.assertEqual(collected.data(), ["ok 120", "bad \ufffd"])

    def test_a_device_that_stops_reading_never_slows_the_node(self) -> None:
        # The test does not read the pty at first: the OS buffer fills, then
        # each write waits write_timeout_s. The node must not wait with it.
        ticker = TickerFactory(1000, payload="x" * 2000)  # 2 MB: far over any buffer
        with self.assertLogs("snr.robot.serial_link", logging.WARNING) as logs:
            node = NodeThread(
                [
                    SerialLinkFactory(
                        self.pty.path, send_keys=["cmd"], write_timeout_s=0.05, read_timeout_s=QUICK
                    ),
                    ticker,
                ],
                timeout_s=15.0,
            )
            self.assertTrue(ticker.done.wait(10.0), f"only {ticker.handled} tasks handled")
            assert node.runner.node is not None
            link: Any = node.runner.node.components["serial_link"]
            # On a busy machine the ticker may finish before the writer has filled
            # the OS buffer: keep storing until a write times out (the device stalls).
            deadline = time.monotonic() + 5.0
            while not link._cut:
                self.assertLess(time.monotonic(), deadline, "no write timed out")
                node.runner.node.schedule(tasks.store_data("cmd", "x" * 2000))
                time.sleep(0.01)
            self.assertTrue(any("Dropped" in line for line in logs.output), logs.output)
            # The device reads again, and new pages come: they go out, then "Recovered".
            deadline = time.monotonic() + 5.0
            while not any("Recovered" in line for line in logs.output):
                self.assertLess(time.monotonic(), deadline, "no recovery line")
                node.runner.node.schedule(tasks.store_data("cmd", "again"))
                self.pty.read_lines(10_000, timeout_s=0.05)
            dropped = link.dropped
            self.pty.read_lines(10_000, timeout_s=0.1)  # what was written meanwhile
            node.stop()
            node.join()
        # Before the writer thread, each of these tasks could wait 0.05 s: 50 s in all.
        self.assertLess(ticker.took_s, 5.0)
        self.assertGreater(dropped, 100)
        self.assertGreater(link.lines_sent, 0)
        text = "\n".join(logs.output)
        self.assertRegex(text, r"Dropped \d+ lines for serial port")
        self.assertRegex(text, r"Recovered: \d+ lines for serial port .* dropped over")
        self.assertLess(len(logs.output), 10, text)  # counted, not a line per drop
        self.assertFalse(link.is_alive())

    def test_bad_lines_are_skipped_and_the_link_reads_on(self) -> None:
        collected = PageCollectorFactory(["good"], stop_after=1)
        with self.assertLogs("snr.robot.serial_link", logging.WARNING) as logs:
            node = NodeThread([SerialLinkFactory(self.pty.path, read_timeout_s=QUICK), collected])
            self.pty.read_lines(1)  # the header: the link is up
            deep = "[" * 5000 + "]" * 5000  # beyond the JSON decoder's recursion limit
            self.pty.write(b"garbage {not json\n")
            self.pty.write(b'{"key":"x","data":1e999}\n')
            self.pty.write(b'{"key":"x","data":' + deep.encode() + b"}\n")
            self.pty.write(b'{"key":"good","data":7}\n')
            node.join()
        self.assertEqual(collected.data(), [7])  # read after all three bad lines
        text = "\n".join(logs.output)
        self.assertEqual(len(logs.output), 3, text)
        self.assertIn("garbage {not json", text)
        self.assertIn("it is not JSON", text)
        self.assertIn("the number inf is out of range", text)
        self.assertIn("nests arrays and objects more than 100 deep", text)
        self.assertIn("More of these are counted", text)  # the next ones are counted

    def test_a_lost_device_is_reported_and_the_node_stops_cleanly(self) -> None:
        with self.assertLogs("snr.robot.serial_link", "ERROR") as logs:
            node = NodeThread([SerialLinkFactory(self.pty.path, read_timeout_s=QUICK)])
            self.pty.read_lines(1)  # the header: the link is up
            self.pty.close_master()  # as if the cable were pulled
            deadline = time.monotonic() + 3.0
            while not logs.output and time.monotonic() < deadline:
                time.sleep(0.02)
            node.stop()
            node.join()
        self.assertIn("Lost serial port", logs.output[0])
        self.assertIn(self.pty.path, logs.output[0])


@needs_pyserial
class TestErrors(SNRTestCase):
    def test_a_port_that_does_not_exist_names_it_and_lists_the_ports(self) -> None:
        with self.assertRaises(CommsError) as caught:
            run_role("robot", [SerialLinkFactory("/dev/ttyNOPE42")])
        message = str(caught.exception)
        self.assertIn("node 'robot' cannot open serial port /dev/ttyNOPE42", message)
        self.assertIn("there is no such serial port", message)
        self.assertIn("Serial ports on this computer: ", message)

    def test_permission_denied_explains_the_dialout_group(self) -> None:
        # The tests may run as root, who is never denied, so make the error by hand.
        from snr.extras.serial.port import describe_open_error

        denied = serial.SerialException(errno.EACCES, "could not open port /dev/ttyUSB0")
        message = str(describe_open_error("/dev/ttyUSB0", denied))
        self.assertIn("permission denied", message)
        self.assertIn("usermod -a -G dialout", message)
        self.assertIn("log out and back in", message)
        busy = serial.SerialException(errno.EBUSY, "could not open port")
        self.assertIn("another program has it open", str(describe_open_error("/dev/ttyUSB0", busy)))

    def test_a_bad_url_is_a_clear_error(self) -> None:
        with self.assertRaises(CommsError) as caught:
            run_role("robot", [SerialLinkFactory("bogus://x")])
        self.assertIn("pyserial URL", str(caught.exception))

    def test_a_misspelt_mode_gets_a_suggestion(self) -> None:
        with self.assertRaises(ConfigError) as caught:
            SerialLinkFactory("loop://", mode="line")
        self.assertIn("Did you mean 'lines'?", str(caught.exception))

    def test_echoing_lines_back_is_refused(self) -> None:
        with self.assertRaises(ConfigError):
            SerialLinkFactory("loop://", send_keys=["x"], receive_key="x", mode="lines")

    def test_pages_mode_keeps_lines_that_are_not_pages_and_logs_them_sparingly(self) -> None:
        node = self.mock_node()
        link = SerialLinkFactory("loop://").get(node)
        noise = b"".join(f"noise {i}\n".encode() for i in range(9))
        with self.assertLogs("snr.mock.serial_link", logging.WARNING) as logs:
            link._take(noise + b'{"key":"x","data":1}\n')
            link._repeats.flush()  # as at terminate: the count of the rest
        self.assertEqual(len(logs.output), 4, logs.output)  # lines 1 to 3, then a count
        self.assertIn("6 more times", logs.output[3])
        self.assertEqual(link.bad_lines, 9)
        stored = [task.val_list[0] for task in node.scheduled]
        self.assertEqual([p.data for p in stored[:9]], [f"noise {i}" for i in range(9)])
        self.assertEqual({p.key for p in stored[:9]}, {"serial_in"})
        self.assertEqual((stored[9].key, stored[9].data), ("x", 1))

    def test_values_json_allows_but_pages_must_not_hold_are_refused(self) -> None:
        node = self.mock_node()
        link = SerialLinkFactory("loop://").get(node)
        nested = "[" * 120 + "1" + "]" * 120  # deeper than a page may nest (MAX_DEPTH)
        lines = [
            b'{"key":"a","data":NaN}',
            b'{"key":"b","data":[1,{"c":-Infinity}]}',
            b'{"key":"d","data":' + nested.encode() + b"}",
            b'{"key":"e","data":1,"created_at_s":1e400}',
            b'{"key":"ok","data":[1.5,{"c":[2]}]}',
        ]
        with self.assertLogs("snr.mock.serial_link", logging.WARNING):
            link._take(b"\n".join(lines) + b"\n")
        stored = [task.val_list[0] for task in node.scheduled]
        self.assertEqual([p.key for p in stored], ["serial_in"] * 4 + ["ok"])
        self.assertEqual(link.bad_lines, 4)

    def test_a_bad_outbox_size_is_a_config_error(self) -> None:
        with self.assertRaises(ConfigError) as caught:
            SerialLinkFactory("loop://", outbox_bytes=0)
        self.assertIn("outbox_bytes=0", str(caught.exception))

    def test_without_pyserial_the_error_says_how_to_install_it(self) -> None:
        hidden = {"serial": None, "serial.tools": None, "serial.tools.list_ports": None}
        with mock.patch.dict(sys.modules, hidden):
            with self.assertRaises(CommsError) as caught:
                SerialLinkFactory("/dev/ttyACM0")
        self.assertIn(install_hint("serial"), str(caught.exception))
