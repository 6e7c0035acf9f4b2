"""examples/controller: the game controller over sockets (thesis 5.4.1, listing 5.3)."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import unittest
from types import ModuleType
from typing import Callable, List

import snr
from snr import ExpectorEndpointFactory, SimulatedJoystick, SNRTestCase, TaskType
from tests.helpers import free_port

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLE = os.path.join(ROOT, "examples", "controller", "main.py")
Y_RELEASED = "(event, 'button_released'): ['Y']"
PRESSED = (TaskType.event, "button_pressed")
RELEASED = (TaskType.event, "button_released")
FIGURE_5_4_LINES = [  # what the default simulated script makes the receiver print
    f"(event, '{change}'): ['{button}']"
    for button in ["A", "B", "X", "Y", "left_trigger", "right_trigger"]
    for change in ["button_pressed", "button_released"]
]


def load_example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("controller_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def stepping_clock(step_s: float) -> Callable[[], float]:
    """Moves ``step_s`` per read, so the script plays in a fixed number of passes."""
    now = [0.0]

    def clock() -> float:
        now[0] += step_s
        return now[0]

    return clock


class TestControllerExample(SNRTestCase):
    def setUp(self) -> None:
        self.example = load_example()

    def test_options_go_to_the_example_and_the_role_to_the_runner(self) -> None:
        options, rest = self.example.parse_options(
            ["main.py", "input_device", "--simulated", "--port", "9123", "--mode", "test"]
        )
        self.assertEqual((options.simulated, options.port, options.seconds), (True, 9123, None))
        self.assertEqual(rest, ["input_device", "--mode", "test"])

    def test_both_pipelines_in_one_node_print_figure_5_4_lines(self) -> None:
        # Without sockets: the input device's parts feed the receiver's directly.
        pad = SimulatedJoystick(clock=stepping_clock(0.005))  # 0.135 s of script a pass
        input_device = self.example.input_device_parts(pad)
        # The script plays in a fixed number of passes (the clock steps per read),
        # so only the wall time depends on the rate: 20 passes a second would take 1 s.
        input_device[0].max_tick_rate_hz = 500
        out = io.StringIO()
        with self.expector({PRESSED: 6, RELEASED: 6}) as expector, contextlib.redirect_stdout(out):
            self.run_test_node([
                *input_device,
                *self.example.receiver_parts(),
                ExpectorEndpointFactory(expector, exit_when_satisfied=True),
            ])  # fmt: skip
        self.assertEqual(out.getvalue().splitlines(), FIGURE_5_4_LINES)

    @unittest.skipUnless(hasattr(snr, "SocketsPair"), "snr.SocketsPair is not built yet")
    def test_two_nodes_over_sockets(self) -> None:
        """Listing 5.3 as a student runs it: two processes, as in two terminals."""
        port = str(free_port())
        env = dict(os.environ, PYTHONPATH=ROOT, SDL_VIDEODRIVER="dummy", SDL_AUDIODRIVER="dummy")
        command = [sys.executable, EXAMPLE]

        def start(*args: str) -> subprocess.Popen[str]:
            return subprocess.Popen(
                [*command, *args, "--port", port, "--seconds", "30"],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env=env,
            )

        ctrl_c = signal.SIGINT if os.name == "posix" else signal.SIGTERM
        receiver = start("receiver")
        sender = None
        try:
            # Start the input device once the server listens, as a student would.
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:
                with (
                    contextlib.suppress(OSError),
                    socket.create_connection(("127.0.0.1", int(port)), timeout=1),
                ):
                    break
                time.sleep(0.02)
            # The receiver prints (and flushes) a line per event: read them as
            # they come, so the test stops it once Y's release is in.
            out_lines: List[str] = []
            err_lines: List[str] = []
            readers = [
                threading.Thread(target=lambda: out_lines.extend(receiver.stdout or [])),
                threading.Thread(target=lambda: err_lines.extend(receiver.stderr or [])),
            ]
            for reader in readers:
                reader.start()
            # Y is released 1.6 s into the pad's script, which starts with the node.
            sender = start("input_device", "--simulated")
            deadline = time.monotonic() + 15
            while Y_RELEASED not in "".join(out_lines) and time.monotonic() < deadline:
                time.sleep(0.01)
            # Stop both with Ctrl-C, as in thesis figure 5.4: the input device first.
            sender.send_signal(ctrl_c)
            _, sender_err = sender.communicate(timeout=10)
            receiver.send_signal(ctrl_c)
            receiver.wait(timeout=10)
            for reader in readers:
                reader.join(10)
            out, err = "".join(out_lines), "".join(err_lines)
        finally:
            for process in (sender, receiver):
                if process is None:
                    continue
                if process.poll() is None:
                    process.kill()
                    process.wait()
                for stream in (process.stdout, process.stderr):
                    if stream is not None:
                        stream.close()
        self.assertEqual(sender.returncode, 0, sender_err)
        self.assertEqual(receiver.returncode, 0, err)
        printed: List[str] = [line for line in out.splitlines() if line.startswith("(event")]
        # Presses made before the client had connected may be missed; the rest
        # arrive in order, each printed exactly once.
        self.assertIn("(event, 'button_pressed'): ['Y']", printed)
        self.assertIn(Y_RELEASED, printed)
        first = FIGURE_5_4_LINES.index(printed[0])
        self.assertEqual(printed, FIGURE_5_4_LINES[first : first + len(printed)])
        self.assertIn("Interrupted by user, exiting", out)


if __name__ == "__main__":
    unittest.main()
