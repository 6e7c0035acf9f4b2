"""Stuck without a word (docs/errors.md entry 17) and unmet expectations (entry 18).

Every mistake runs for real, as the page shows it. Programs that cannot be
stopped from inside (a handler or loop() that never returns, a node nothing
stops) run in subprocesses, all at once, with the watchdog's times cut to a
twentieth; the classes of the others run in a node in this process. Either
way the warning must be the one the page shows, and the wrong advice the
page says is held back must not appear.
"""

from __future__ import annotations

import linecache
import logging
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
import types
import unittest
from typing import Any, Callable, Dict, List, Optional, Tuple

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    LoopFactory,
    Node,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    tasks,
)
from tests.examples_support import ROOT, script_env
from tests.helpers import FactoryOf, LoopFactoryOf, StopWhenFactory

HERE = "test_watchdog.py"
ERRORS_MD = os.path.join(ROOT, "docs", "errors.md")
SAID_ONCE = "(This shows once, in DEBUG mode only; node.watchdog = None turns the watchdog off.)"

# Runs robot.py as `python robot.py robot` would, with the watchdog's times
# (2 s stuck, 3 s idle) cut to 0.1 s and 0.15 s, and a queue of 1,000 tasks.
FAST_WATCHDOG = textwrap.dedent(
    """
    import runpy, sys
    from snr.core.node import Node
    from snr.core.checks.watchdog import Watchdog
    Watchdog.every_s, Watchdog.stuck_s, Watchdog.idle_s = 0.01, 0.1, 0.15
    Node.max_queued_tasks = 1000
    sys.argv = sys.argv[1:]
    runpy.run_path(sys.argv[0], run_name="__main__")
    """
)


def docs_blocks(heading: str, kind: str) -> List[str]:
    """The ```{kind} blocks of the errors.md entry under ``heading`` (e.g. "### 17a")."""
    with open(ERRORS_MD, encoding="utf-8") as f:
        page = f.read()
    start = page.index(f"\n{heading}") + 1
    next_heading = re.compile(r"\n##+ ").search(page, start + len(heading))
    entry = page[start : next_heading.start() if next_heading else len(page)]
    return re.findall(rf"```{kind}\n(.*?)```", entry, re.S)


def docs_entry(entry: str) -> Tuple[str, List[str]]:
    """The program and the output lines of errors.md entry ``entry`` (e.g. "17a")."""
    heading = f"### {entry}"
    return docs_blocks(heading, "python")[0], docs_blocks(heading, "text")[0].splitlines()


def as_in_the_docs(line: str) -> str:
    """A warning as a log record has it, with the default thresholds (2 s, 3 s, 10,000)."""
    line = re.sub(r"^(\d\d:\d\d:\d\d )?snr\.\w+ [A-Z]+: ", "", line)  # as a log record has it
    for fast, default in (("for 0.1 s", "for 2 s"), ("for 0.15 s", "for 3 s")):
        line = line.replace(fast, default)
    return line.replace("(1,000 tasks)", "(10,000 tasks)")


def warnings_of(lines: List[str]) -> List[str]:
    """The watchdog's warnings among ``lines`` of output, as the page shows them."""
    return [as_in_the_docs(line) for line in lines if SAID_ONCE in line]


def shown_in_the_docs(entry: str) -> List[str]:
    """The watchdog's warning in the output errors.md shows for ``entry``."""
    shown = warnings_of(docs_entry(entry)[1])
    assert len(shown) == 1, shown
    return shown


class Program:
    """A student's program running in a subprocess; a thread reads its stderr as it goes.

    With ``kill_at``, the program is killed as soon as a line of its stderr
    holds that text: programs that spin or flood stop using a core the moment
    their warning is out, and the others start sooner.
    """

    def __init__(self, source: str, kill_at: Optional[str] = None) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-watchdog-")
        with open(os.path.join(self.folder, "robot.py"), "w", encoding="utf-8") as f:
            f.write(source)
        self.proc = subprocess.Popen(
            [sys.executable, "-c", FAST_WATCHDOG, "robot.py", "robot"],
            cwd=self.folder,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=script_env(),
        )
        self.kill_at = kill_at
        self.stderr = ""
        self.stdout: Optional[str] = None
        self._ended = False
        self._news = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stderr is not None
        for raw in iter(self.proc.stderr.readline, b""):
            line = raw.decode("utf-8", "replace")
            if self.kill_at is not None and self.kill_at in line and self.proc.poll() is None:
                self.proc.kill()
            with self._news:
                self.stderr += line
                self._news.notify_all()
        with self._news:
            self._ended = True
            self._news.notify_all()

    def wait_for(self, text: str, timeout_s: float = 15.0) -> bool:
        """Wait until a line of stderr holds ``text``; False if it ends or times out first."""
        with self._news:
            self._news.wait_for(lambda: text in self.stderr or self._ended, timeout_s)
            return text in self.stderr

    def stop(self, signum: int = signal.SIGKILL) -> Tuple[str, str]:
        """Send ``signum`` unless it has ended; then its stdout and stderr (again if asked)."""
        if self.stdout is None:
            if self.proc.poll() is None:
                self.proc.send_signal(signum)
            self.proc.wait(15)
            self._reader.join(15)
            assert self.proc.stdout is not None and self.proc.stderr is not None
            self.stdout = self.proc.stdout.read().decode("utf-8", "replace")
            self.proc.stdout.close()
            self.proc.stderr.close()
            shutil.rmtree(self.folder, ignore_errors=True)
        return self.stdout, self.stderr


# Two programs that must not be told they will never stop.
STOPPED_BY_A_TIMER = """
import threading
from snr import *

class Beeper(Endpoint):
    def __init__(self, factory, parent):
        super().__init__(factory, parent, "beeper")

    def begin(self):
        # Something will stop the node: a timer thread, 0.5 s from now.
        threading.Timer(0.5, self.schedule, [tasks.terminate("timer")]).start()

class BeeperFactory(EndpointFactory):
    def get(self, parent):
        return Beeper(self, parent)

CliRunner({"robot": [BeeperFactory()]}).run()
"""

SERVER_WAITING_FOR_CLIENTS = """
from snr import *
from snr.std_mods.comms import SocketsServerFactory

CliRunner({"robot": [SocketsServerFactory(("127.0.0.1", 0), ["x"])]}).run()
"""


def docs_module(entry: str) -> types.ModuleType:
    """The entry's program as a module ``robot`` from ``robot.py``, all but its last line.

    The last line (``CliRunner(...).run()``) is left out, so the test runs the
    program's classes in a node of its own. The source goes into linecache, so
    messages show the lines of ``robot.py`` as they would for the student.
    """
    source = docs_entry(entry)[0]
    lines = source.splitlines(True)
    assert lines[-1].startswith("CliRunner("), lines[-1]
    linecache.cache["robot.py"] = (len(source), None, lines, "robot.py")
    module = types.ModuleType("robot")
    module.__file__ = "robot.py"
    sys.modules["robot"] = module  # inspect finds a class's file through its module
    exec(compile("".join(lines[:-1]), "robot.py", "exec"), module.__dict__)
    return module


class _Lines(logging.Handler):
    """Keeps every message a node logs; calls ``on_warning`` for the watchdog's."""

    def __init__(self, on_warning: Callable[[], None]) -> None:
        super().__init__(logging.INFO)
        self.lines: List[str] = []
        self.on_warning = on_warning

    def emit(self, record: logging.LogRecord) -> None:
        message = record.getMessage()
        self.lines.append(message)
        if SAID_ONCE in message:
            self.on_warning()


class Flooder(ThreadLoop):
    """Stores as fast as it can (it has no tick rate)."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "flooder")

    def loop(self) -> None:
        self.store_data("noise", 0)


class FastCounter(ThreadLoop):
    """Has a tick rate, far more than any node can handle."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "fast_counter", max_tick_rate_hz=100_000)

    def loop(self) -> None:
        self.store_data("fast_count", 1)


class Listener(ThreadLoop):
    """Waits long in one call, as a loop reading a socket does: nothing wrong."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "listener")

    def loop(self) -> None:
        self.wait_s(60)


PROGRAMS: Dict[str, Program] = {}


def setUpModule() -> None:
    for entry in ("17b", "17c"):
        PROGRAMS[entry] = Program(docs_entry(entry)[0], kill_at=SAID_ONCE)
    PROGRAMS["timer"] = Program(STOPPED_BY_A_TIMER)
    PROGRAMS["server"] = Program(SERVER_WAITING_FOR_CLIENTS)


def tearDownModule() -> None:
    for program in PROGRAMS.values():
        program.stop()  # (a no-op for the ones a test stopped already)
    PROGRAMS.clear()


class TestTheClassesOfTheDocs(SNRTestCase):
    """Entries 17a and 17d, run in a node of this process with a few loops added."""

    def setUp(self) -> None:
        self.addCleanup(linecache.cache.pop, "robot.py", None)
        self.addCleanup(sys.modules.pop, "robot", None)

    def run_watched(
        self,
        factories: List[Any],
        warnings: int,
        release: Callable[[Node], None] = lambda node: None,
        max_wait_s: float = 1.0,
    ) -> Tuple[Node, List[str]]:
        """Run a DEBUG node until the watchdog gave ``warnings`` warnings (10 s at most).

        ``release(node)`` then frees what is stuck, and the node is stopped.
        The watchdog's times are cut to a twentieth; the queue holds 1,000.
        """
        node = Node("robot", Config({"robot": factories}))
        assert node.watchdog is not None and node.key_hints is not None
        node.watchdog.every_s, node.watchdog.stuck_s = 0.01, 0.1
        node.key_hints.typo_s, node.key_hints.missing_s = 0.02, 0.05
        node.queue.high_water, node.queue.low_water = 1000, 500
        node.queue.max_wait_s = max_wait_s

        def stop() -> None:
            release(node)
            node.set_terminate_flag("the test saw what it waited for")

        watchdog = node.watchdog

        def stop_once_warned() -> None:
            if len(watchdog.said) >= warnings:
                stop()

        said = _Lines(stop_once_warned)
        safety = threading.Timer(10.0, stop)
        node.log.addHandler(said)
        node.log.propagate = False  # the test reads the lines; nobody else need see them
        safety.start()
        try:
            node.loop()
        finally:
            safety.cancel()
            node.log.removeHandler(said)
            node.log.propagate = True
        self.assertNotEqual(node.terminate_reason, None)
        return node, said.lines

    def test_17a_a_handler_waiting_for_data(self) -> None:
        robot = docs_module("17a")

        def release(node: Node) -> None:
            # What only the node's thread could do while the handler blocks it.
            node.pages["gripper_closed"] = node.page("gripper_closed", True)

        flooder = LoopFactoryOf(Flooder)
        node, lines = self.run_watched(
            [robot.GripperFactory(), robot.GripperSwitchFactory(), flooder],
            1,
            release,
            max_wait_s=0.02,  # the flooder waits, drops a page, waits again...
        )
        self.assertEqual(warnings_of(lines), shown_in_the_docs("17a"))
        # The flooder had to wait (the handler holds the node), but is not blamed.
        self.assertEqual(node.watchdog.said if node.watchdog else None, ["handler Gripper.grab"])
        self.assertGreater(node.queue.waits, 0)  # how often depends on the machine's load
        # Nor is the key the handler waits for called missing: its page is queued.
        hints = [line for line in lines if "'gripper_closed'" in line and SAID_ONCE not in line]
        self.assertEqual(hints, [])

    def test_17d_a_loop_with_no_tick_rate(self) -> None:
        robot = docs_module("17d")
        loops = [robot.CounterFactory(), LoopFactoryOf(FastCounter), LoopFactoryOf(Listener)]
        node, lines = self.run_watched(loops, 2)
        said = warnings_of(lines)
        self.assertEqual(
            [line for line in said if "Loop 'counter'" in line], shown_in_the_docs("17d")
        )
        fast = [line for line in said if "Loop 'fast_counter'" in line]
        self.assertEqual(len(fast), 1, said)
        for part in (HERE, "up to 100,000 times a second", "lower max_tick_rate_hz"):
            self.assertIn(part, fast[0])
        # The listener waited in one call all along: waiting for input is no mistake.
        self.assertEqual(
            sorted(node.watchdog.said if node.watchdog else []),
            ["flood counter", "flood fast_counter"],
        )


class Stuck(Endpoint):
    """Its handler of the event 'go' blocks until the test lets it go."""

    def __init__(self, factory: FactoryOf, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stuck")
        self.released = threading.Event()
        self.task_handlers = {(TaskType.event, "go"): self.on_go}

    def on_go(self, task: Task, key: TaskId) -> SomeTasks:
        self.released.wait(5.0)
        return None


class TestAnIdleNode(unittest.TestCase):
    """An idle node is not stuck: the watchdog sleeps, and its first task wakes it."""

    def test_the_watchdog_dozes_while_idle_and_wakes_with_the_work(self) -> None:
        built: List[Stuck] = []

        def build(factory: FactoryOf, parent: AbstractNode) -> Stuck:
            built.append(Stuck(factory, parent))
            return built[-1]

        node = Node("robot", Config({"robot": [FactoryOf(build)]}))
        watchdog = node.watchdog
        assert watchdog is not None
        watchdog.every_s, watchdog.stuck_s, watchdog.dozing_s = 0.01, 0.1, 30.0
        seen: Dict[str, float] = {}

        def drive() -> None:
            deadline = time.monotonic() + 5.0
            while not watchdog.dozing and time.monotonic() < deadline:
                time.sleep(0.01)
            seen["dozed"] = float(watchdog.dozing)
            sent_at = time.monotonic()
            node.schedule(tasks.event("go"))
            while not watchdog.said and time.monotonic() < deadline + 5.0:
                time.sleep(0.01)
            seen["said_after_s"] = time.monotonic() - sent_at
            built[0].released.set()
            node.set_terminate_flag("the test saw what it waited for")

        driver = threading.Thread(target=drive, daemon=True)
        with self.assertLogs("snr.robot", "WARNING"):
            driver.start()
            node.loop()
        driver.join(5.0)
        self.assertEqual(seen["dozed"], 1.0, "an idle node's watchdog sleeps until there is work")
        self.assertEqual(watchdog.said, ["handler Stuck.on_go"])
        # Found about stuck_s after the task came, not dozing_s (30 s) later.
        self.assertLess(seen["said_after_s"], 3.0)


class TestAnUnmetExpectation(unittest.TestCase):
    """Entry 18: the page's test fails saying it waited, and what it saw instead."""

    def failure_of(self, source: str, timeout_s: float, **names: Any) -> str:
        """Run the page's test file (as module ``test_filter``); its one failure, as printed.

        ``names`` are defined in the module before it runs.
        """
        lines = source.splitlines(True)
        linecache.cache["test_filter.py"] = (len(source), None, lines, "test_filter.py")
        self.addCleanup(linecache.cache.pop, "test_filter.py", None)
        module = types.ModuleType("test_filter")
        module.__file__ = "test_filter.py"
        module.__dict__.update(names)
        exec(compile(source, "test_filter.py", "exec"), module.__dict__)
        case = module.TestFilter("test_average")
        case.timeout_s = timeout_s
        result = unittest.TestResult()
        case.run(result)
        self.assertEqual((len(result.failures), len(result.errors)), (1, 0), result.errors)
        return str(result.failures[0][1])

    def test_the_time_limit_ran_out(self) -> None:
        source = docs_blocks("## 18", "python")[0]
        printed = self.failure_of(source, timeout_s=0.5)  # time for the replayer on a busy machine
        shown = docs_blocks("## 18", "text")[0]
        real = [line for line in printed.splitlines() if line.startswith("AssertionError")]
        expected = [line for line in shown.splitlines() if line.startswith("AssertionError")]
        self.assertEqual([line.replace("of 0.5 s", "of 2 s") for line in real], expected)
        for part in (
            "It waited the whole time limit",
            "closest seen instead: (store_page, 'depth_avg'), 4 times",
            "Seen but not expected: (store_page, 'depth') 4 times",
        ):
            self.assertIn(part, real[0])
        # The traceback points at the test's own line, not at SNR's.
        self.assertIn('File "test_filter.py", line 10, in test_average', printed)
        self.assertNotIn("snr", printed.split("AssertionError")[0])

    def test_the_node_stopped_by_itself(self) -> None:
        # The page stops the node with TimeoutLoopFactory(seconds=0.5); this
        # stops it once the filter's four pages were handled, which is what
        # the half second is for, without counting on a busy machine's speed.
        source = docs_blocks("## 18", "python")[0].replace(
            "ExpectorEndpointFactory(expector, exit_when_satisfied=True),",
            "ExpectorEndpointFactory(expector), StopWhenFactory(AVERAGE, count=4),",
        )
        average = (TaskType.store_page, "depth_avg")
        printed = self.failure_of(source, 5, StopWhenFactory=StopWhenFactory, AVERAGE=average)
        shown = docs_blocks("## 18", "text")[1].rstrip("\n")
        self.assertIn(shown, printed)


class TestTheProgramsOfTheDocs(unittest.TestCase):
    """Entry 17's programs that only a signal can stop, and two that must not be told off.

    They all start with this module (`setUpModule`), so they start up while
    the tests in this process run.
    """

    programs = PROGRAMS

    def check_entry(self, entry: str, *parts: str) -> None:
        program = self.programs[entry]
        said = program.wait_for(SAID_ONCE)
        _, stderr = program.stop()  # (killed already, once it said it)
        self.assertTrue(said, stderr)
        self.assertEqual(warnings_of(stderr.splitlines()), shown_in_the_docs(entry))
        for part in parts:
            self.assertIn(part, warnings_of(stderr.splitlines())[0])

    def test_17b_a_loop_with_a_while_true_of_its_own(self) -> None:
        self.check_entry(
            "17b", "DepthSensor", "`while True:` (robot.py:13", "loop() should do one pass"
        )

    def test_17c_a_node_nothing_will_ever_stop(self) -> None:
        self.check_entry("17c", "nothing will ever schedule tasks.terminate", "Ctrl+C")

    def test_a_node_a_timer_will_stop_is_not_reported(self) -> None:
        program = self.programs["timer"]
        program.proc.wait(15)  # it stops by itself, 0.5 s after it started
        _, err = program.stop()
        self.assertIn("terminated: timer", err)
        self.assertNotIn("nothing to do", err)

    def test_a_server_waiting_for_clients_is_not_reported(self) -> None:
        program = self.programs["server"]
        self.assertTrue(program.wait_for("Listening for sockets clients"), program.stderr)
        # Idle for over twice the watchdog's 0.15 s: the warning would come by now.
        self.assertFalse(program.wait_for("nothing to do", timeout_s=0.4), program.stderr)
        out, err = program.stop(signal.SIGINT)
        self.assertIn("Interrupted by user", out)
        self.assertNotIn("nothing to do", err)
