"""docs/tutorial.md: each step prints exactly what the page shows.

Each transcript on the page (a block starting with ``$ command``) is run here
as a student runs it, from a fresh folder, and its output is compared with
the page's by the rules of `tests.tutorial_transcripts` (clock times, ports,
durations, repeated readings, and lines that come or not with timing). A
step that runs for seconds is run shorter with an option the page documents
(``--seconds``, ``--tick-s``); ``--port`` picks a free port. Steps that are
one node run in this process; the ones that need two processes or Ctrl-C run
as subprocesses.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import queue
import re
import runpy
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from typing import Callable, Dict, Iterator, List, Optional

from snr.core.logs import LOG_FORMAT
from snr.std_mods.io.remote_console import RemoteConsole
from tests.examples_support import ROOT, TUTORIAL, script_env
from tests.helpers import free_port
from tests.quiet import captured_logs
from tests.tutorial_transcripts import compare, transcripts

PAGE = os.path.join(ROOT, "docs", "tutorial.md")
SENSOR_PORT = 9010  # the ports the page shows
CONSOLE_PORT = 9123


@contextlib.contextmanager
def terminal() -> Iterator[io.StringIO]:
    """stdout, stderr and SNR's log lines in one buffer, in order, as a terminal shows them."""
    screen = io.StringIO()
    handler = logging.StreamHandler(screen)
    handler.setFormatter(logging.Formatter(LOG_FORMAT, datefmt="%H:%M:%S"))
    # Only to the screen: not also to the stderr handler an earlier node may have
    # given "snr"; and the levels these DEBUG nodes set are put back afterwards.
    with captured_logs("snr"):
        logging.getLogger("snr").addHandler(handler)  # so SNR's stderr handler steps aside
        with contextlib.redirect_stdout(screen), contextlib.redirect_stderr(screen):
            yield screen


class Process:
    """A step run as a subprocess; its stdout and stderr merged, line by line as they come."""

    def __init__(self, args: List[str], cwd: str) -> None:
        self.process = subprocess.Popen(
            [sys.executable, *args],
            cwd=cwd,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=script_env({"PYTHONUNBUFFERED": "1"}),  # stdout and stderr in order
            # Ctrl-C must work in the child even when this process ignores it.
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: List[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put(line.rstrip("\n"))

    def wait_for(self, pattern: str, timeout_s: float = 10.0) -> str:
        """The first new line matching ``pattern``; fails after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                line = self.lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                message = f"No line matching {pattern!r}; it printed {self.seen}"
                raise AssertionError(message) from None
            self.seen.append(line)
            if re.search(pattern, line):
                return line

    def output(self, timeout_s: float = 10.0) -> str:
        """Everything it printed, once it has ended by itself."""
        self.process.wait(timeout_s)
        self.reader.join(timeout_s)
        while not self.lines.empty():
            self.seen.append(self.lines.get())
        return "\n".join(self.seen)

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(10)
        self.reader.join(10)
        if self.process.stdout is not None:
            self.process.stdout.close()


class TestComparisonRules(unittest.TestCase):
    """The rules of `tests.tutorial_transcripts`, each on its own."""

    def test_clock_times_ports_and_durations_may_differ(self) -> None:
        page = [
            "12:00:00 snr.a.sockets_server_9010 INFO: Listening on 127.0.0.1:9010",
            "12:00:01 snr.a INFO: Client from 127.0.0.1:53302",
            "Ran 5 tests in 0.041s",
        ]
        run = (
            "23:59:58 snr.a.sockets_server_40001 INFO: Listening on 127.0.0.1:40001\n"
            "23:59:59 snr.a INFO: Client from 127.0.0.1:38114\n"
            "Ran 5 tests in 1.250s\n"
        )
        self.assertIsNone(compare(page, run, {40001: 9010}))

    def test_a_line_added_removed_or_changed_is_a_difference(self) -> None:
        page = ["Hello #1", "12:00:00 snr.a INFO: stopped"]
        for run in [
            "Hello #1\nHello #2\n12:00:00 snr.a INFO: stopped",  # added
            "12:00:00 snr.a INFO: stopped",  # removed
            "Hello #1\n12:00:00 snr.a WARNING: stopped",  # changed
            "Hello #1\n12:00:00 snr.a INFO: stopped\nBye",  # added at the end
        ]:
            with self.subTest(run=run):
                self.assertIsNotNone(compare(page, run))

    def test_dots_stand_for_one_or_more_lines_of_the_same_shape(self) -> None:
        page = ["depth 2.00 m", "depth 2.33 m", "...", "done"]
        self.assertIsNone(compare(page, "depth 2.00 m\ndepth 2.62 m\ndepth 3.1 m\ndone"))
        self.assertIsNotNone(compare(page, "depth 2.00 m\ndone"))  # none at all
        self.assertIsNotNone(compare(page, "depth 2.00 m\nheight 2.33 m\ndone"))  # another shape

    def test_only_the_listed_timing_lines_are_dropped(self) -> None:
        page = ["ready"]
        late = "12:00:00 snr.s INFO: No peer is connected, so the page under 'x' is not sent."
        self.assertIsNone(compare(page, f"ready\n{late}"))
        self.assertIsNotNone(compare(page, "ready\n12:00:00 snr.s INFO: Something else"))

    def test_the_page_has_a_transcript_per_command(self) -> None:
        markdown = "```\n$ python a.py\nA\n```\n\n```python\nx = 1\n```\n\n```\nno command\n```\n"
        self.assertEqual(transcripts(markdown), {"$ python a.py": ["A"]})


class TestTutorialTranscripts(unittest.TestCase):
    page: Dict[str, List[str]]

    @classmethod
    def setUpClass(cls) -> None:
        with open(PAGE, encoding="utf-8") as f:
            cls.page = transcripts(f.read())

    def setUp(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-tutorial-")
        self.addCleanup(shutil.rmtree, self.folder, True)

    # -- helpers ----------------------------------------------------------------
    def shown(self, command: str) -> List[str]:
        """The lines the page shows under ``$ command``."""
        self.assertIn(f"$ {command}", self.page, "The page has no transcript for this command.")
        return self.page[f"$ {command}"]

    def assertPrints(
        self, command: str, output: str, ports: Optional[Dict[int, int]] = None
    ) -> None:
        """Fail unless ``output`` is what the page shows under ``$ command``."""
        difference = compare(self.shown(command), output, ports)
        if difference is not None:
            self.fail(f"`{command}` does not print what docs/tutorial.md shows.\n{difference}")

    def run_in_process(self, command: str, *extra: str) -> str:
        """Run ``python step.py ARGS`` here, from the temp folder; what it printed."""
        words = command.split()
        self.assertEqual(words[0], "python")
        script = os.path.join(TUTORIAL, words[1])
        argv, path, cwd = sys.argv, list(sys.path), os.getcwd()
        sys.argv = [script, *words[2:], *extra]
        sys.path.insert(0, TUTORIAL)  # as for `python step.py`: the step's siblings import
        os.chdir(self.folder)
        try:
            with terminal() as screen:
                try:
                    runpy.run_path(script, run_name="__main__")
                except SystemExit as done:
                    self.assertIn(done.code, (0, None, False), screen.getvalue())
        finally:
            sys.argv, sys.path[:] = argv, path
            os.chdir(cwd)
        return screen.getvalue()

    def start(self, command: str, *extra: str) -> Process:
        """Start ``python step.py ARGS`` as a subprocess in the temp folder."""
        words = command.split()
        script = os.path.join(self.folder, words[1])
        if not os.path.exists(script):
            script = os.path.join(TUTORIAL, words[1])
        process = Process([script, *words[2:], *extra], self.folder)
        self.addCleanup(process.kill)
        return process

    # -- the steps --------------------------------------------------------------
    def test_every_transcript_on_the_page_is_checked(self) -> None:
        checked = {
            f"$ {command}"
            for command in [
                "python step01_first_endpoint.py",
                "python step02_pages_and_keys.py",
                "python step03_a_loop.py",
                "python step04_two_nodes.py display",
                "python step04_two_nodes.py sensor",
                "python step05_testing.py",
                "python step06_hot_reload.py",
                "python step06_hot_reload.py --no-watch --tick-s 60",
                f"snr-console 127.0.0.1:{CONSOLE_PORT}",
                "python step07_record_replay.py record",
                "python step07_record_replay.py replay",
            ]
        }
        self.assertEqual(set(self.page), checked)

    def test_step01_first_endpoint(self) -> None:
        command = "python step01_first_endpoint.py"
        self.assertPrints(command, self.run_in_process(command))

    def test_step02_pages_and_keys(self) -> None:
        command = "python step02_pages_and_keys.py"
        self.assertPrints(command, self.run_in_process(command))

    def test_step03_a_loop(self) -> None:
        command = "python step03_a_loop.py"
        self.assertPrints(command, self.run_in_process(command, "--seconds", "0.3"))

    def test_step04_two_nodes_in_two_terminals(self) -> None:
        port = free_port()
        display = self.start("python step04_two_nodes.py display", "--port", str(port))
        display.wait_for("Listening for sockets clients")
        # Readings at 0, 0.2, ... 0.8 s (5 a second): the stop at 0.9 s is 0.1 s from
        # the nearest, and a busy machine has 0.8 s to open the link.
        sensor = self.start(
            "python step04_two_nodes.py sensor", "--port", str(port), "--seconds", "0.9"
        )
        ports = {port: SENSOR_PORT}
        self.assertPrints("python step04_two_nodes.py sensor", sensor.output(), ports)
        self.assertPrints("python step04_two_nodes.py display", display.output(), ports)

    def test_step05_testing(self) -> None:
        command = "python step05_testing.py"
        self.assertPrints(command, self.run_in_process(command))

    def copy_step06(self) -> Callable[[str], None]:
        """Copy step 6 to the temp folder; a function that changes its GREETING there."""
        for name in ["step06_hot_reload.py", "step06_greeter.py"]:
            shutil.copy(os.path.join(TUTORIAL, name), self.folder)
        greeter = os.path.join(self.folder, "step06_greeter.py")

        def edit_greeting(greeting: str) -> None:
            with open(greeter, encoding="utf-8") as f:
                source = f.read()
            with open(greeter, "w", encoding="utf-8") as f:
                f.write(re.sub(r'GREETING = ".*"', f'GREETING = "{greeting}"', source))

        return edit_greeting

    @unittest.skipUnless(os.name == "posix", "sends Ctrl-C (SIGINT)")
    def test_step06_reloads_when_saved_and_stops_on_ctrl_c(self) -> None:
        edit_greeting = self.copy_step06()
        port = free_port()
        command = "python step06_hot_reload.py"
        node = self.start(command, "--port", str(port), "--tick-s", "0.05")
        node.wait_for(r"^Hello #2$")
        edit_greeting("Hi there")
        node.wait_for(r"^Hi there #\d+$")
        node.process.send_signal(signal.SIGINT)
        self.assertPrints(command, node.output(), {port: CONSOLE_PORT})

    def test_step06_console_reloads_and_exit_stops_the_node(self) -> None:
        edit_greeting = self.copy_step06()
        port = free_port()
        command = "python step06_hot_reload.py --no-watch --tick-s 60"
        node = self.start(command, "--port", str(port))
        node.wait_for(r"^Hello #1$")
        edit_greeting("Ahoy")
        console_command = f"snr-console 127.0.0.1:{CONSOLE_PORT}"
        typed = [line.split("> ", 1)[1] for line in self.shown(console_command) if "> " in line]
        screen = io.StringIO()
        lines = iter(typed)

        def type_line(prompt: str) -> str:
            line = next(lines)  # runs out only if the node outlives `exit`
            screen.write(f"{prompt}{line}\n")  # the terminal echoes what was typed
            return line

        console = RemoteConsole("127.0.0.1", port)  # as snr-console's main() does:
        try:
            screen.write(console.connect().text + "\n")
            code = console.interact(read_line=type_line, output=screen)
        finally:
            console.close()
        self.assertEqual(code, 0)
        ports = {port: CONSOLE_PORT}
        self.assertPrints(console_command, screen.getvalue(), ports)
        self.assertPrints(command, node.output(), ports)

    def test_step07_records_under_runs_then_replays(self) -> None:
        record = "python step07_record_replay.py record"
        self.assertPrints(record, self.run_in_process(record))
        self.assertTrue(os.path.isfile(os.path.join(self.folder, "runs", "depth_run.jsonl")))
        replay = "python step07_record_replay.py replay"
        self.assertPrints(replay, self.run_in_process(replay))


if __name__ == "__main__":
    unittest.main()
