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
    CommsError,
    Config,
    ConfigError,
    ListReplayerFactory,
    Mode,
    Node,
    SerialLinkFactory,
    SNRTestCase,
    TestRunner,
    TimeoutLoopFactory,
)
from tests.page_collector import PageCollectorFactory

try:
    import serial
except ImportError:  # pragma: no cover - pyserial is a dev dependency
    serial = None

needs_pyserial = unittest.skipIf(serial is None, "pyserial is not installed")
needs_pty = unittest.skipUnless(sys.platform.startswith(("linux", "darwin")), "needs a pty")


def run_role(role: str, factories: Sequence[AbstractFactory], timeout_s: float = 5.0) -> Node:
    runner = TestRunner(role, Config({role: list(factories)}, mode=Mode.TEST), timeout_s)
    runner.run()
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
                    "loop://", send_keys=["to_mcu"], receive_key="from_mcu", mode="lines"
                ),
                received,
            ],
        )
        self.assertEqual(received.data(), ["hello", "42", "[1,2.5]", '{"a":null}'])

    def test_pages_mode_sends_pages_and_stores_what_comes_back_once(self) -> None:
        collected = PageCollectorFactory(["ping"])
        run_role(
            "robot",
            [
                ListReplayerFactory([1, "two", [3]], "ping"),
                SerialLinkFactory("loop://", send_keys=["ping"]),
                collected,
                TimeoutLoopFactory(seconds=0.4),
            ],
        )
        # each page is stored once locally and once more when it comes back;
        # the link does not send back what it received, so there is no echo loop
        self.assertEqual(len(collected.pages), 6, collected.pages)
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
                    SerialLinkFactory("loop://", send_keys=["out"], receive_key="in", mode="lines"),
                    received,
                ],
            )
        self.assertEqual(received.data(), ["fine"])
        self.assertIn("line break", logs.output[0])

    def test_the_link_stops_quickly_with_its_node(self) -> None:
        node = run_role("robot", [SerialLinkFactory("loop://"), TimeoutLoopFactory(seconds=0.2)])
        link: Any = node.components["serial_link"]
        self.assertFalse(link.is_alive())
        self.assertIsNone(link.port)


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
        collected = PageCollectorFactory(["temp_c", "serial_text", "motor"], stop_after=4)
        node = NodeThread(
            [
                SerialLinkFactory(self.pty.path, send_keys=["motor"], receive_key="serial_text"),
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
                [SerialLinkFactory(self.pty.path, receive_key="serial_text"), collected]
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
                SerialLinkFactory(self.pty.path, 9600, ["speed"], "arduino", mode="lines"),
                ListReplayerFactory([120], "speed", period_s=0.05),
                collected,
            ]
        )
        self.assertEqual(self.pty.read_lines(1), ["120"])
        self.pty.write(b"ok 120\r\nbad \xff\n")
        node.join()
        self.assertEqual(collected.data(), ["ok 120", "bad \ufffd"])

    def test_a_lost_device_is_reported_and_the_node_stops_cleanly(self) -> None:
        with self.assertLogs("snr.robot.serial_link", "ERROR") as logs:
            node = NodeThread([SerialLinkFactory(self.pty.path)])
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
        self.assertIn("'/dev/ttyNOPE42' does not exist", message)
        self.assertRegex(message, "Serial ports on this computer|No serial ports were found")

    def test_permission_denied_explains_the_dialout_group(self) -> None:
        # The tests may run as root, who is never denied, so make the error by hand.
        from snr.std_mods.comms.serial_link import describe_open_error

        denied = serial.SerialException(errno.EACCES, "could not open port /dev/ttyUSB0")
        message = str(describe_open_error("/dev/ttyUSB0", denied))
        self.assertIn("Permission denied", message)
        self.assertIn("usermod -a -G dialout", message)
        self.assertIn("log out and back in", message)
        busy = serial.SerialException(errno.EBUSY, "could not open port")
        self.assertIn("busy", str(describe_open_error("/dev/ttyUSB0", busy)))

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
        self.assertEqual(len(logs.output), 4)  # about lines 1, 2, 4 and 8 of 9
        stored = [task.val_list[0] for task in node.scheduled]
        self.assertEqual([p.data for p in stored[:9]], [f"noise {i}" for i in range(9)])
        self.assertEqual({p.key for p in stored[:9]}, {"serial_in"})
        self.assertEqual((stored[9].key, stored[9].data), ("x", 1))

    def test_without_pyserial_the_error_says_how_to_install_it(self) -> None:
        hidden = {"serial": None, "serial.tools": None, "serial.tools.list_ports": None}
        with mock.patch.dict(sys.modules, hidden):
            with self.assertRaises(CommsError) as caught:
                SerialLinkFactory("/dev/ttyACM0")
        self.assertIn("pip install 'snr[serial]'", str(caught.exception))
