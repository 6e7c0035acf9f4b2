"""The board protocol of the serial link: ready line, heartbeats, failsafe, replugging.

The link's side runs against a pseudo-terminal, as in test_serial_link.py;
the board's side is played by the test, or by the MicroPython helper of
examples/boards/ running under CPython.
"""

from __future__ import annotations

import importlib.util
import json
import logging
import os
import re
import select
import shutil
import subprocess
import tempfile
import time
import unittest
from types import ModuleType
from typing import Any, Callable, List, Tuple

from snr import Page, SerialLinkFactory, SNRTestCase, tasks
from snr.extras.serial import board as board_protocol
from snr.extras.serial.board import READY_LINE, BoardWatch, compact_line
from snr.prelude import ConfigError
from tests.examples_support import ROOT
from tests.page_collector import PageCollectorFactory
from tests.test_serial_link import QUICK, NodeThread, PtyPair, needs_pty, needs_pyserial

BOARDS = os.path.join(ROOT, "examples", "boards")
READY = READY_LINE.encode() + b"\r\n"


def load_micropython_helper() -> ModuleType:
    """examples/boards/micropython/snr_board.py, imported as the board imports it."""
    path = os.path.join(BOARDS, "micropython", "snr_board.py")
    spec = importlib.util.spec_from_file_location("snr_board", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def wait_for(condition: Callable[[], Any], what: str, timeout_s: float = 5.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.005)


def node_of(thread: NodeThread) -> Any:
    wait_for(lambda: thread.runner.node is not None, "the node")
    return thread.runner.node


def port_opened(thread: NodeThread) -> Any:
    """The node's serial link, once its port is open: pyserial empties the port on opening,
    so a board's output counts only from then on (a real board resets then, too)."""
    node = node_of(thread)
    wait_for(lambda: getattr(node.components.get("serial_link"), "port", None), "the port")
    return node.components["serial_link"]


class TestBoardWatch(unittest.TestCase):
    """The computer's side of the protocol, on a clock the test turns."""

    def test_lines_before_the_ready_line_are_boot_noise(self) -> None:
        watch = BoardWatch(ready_timeout_s=5.0)
        watch.opened(now_s=0.0)
        self.assertFalse(watch.ready)
        self.assertEqual(watch.line(b"\x00\xf0garbage", 0.5), "boot")
        self.assertEqual(watch.line(b"Booting v1.2\r", 0.6), "boot")
        self.assertEqual(watch.tick(4.9), [])
        # bootloader bytes glued to the front of the ready line do not hide it
        self.assertEqual(watch.line(b"\xfe\xfe" + READY_LINE.encode() + b"\r", 1.5), "ready")
        self.assertEqual((watch.ready, watch.boot_lines), (True, 2))
        self.assertEqual(watch.line(b'{"key":"x","data":1}', 1.6), "use")
        self.assertEqual(watch.line(READY_LINE.encode(), 2.0), "ready-again")  # it restarted
        watch.opened(now_s=10.0)  # reopened: the board starts again
        self.assertEqual(watch.line(b'{"key":"x","data":1}', 10.1), "boot")

    def test_no_ready_line_in_time_is_reported_once_then_lines_are_used(self) -> None:
        watch = BoardWatch(ready_timeout_s=2.0, answer_timeout_s=1.0)
        watch.opened(now_s=0.0)
        self.assertEqual(watch.tick(1.9), [])
        self.assertEqual(watch.tick(2.0), ["ready-timeout"])
        self.assertEqual(watch.tick(2.5), [])  # silence is counted from the timeout
        self.assertEqual(watch.line(b"hello", 2.6), "use")
        self.assertEqual(watch.line(READY_LINE.encode(), 2.7), "ready")  # late, but welcome

    def test_silence_is_reported_once_and_the_answer_after_it(self) -> None:
        watch = BoardWatch(answer_timeout_s=1.0)
        watch.opened(now_s=0.0)
        self.assertEqual(watch.line(b"a", 0.5), "use")
        self.assertEqual(watch.tick(1.4), [])
        self.assertEqual(watch.tick(1.5), ["silent"])
        self.assertEqual(watch.tick(9.0), [])
        self.assertEqual(watch.line(b"b", 9.5), "use-again")
        self.assertEqual(watch.last_silence_s, 9.0)
        self.assertEqual(watch.line(b"c", 9.6), "use")

    def test_heartbeats_are_due_at_their_period_with_no_burst_after_a_stall(self) -> None:
        watch = BoardWatch(heartbeat_s=0.2)
        watch.opened(now_s=0.0)
        self.assertEqual(watch.tick(0.0), ["heartbeat"])
        self.assertEqual(watch.tick(0.1), [])
        self.assertEqual(watch.tick(0.2), ["heartbeat"])
        self.assertEqual(watch.tick(5.0), ["heartbeat"])  # one, not 24
        self.assertEqual(watch.tick(5.1), [])

    def test_no_heartbeat_before_the_board_is_ready(self) -> None:
        watch = BoardWatch(ready_timeout_s=5.0, heartbeat_s=0.2)
        watch.opened(now_s=0.0)
        self.assertEqual(watch.tick(1.0), [])
        watch.line(READY_LINE.encode(), 1.2)
        self.assertEqual(watch.tick(1.3), ["heartbeat"])

    @needs_pyserial  # the factory checks for pyserial first
    def test_bad_settings_are_config_errors(self) -> None:
        for bad in (0, -1.0, "1s"):
            with self.assertRaises(ConfigError):
                SerialLinkFactory("loop://", heartbeat_s=bad)  # type: ignore[arg-type]
        with self.assertRaises(ConfigError) as caught:
            SerialLinkFactory("loop://", mode="lines", compact=True)
        self.assertIn("mode='pages'", str(caught.exception))

    def test_compact_lines_fit_an_uno_s_receive_buffer(self) -> None:
        page = Page("motor", {"left": 100, "right": -100, "vertical": 0}, "urov", 1.7e9)
        self.assertEqual(
            compact_line(page), '{"key":"motor","data":{"left":100,"right":-100,"vertical":0}}'
        )
        self.assertLess(len(compact_line(page)) + 1, board_protocol.UNO_RX_BUFFER_BYTES)
        self.assertLess(len(READY_LINE) + 1, board_protocol.UNO_RX_BUFFER_BYTES)


@needs_pyserial
@needs_pty
class TestLinkAndBoard(SNRTestCase):
    """The link against a board played by the test on a pseudo-terminal."""

    def setUp(self) -> None:
        self.pty = PtyPair()
        self.addCleanup(self.pty.close)

    def test_boot_noise_and_a_late_ready_line_lose_and_garble_nothing(self) -> None:
        collected = PageCollectorFactory(["motor", "temp_c", "serial_in"], stop_after=3)
        with self.assertLogs("snr.robot.serial_link", logging.INFO) as logs:
            node = NodeThread(
                [
                    SerialLinkFactory(
                        self.pty.path,
                        send_keys=["motor"],
                        ready_timeout_s=5.0,
                        compact=True,
                        read_timeout_s=QUICK,
                    ),
                    collected,
                ]
            )
            port_opened(node)
            # The board resets: boot noise, some of it with no line break.
            self.pty.write(b"\x00\xf0\xfe")
            self.pty.write(b"Booting v1.2\r\n{half a page\r\n")
            node_of(node).schedule(tasks.store_data("motor", [10, 10, 0]))
            node_of(node).schedule(tasks.store_data("motor", [50, -50, 0]))
            wait_for(lambda: len(collected.pages) == 2, "the motor pages to be stored")
            self.pty.write(b"\xfe" + READY)  # late, and glued to a stray byte
            lines = self.pty.read_lines(3)
            self.pty.write(b'{"key":"temp_c","data":21.5}\r\n')
            node.join()
        # The first bytes the board sees are the header, then the commands held
        # for it while it started, in order, whole and compact.
        self.assertEqual(
            lines,
            [READY_LINE, '{"key":"motor","data":[10,10,0]}', '{"key":"motor","data":[50,-50,0]}'],
        )
        link: Any = node.runner.node.components["serial_link"]  # type: ignore[union-attr]
        self.assertEqual(link.boot_lines, 2)
        self.assertEqual(collected.pages[2].key, "temp_c")  # the noise is not stored
        self.assertIn("is ready (2 lines of boot output skipped)", "\n".join(logs.output))

    def test_no_ready_line_in_time_says_what_to_print_and_sends_anyway(self) -> None:
        with self.assertLogs("snr.robot.serial_link", logging.ERROR) as logs:
            node = NodeThread(
                [
                    SerialLinkFactory(
                        self.pty.path,
                        send_keys=["motor"],
                        ready_timeout_s=0.1,
                        read_timeout_s=QUICK,
                    )
                ]
            )
            node_of(node).schedule(tasks.store_data("motor", 1))
            header, page = self.pty.read_lines(2)
            node.stop()
            node.join()
        self.assertEqual(header, READY_LINE)
        self.assertEqual(json.loads(page)["data"], 1)
        self.assertIn("sent no ready line within 0.1 s", logs.output[0])
        self.assertIn(READY_LINE, logs.output[0])

    def test_heartbeats_flow_and_a_board_that_stops_answering_is_reported(self) -> None:
        answer_s = 0.3
        with self.assertLogs("snr.robot.serial_link", logging.INFO) as logs:
            node = NodeThread(
                [
                    SerialLinkFactory(
                        self.pty.path,
                        ready_timeout_s=5.0,
                        heartbeat_s=0.02,
                        answer_timeout_s=answer_s,
                        read_timeout_s=QUICK,
                    )
                ]
            )
            port_opened(node)
            self.pty.write(READY)
            header, *beats = self.pty.read_lines(3)
            for n in range(3):  # the board's heartbeats
                self.pty.write(b'{"key":"hb","data":%d}\r\n' % n)
            last_line_s = time.time()  # the clock of log records
            wait_for(lambda: "stopped answering" in "\n".join(logs.output), "the report")
            self.pty.write(b'{"key":"hb","data":3}\r\n')
            wait_for(lambda: "answers again" in "\n".join(logs.output), "the recovery")
            node.stop()
            node.join()
        self.assertEqual(header, READY_LINE)
        self.assertEqual(beats, ['{"key":"hb","data":0}', '{"key":"hb","data":1}'])
        silent = next(r for r in logs.records if "stopped answering" in r.getMessage())
        self.assertEqual(silent.levelno, logging.WARNING)
        self.assertGreaterEqual(silent.created, last_line_s + answer_s - 0.01)  # not early
        link: Any = node.runner.node.components["serial_link"]  # type: ignore[union-attr]
        self.assertEqual(link.heartbeats_received, 4)  # counted, not stored

    def test_unplug_and_replug_recovers_with_a_new_handshake(self) -> None:
        # /dev/serial/by-id/ names are symlinks: replugging points one at a new device
        folder = tempfile.mkdtemp(prefix="snr-by-id-")
        self.addCleanup(shutil.rmtree, folder, True)
        by_id = os.path.join(folder, "usb-Arduino_Uno_1234-if00")
        os.symlink(self.pty.path, by_id)
        with self.assertLogs("snr.robot.serial_link", logging.INFO) as logs:
            node = NodeThread(
                [
                    SerialLinkFactory(
                        by_id, send_keys=["motor"], ready_timeout_s=5.0, read_timeout_s=QUICK
                    )
                ],
                timeout_s=10.0,
            )
            port_opened(node)
            self.pty.write(READY)
            self.assertEqual(self.pty.read_lines(1), [READY_LINE])
            self.pty.close_master()  # unplugged
            wait_for(lambda: "Lost serial port" in "\n".join(logs.output), "the loss")
            replugged = PtyPair()
            self.addCleanup(replugged.close)
            os.symlink(replugged.path, by_id + ".new")
            os.replace(by_id + ".new", by_id)
            wait_for(lambda: "Reopened" in "\n".join(logs.output), "the reopening")
            node_of(node).schedule(tasks.store_data("motor", 7))  # held until ready
            replugged.write(b"Booting again\r\n" + READY)
            header, page = replugged.read_lines(2)
            node.stop()
            node.join()
        self.assertEqual(header, READY_LINE)
        self.assertEqual(json.loads(page)["data"], 7)
        link: Any = node.runner.node.components["serial_link"]  # type: ignore[union-attr]
        self.assertEqual(link.boot_lines, 1)


class FakeUart:
    """A board's UART whose other end is a list of lines and a list of writes."""

    def __init__(self) -> None:
        self.incoming = b""
        self.written: List[bytes] = []

    def any(self) -> int:
        return len(self.incoming)

    def read(self, count: int) -> bytes:
        data, self.incoming = self.incoming[:count], self.incoming[count:]
        return data

    def write(self, data: bytes) -> int:
        self.written.append(data)
        return len(data)


class PtyUart:
    """A board's UART on the test's end of a pseudo-terminal (``machine.UART``'s calls)."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def any(self) -> int:
        ready, _, _ = select.select([self.fd], [], [], 0)
        return 4096 if ready else 0

    def read(self, count: int) -> bytes:
        return os.read(self.fd, count)

    def write(self, data: bytes) -> int:
        return os.write(self.fd, data)


class TestMicroPythonHelper(unittest.TestCase):
    def setUp(self) -> None:
        self.snr_board = load_micropython_helper()
        self.now_ms = 0
        self.pages: List[Tuple[str, Any]] = []
        self.stops = 0

    def board(self, port: Any, **options: Any) -> Any:
        def stop() -> None:
            self.stops += 1

        return self.snr_board.SnrBoard(
            port, lambda key, data: self.pages.append((key, data)), stop, **options
        )

    def test_the_failsafe_fires_when_commands_and_heartbeats_stop(self) -> None:
        uart = FakeUart()
        board = self.board(uart, clock_ms=lambda: self.now_ms)
        board.begin()
        self.assertEqual(self.stops, 1)  # it starts stopped
        self.assertEqual(uart.written[0], READY_LINE.encode() + b"\n")
        uart.incoming = (
            READY_LINE.encode() + b'\n{"key":"motor","data":[50,-50,0]}\r\n{"key":"hb","data":0}\n'
        )
        board.poll()
        self.assertEqual(self.pages, [("motor", [50, -50, 0])])  # heartbeats are not pages
        self.assertFalse(board.failsafe_active)
        self.now_ms = 999
        board.poll()
        self.assertEqual(self.stops, 1)
        uart.incoming = b'{"key":"hb","data":1}\n'  # a heartbeat keeps it going
        board.poll()
        self.now_ms = 1998
        board.poll()
        self.assertEqual(self.stops, 1)
        self.now_ms = 1999 + 1  # FAILSAFE_MS after the last line
        board.poll()
        board.poll()
        self.assertEqual((self.stops, board.failsafes, board.failsafe_active), (2, 1, True))
        # Hearing nothing, it says it is ready now and every FAILSAFE_MS: a computer
        # that opens the port without resetting the board hears that too.
        uart.written.clear()
        for self.now_ms in (2500, 2999, 3000, 3999, 4000):
            board.poll()
        ready_lines = [line for line in uart.written if line.startswith(b'{"format"')]
        self.assertEqual(len(ready_lines), 2)

    def test_noise_and_long_lines_are_counted_and_reset_nothing(self) -> None:
        uart = FakeUart()
        board = self.board(uart, clock_ms=lambda: self.now_ms)
        board.begin()
        too_long = b'{"key":"x","data":"' + b"y" * 200 + b'"}\n'
        uart.incoming = b"\xff\xfenoise\n[1]\n" + too_long + b'{"key":"ok","data":1}\n'
        board.poll()
        self.assertEqual(self.pages, [("ok", 1)])
        self.assertEqual(board.bad_lines, 3)

    def test_heartbeats_and_pages_it_sends_are_snr_page_lines(self) -> None:
        uart = FakeUart()
        board = self.board(uart, clock_ms=lambda: self.now_ms)
        board.begin()
        for self.now_ms in (0, 100, 200, 250, 400):
            board.poll()
        board.send("depth_m", 2.5)
        lines = b"".join(uart.written).decode().splitlines()
        self.assertEqual(
            lines,
            [
                READY_LINE,
                '{"key":"hb","data":0}',
                '{"key":"hb","data":1}',
                '{"key":"hb","data":2}',
                '{"key":"depth_m","data":2.5}',
            ],
        )

    @needs_pyserial
    @needs_pty
    def test_it_talks_to_the_link_and_its_failsafe_fires_when_the_node_stops(self) -> None:
        pty = PtyPair()
        self.addCleanup(pty.close)
        board = self.board(PtyUart(pty.master), failsafe_ms=150, heartbeat_ms=20)
        collected = PageCollectorFactory(["depth_m"])
        node = NodeThread(
            [
                SerialLinkFactory(
                    pty.path,
                    send_keys=["motor"],
                    ready_timeout_s=5.0,
                    heartbeat_s=0.02,
                    compact=True,
                    read_timeout_s=QUICK,
                ),
                collected,
            ]
        )
        node_of(node).schedule(tasks.store_data("motor", [50, -50, 0]))
        port_opened(node)
        board.begin()

        def poll_until(condition: Callable[[], bool], what: str) -> None:
            deadline = time.monotonic() + 5.0
            while not condition():
                self.assertLess(time.monotonic(), deadline, f"timed out waiting for {what}")
                board.poll()
                time.sleep(0.002)

        poll_until(lambda: bool(self.pages), "the motor command")
        board.send("depth_m", 2.5)
        poll_until(lambda: bool(collected.pages), "the depth page")
        self.assertEqual(self.stops, 1)  # only begin's: heartbeats keep it going
        node.stop()
        node.join()
        poll_until(lambda: board.failsafes == 1, "the failsafe")
        self.assertEqual(self.pages, [("motor", [50, -50, 0])])
        self.assertEqual(collected.data(), [2.5])
        link: Any = node.runner.node.components["serial_link"]  # type: ignore[union-attr]
        self.assertGreater(link.heartbeats_received, 0)


class TestArduinoHelper(unittest.TestCase):
    def test_the_sketch_s_protocol_constants_are_the_link_s(self) -> None:
        with open(os.path.join(BOARDS, "arduino", "snr_board", "SnrBoard.h")) as f:
            header = f.read()
        defines = dict(re.findall(r"#define (SNR_\w+) (.+)", header))
        ready = json.loads(defines["SNR_READY_LINE"])  # a C string literal, JSON-escaped
        self.assertEqual(ready, READY_LINE)
        self.assertEqual(int(defines["SNR_HEARTBEAT_MS"]), board_protocol.HEARTBEAT_S * 1000)
        self.assertEqual(int(defines["SNR_FAILSAFE_MS"]), board_protocol.FAILSAFE_S * 1000)
        self.assertEqual(json.loads(defines["SNR_HEARTBEAT_KEY"]), board_protocol.HEARTBEAT_KEY)
        self.assertLess(int(defines["SNR_MAX_LINE"]), 256)

    @unittest.skipUnless(shutil.which("g++"), "needs a C++ compiler")
    def test_the_header_builds_and_keeps_the_protocol_on_a_computer(self) -> None:
        # tests/data/arduino_host/ fakes the little of Arduino.h the header uses.
        folder = tempfile.mkdtemp(prefix="snr-arduino-")
        self.addCleanup(shutil.rmtree, folder, True)
        program = os.path.join(folder, "snr_host")
        host = os.path.join(ROOT, "tests", "data", "arduino_host")
        sketch = os.path.join(BOARDS, "arduino", "snr_board")
        flags = ["-std=c++11", "-Wall", "-Wextra", "-Werror", "-I", host, "-I", sketch]
        subprocess.run(
            ["g++", *flags, os.path.join(host, "host_main.cpp"), "-o", program],
            check=True,
            timeout=60,
        )
        too_long = '{"key":"x","data":[' + ",".join(["1"] * 60) + "]}"
        commands = [
            "T 0",
            "P",
            f"I {READY_LINE}",
            'I {"key":"motor","data":[50,-50.5]}',
            'I {"key":"hb","data":3}',
            "I garbage",
            'I {"key":"x","data":"text"}',
            f"I {too_long}",
            'I {"key":"depth","data":2.5,"origin":"pi","created_at_s":1.0,"process":true}',
            "P",
            "S depth_m 2.41",
            "T 999",
            "P",
            "T 1000",
            "P",
        ]
        result = subprocess.run(
            [program],
            input="\n".join(commands) + "\n",
            capture_output=True,
            text=True,
            check=True,
            timeout=10,
        )
        self.assertEqual(
            result.stdout.splitlines(),
            [
                "STOP",  # begin() stops the actuators, then says it is ready
                f"W {READY_LINE}",
                'W {"key":"hb","data":0}',
                "PAGE motor 50 -50.5",
                "PAGE depth 2.5",  # a full page line is read too
                'W {"key":"depth_m","data":2.410}',
                'W {"key":"hb","data":1}',
                "STOP",  # FAILSAFE_MS after the last page line
                f"W {READY_LINE}",  # nobody talks to it: it says it is ready
                "BAD 3 FAILSAFES 1",  # garbage, text data, too long
            ],
        )

    def test_the_micropython_helper_s_constants_are_the_link_s(self) -> None:
        helper = load_micropython_helper()
        self.assertEqual(helper.READY_LINE, READY_LINE)
        self.assertEqual(helper.HEARTBEAT_KEY, board_protocol.HEARTBEAT_KEY)
        self.assertEqual(helper.HEARTBEAT_MS, board_protocol.HEARTBEAT_S * 1000)
        self.assertEqual(helper.FAILSAFE_MS, board_protocol.FAILSAFE_S * 1000)


if __name__ == "__main__":
    unittest.main()
