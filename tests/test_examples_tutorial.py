"""examples/tutorial: every step of docs/tutorial.md runs and does what the page says."""

import contextlib
import io
import os
import queue
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from typing import List, Optional

import snr
from tests.examples_support import TUTORIAL, load_module, run_script, script_env
from tests.helpers import StopWhenFactory


def step(name: str) -> str:
    return os.path.join(TUTORIAL, name)


def run_step_in_process(file: str, role: str) -> List[str]:
    """Load a step, run its ``config`` for ``role``, and return what it printed."""
    module = load_module(step(file), f"tutorial_{file[:-3]}")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        snr.SynchronousRunner(role, module.config).run()
    return out.getvalue().splitlines()


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class LiveOutput:
    """The lines a running subprocess prints, as they come."""

    def __init__(self, process: "subprocess.Popen[str]") -> None:
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: List[str] = []
        assert process.stdout is not None
        stream = process.stdout
        self.thread = threading.Thread(target=self._read, args=(stream,), daemon=True)
        self.thread.start()

    def _read(self, stream: io.TextIOBase) -> None:
        for line in stream:
            self.lines.put(line.rstrip("\n"))

    def wait_for(self, pattern: str, timeout_s: float = 10.0) -> Optional[str]:
        """The first new line matching ``pattern``, or None after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                line = self.lines.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                break
            self.seen.append(line)
            if re.search(pattern, line):
                return line
        return None


class TestTutorialSteps(unittest.TestCase):
    def test_step01_first_endpoint(self) -> None:
        printed = run_step_in_process("step01_first_endpoint.py", "greeter")
        self.assertEqual(printed, ["Hello, world!"])

    def test_step02_pages_and_keys(self) -> None:
        printed = run_step_in_process("step02_pages_and_keys.py", "thermometer_node")
        self.assertEqual(
            printed,
            [
                "temperature_f = 68.0 (from thermometer_node)",
                "temperature_f = 70.7 (from thermometer_node)",
                "temperature_f = 73.4 (from thermometer_node)",
                "newest temperature_c in the datastore: 23.0",
            ],
        )

    def test_step03_a_loop(self) -> None:
        loop_step = load_module(step("step03_a_loop.py"), "tutorial_step03_a_loop")
        self.assertEqual(loop_step.config.roles(), ["submarine"])
        # The step's parts, faster: 50 readings a second, until three are printed.
        config = snr.Config(
            {
                "submarine": [
                    loop_step.DepthSensorFactory(rate_hz=50),
                    loop_step.DepthPrinterFactory(),
                    StopWhenFactory((snr.TaskType.store_page, "depth_m"), count=3),
                    snr.TimeoutLoopFactory(seconds=5),  # only if the stop never comes
                ]
            }
        )
        out = io.StringIO()
        runner = snr.SynchronousRunner("submarine", config)
        with contextlib.redirect_stdout(out):
            runner.run()
        assert runner.node is not None
        self.assertEqual(runner.node.terminate_reason, "test work done")
        printed = out.getvalue().splitlines()
        self.assertGreaterEqual(len(printed), 3)
        self.assertEqual(printed[0], "depth 2.00 m")
        for line in printed:
            self.assertRegex(line, r"^depth \d\.\d\d m$")

    def test_step05_testing(self) -> None:
        tests = load_module(step("step05_testing.py"), "tutorial_step05_testing")
        suite = unittest.defaultTestLoader.loadTestsFromModule(tests)
        result = unittest.TextTestRunner(stream=io.StringIO(), verbosity=0).run(suite)
        self.assertTrue(result.wasSuccessful(), result.failures + result.errors)
        self.assertEqual(result.testsRun, 5)


class TestStepsWithProcesses(unittest.TestCase):
    def setUp(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-tutorial-")
        self.addCleanup(shutil.rmtree, self.folder, True)

    def start(self, *args: str) -> "subprocess.Popen[str]":
        process = subprocess.Popen(
            [sys.executable, *args],
            cwd=self.folder,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=script_env(),
        )

        def stop() -> None:
            if process.poll() is None:
                process.kill()
            process.communicate(timeout=10)

        self.addCleanup(stop)
        return process

    @unittest.skipUnless(hasattr(snr, "SocketsPair"), "snr.SocketsPair is not built yet")
    def test_step04_two_nodes(self) -> None:
        port = str(free_port())
        args = [
            step("step04_two_nodes.py"),
            "display",
            "sensor",
            "--port",
            port,
            "--seconds",
            "1.0",
        ]
        done = run_script(args, cwd=self.folder, timeout_s=30)
        self.assertEqual(done.returncode, 0, done.stderr)
        received = [line for line in done.stdout.splitlines() if "measured by sensor" in line]
        self.assertGreaterEqual(len(received), 2, done.stdout + done.stderr)

    def copy_step06(self) -> str:
        for name in ["step06_hot_reload.py", "step06_greeter.py"]:
            shutil.copy(step(name), self.folder)
        return os.path.join(self.folder, "step06_greeter.py")

    def edit_greeting(self, greeter: str, greeting: str) -> None:
        with open(greeter, encoding="utf-8") as f:
            source = f.read()
        source = re.sub(r'GREETING = ".*"', f'GREETING = "{greeting}"', source)
        with open(greeter, "w", encoding="utf-8") as f:
            f.write(source)

    def test_step06_reloads_when_the_file_is_saved(self) -> None:
        greeter = self.copy_step06()
        node = self.start("step06_hot_reload.py", "--no-console", "--tick-s", "0.1")
        output = LiveOutput(node)
        self.assertIsNotNone(output.wait_for(r"^Hello #2$"), output.seen)
        self.edit_greeting(greeter, "Hi there")
        self.assertIsNotNone(output.wait_for(r"changed: reloading 'greeter'"), output.seen)
        line = output.wait_for(r"^Hi there #\d+$")
        self.assertIsNotNone(line, output.seen)
        # The count went on: it is kept on the factory, which the reload keeps.
        assert line is not None
        self.assertGreater(int(line.split("#")[1]), 2)
        node.terminate()

    @unittest.skipUnless(
        hasattr(snr, "CommandReceiverFactory"), "snr.CommandReceiverFactory is not built yet"
    )
    def test_step06_reloads_from_the_console(self) -> None:
        greeter = self.copy_step06()
        port = str(free_port())
        node = self.start("step06_hot_reload.py", "--no-watch", "--port", port, "--tick-s", "0.1")
        output = LiveOutput(node)
        self.assertIsNotNone(output.wait_for(r"^Hello #2$"), output.seen)
        self.edit_greeting(greeter, "Ahoy")
        console = run_script(["-m", "snr.console", f"127.0.0.1:{port}", "-c", "reload greeter"])
        self.assertEqual(console.returncode, 0, console.stdout + console.stderr)
        self.assertIn("Reloaded 'greeter'", console.stdout)
        self.assertIsNotNone(output.wait_for(r"^Ahoy #\d+$"), output.seen)
        node.terminate()

    @unittest.skipUnless(
        hasattr(snr, "RecorderEndpointFactory") and hasattr(snr, "ReplayerLoopFactory"),
        "the recorder and replayer are not built yet",
    )
    def test_step07_record_then_replay(self) -> None:
        script = step("step07_record_replay.py")
        recorded = run_script([script, "record", "--file", "run.jsonl"], cwd=self.folder)
        self.assertEqual(recorded.returncode, 0, recorded.stderr)
        self.assertTrue(os.path.exists(os.path.join(self.folder, "run.jsonl")))
        replayed = run_script([script, "replay", "--file", "run.jsonl"], cwd=self.folder)
        self.assertEqual(replayed.returncode, 0, replayed.stderr)
        lines = replayed.stdout.splitlines()
        self.assertEqual(len(lines), 20)  # every recorded reading, filtered
        self.assertTrue(all(line.endswith("(recorded by record)") for line in lines), lines)


if __name__ == "__main__":
    unittest.main()
