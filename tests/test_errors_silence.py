"""docs/errors.md sections 15 and 16, run as printed: silent mistakes and misplaced blame.

Every entry there is a complete ``robot.py`` with the output of ``python robot.py
robot``. Each test here runs that very program in this process, with the real
`CliRunner`, node and components, and checks that every line the page shows
(less the time stamps, and the frames it leaves out as ``...``) is in the
output, and that the exit status is the one shown.

To keep the suite fast, the program's `TimeoutLoopFactory` is a subclass
that ends the node as soon as everything the page shows before "terminated"
has been printed (at most 2 s), and the node's wiring check runs once the first
page is stored (or after 0.15 s when none is) instead of 3 s. Nothing else is
changed.

The tests after those aim at the mechanisms rather than at the entries: a
mistake of the same kind, not in the catalogue, must be caught too.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import re
import runpy
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import traceback
import unittest
import warnings
from pathlib import Path
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    NamedTuple,
    Optional,
    Sequence,
    TextIO,
    Tuple,
    Type,
    Union,
)
from unittest import mock

import snr
from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)
from snr.core.checks.runner_checks import snr_excepthook
from snr.prelude import ComponentError, HandlerError, SNRError
from snr.std_mods.utils.timeout import TimeoutLoop
from tests.examples_support import ROOT
from tests.quiet import captured_logs

DOCS = Path(ROOT, "docs", "errors.md")
STUDENT_DIR = "/home/student/rov"
TIME_STAMP = re.compile(r"^\d\d:\d\d:\d\d ")
CARETS = re.compile(r"^\s*[\^~]+\s*$")
BOUND_S = 2.0


class Entry(NamedTuple):
    label: str  # "15a"
    program: str
    output: List[str]  # what the program prints, as the page shows it
    status: int


def catalogue() -> Dict[str, Entry]:
    """The entries of sections 15 and 16 of docs/errors.md, by label."""
    text = DOCS.read_text("utf-8")
    start = text.index("\n## 15. ")
    end = text.index("\n## ", text.index("\n## 16. ") + 1)
    entries: Dict[str, Entry] = {}
    for chunk in text[start:end].split("\n### ")[1:]:
        label = chunk.split(".", 1)[0]
        program = chunk.split("```python\n", 1)[1].split("```", 1)[0]
        shown = chunk.split("```text\n", 1)[1].split("```", 1)[0].splitlines()
        status = int(shown[shown.index("$ echo $?") + 1])
        output = [line for line in shown if not line.startswith("$ ")]
        output = output[: len(output) - 1]  # the status itself
        entries[label] = Entry(label, program, output, status)
    return entries


def comparable(line: str) -> Optional[str]:
    """A line of output as compared: no time stamp; None for lines not compared."""
    if line.strip() == "..." or CARETS.match(line) or not line.strip():
        return None
    return TIME_STAMP.sub("", line)


class Capture(io.StringIO):
    """Everything the program prints and logs, in order; safe from the node's threads."""

    def __init__(self) -> None:
        super().__init__()
        self.lock = threading.Lock()

    def write(self, text: str) -> int:
        with self.lock:
            return super().write(text)

    def text(self) -> str:
        with self.lock:
            return self.getvalue()


def run_program(
    source: str,
    wanted: List[str],
    argv: Sequence[str] = ("robot.py", "robot"),
    tune: Callable[[AbstractNode], None] = lambda node: None,
    done: Optional[Callable[[str], bool]] = None,
    bound_s: float = BOUND_S,
) -> Tuple[List[str], int]:
    """Run ``source`` as ``python robot.py robot`` would; its output lines and exit status.

    ``argv`` is the command line (``python`` left out); ``tune(node)`` runs as
    the program's `TimeoutLoopFactory` builds its loop, to cut a node's hint
    times short; ``done(output)``, if given, tells that loop when to end the
    node instead of ``wanted``; the node runs at most ``bound_s`` seconds.
    """
    folder = tempfile.mkdtemp(prefix="snr-student-")
    path = os.path.join(folder, "robot.py")
    Path(path).write_text(source, "utf-8")
    capture = Capture()
    waiting_for = [w for w in wanted if "terminated:" not in w]

    def seen_all() -> bool:
        text = capture.text().replace(folder, STUDENT_DIR)
        return done(text) if done is not None else all(w in text for w in waiting_for)

    handler = logging.StreamHandler(capture)
    handler.setFormatter(logging.Formatter("%(name)s %(levelname)s: %(message)s"))
    snr_log = logging.getLogger("snr")
    role_log = logging.getLogger("snr.robot")
    saved = (snr_log.propagate, role_log.level, os.getcwd(), snr_log.handlers[:])
    snr_log.handlers = [handler]  # the screen only, not also an earlier node's stderr handler
    snr_log.propagate = False
    role_log.setLevel(logging.INFO)
    status = 0
    try:
        os.chdir(folder)
        with contextlib.ExitStack() as stack:
            stack.enter_context(contextlib.redirect_stdout(capture))
            stack.enter_context(contextlib.redirect_stderr(capture))
            stack.enter_context(mock.patch.object(sys, "argv", list(argv)))
            # Warnings printed as `python robot.py` prints them, whichever runner runs the
            # tests (pytest would otherwise collect them for its summary).
            stack.enter_context(warnings.catch_warnings())
            warnings.simplefilter("default")
            warnings.showwarning = _print_warning
            # As `python robot.py`: sys.argv[0] stays as typed (runpy would make it the path).
            stack.enter_context(mock.patch.object(runpy, "_ModifiedArgv0", _ArgvAsTyped))
            stack.enter_context(
                mock.patch.object(snr, "TimeoutLoopFactory", fast_timeout(seen_all, tune, bound_s))
            )
            try:
                runpy.run_path(path, run_name="__main__")
            except SystemExit as end:
                status = end.code if isinstance(end.code, int) else 1
            except SNRError as error:  # what `import snr`'s sys.excepthook prints for it
                tb = error.__traceback__
                while tb is not None and tb.tb_frame.f_code.co_filename != path:
                    tb = tb.tb_next  # runpy's frames: `python robot.py` has none
                snr_excepthook(type(error), error, tb)
                status = 1
            except Exception as error:  # what Python prints for an uncaught error
                frames = [f for f in traceback.extract_tb(error.__traceback__)]
                theirs = [f for f in frames if f.filename == path]
                print("Traceback (most recent call last):", file=sys.stderr)
                print("".join(traceback.format_list(theirs)), end="", file=sys.stderr)
                print("".join(traceback.format_exception_only(error)), end="", file=sys.stderr)
                status = 1
    finally:
        snr_log.propagate, level, cwd, snr_log.handlers = saved
        role_log.setLevel(level)
        os.chdir(cwd)
        shutil.rmtree(folder, ignore_errors=True)
    lines = capture.text().replace(folder, STUDENT_DIR).splitlines()
    return lines, status


# Entries whose message the interpreter itself gives (at exit, or its report of an
# uncaught error): run as a process of their own.
AS_A_PROCESS = {"15q", "16p"}


def run_process(source: str, argv: Sequence[str] = ("robot.py", "robot")) -> Tuple[List[str], int]:
    """Run ``source`` as ``python robot.py robot`` in a process of its own; lines and status.

    For what only a whole interpreter shows (its exit, its printing of an uncaught
    error). stdout and stderr are read as one stream, the folder shown as the page's.
    """
    folder = tempfile.mkdtemp(prefix="snr-student-")
    try:
        Path(folder, argv[0]).write_text(source, "utf-8")
        env = {k: v for k, v in os.environ.items() if not k.startswith("SNR_")}
        done = subprocess.run(
            [sys.executable, *argv],
            cwd=folder,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            timeout=30,
            check=False,
        )
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return done.stdout.replace(folder, STUDENT_DIR).splitlines(), done.returncode


class _ArgvAsTyped(contextlib.nullcontext):  # type: ignore[type-arg]
    """Leaves ``sys.argv[0]`` alone where runpy would set it to the program's path."""

    def __init__(self, value: object) -> None:
        super().__init__()


def _print_warning(
    message: Union[Warning, str],
    category: Type[Warning],
    filename: str,
    lineno: int,
    file: Optional[TextIO] = None,
    line: Optional[str] = None,
) -> None:
    """What Python's own `warnings.showwarning` does: the warning on stderr."""
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def fast_timeout(
    done: Callable[[], bool],
    tune: Callable[[AbstractNode], None] = lambda node: None,
    bound_s: float = BOUND_S,
) -> type:
    """A TimeoutLoopFactory whose loop ends the node once ``done()`` (at most ``bound_s``)."""

    class ExpectingTimeoutLoop(TimeoutLoop):
        def loop(self) -> None:
            deadline = time.monotonic() + bound_s
            # The node's own wiring check runs 3 s after start, when pages have
            # been flowing: run it once the first page is in (programs that
            # store nothing wait 0.15 s).
            first_page = time.monotonic() + 0.15
            node = self.parent
            assert isinstance(node, Node)  # the datastore is the Node's, not in AbstractNode
            while not node.datastore and time.monotonic() < first_page:
                if self.wait_s(0.005):
                    return
            self.schedule(tasks.event(tasks.CHECK_WIRING))
            while not done() and time.monotonic() < deadline:
                if self.wait_s(0.005):
                    return  # the node stopped by itself
            self.schedule(tasks.terminate("Timeout"))
            self.set_terminate_flag("timeout reached")

    class ExpectingTimeoutLoopFactory(TimeoutLoopFactory):
        def get(self, parent: AbstractNode) -> TimeoutLoop:
            hints = getattr(parent, "key_hints", None)
            if hints is not None:
                hints.handlers_s = 3 * BOUND_S  # the loop above runs the check sooner
            tune(parent)
            return ExpectingTimeoutLoop(self, parent, self.seconds)

    # Printed in messages as the student wrote it: TimeoutLoopFactory(...).
    ExpectingTimeoutLoopFactory.__name__ = "TimeoutLoopFactory"
    ExpectingTimeoutLoopFactory.__qualname__ = "TimeoutLoopFactory"
    return ExpectingTimeoutLoopFactory


class TestCatalogue(unittest.TestCase):
    """Each program of sections 15 and 16 prints what the page shows."""

    entries: Dict[str, Entry]

    @classmethod
    def setUpClass(cls) -> None:
        cls.entries = catalogue()

    def test_the_catalogue_has_at_least_twenty_entries(self) -> None:
        self.assertGreaterEqual(len(self.entries), 20)

    def check(self, label: str) -> None:
        entry = self.entries[label]
        wanted = [c for c in (comparable(line) for line in entry.output) if c is not None]
        if label in AS_A_PROCESS:
            lines, status = run_process(entry.program)
        else:
            lines, status = run_program(entry.program, wanted)
        got = {c for c in (comparable(line) for line in lines) if c is not None}
        missing = [w for w in wanted if w not in got]
        self.assertEqual(missing, [], f"{label}: printed instead:\n" + "\n".join(lines))
        self.assertEqual(status, entry.status, label)


def add_entry_tests(test_class: type, labels: Iterable[str]) -> None:
    """Give ``test_class`` a ``test_<label>`` calling ``self.check(label)`` for each label."""
    for label in labels:

        def test(self: Any, label: str = label) -> None:
            self.check(label)

        setattr(test_class, f"test_{label}", test)


add_entry_tests(TestCatalogue, catalogue())


# -- the mechanisms, on mistakes the catalogue does not list ------------------------
class LogLines(logging.Handler):
    def __init__(self, until: Sequence[str] = (), then: Callable[[], None] = lambda: None) -> None:
        super().__init__()
        self.lines: List[str] = []
        self.until, self.then = until, then

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(record.getMessage())
        text = "\n".join(self.lines)
        if self.until and all(part in text for part in self.until):
            self.then()


def run_node(
    factories: List[Any],
    mode: Mode = Mode.DEBUG,
    timeout_ms: float = 100,
    until: Sequence[str] = (),
) -> Tuple[Node, List[str]]:
    """Run a node of ``factories`` plus a timeout; the node and its log lines.

    The timeout is 0.1 s, or with ``until`` 5 s, and the node ends as soon as
    every part of ``until`` has been logged (a loaded machine may be slow).
    """
    node_box: List[Node] = []
    lines = LogLines(until, lambda: node_box[0].set_terminate_flag("seen") if node_box else None)
    timeout_ms = 5000 if until else timeout_ms
    # Only to `lines`, not to the run's output; the level a DEBUG node sets is put back.
    with captured_logs("snr.silence"):
        # Before the node is built: classes are read as it adds them.
        logging.getLogger("snr.silence").addHandler(lines)
        config = Config({"silence": [*factories, TimeoutLoopFactory(ms=timeout_ms)]}, mode)
        node = Node("silence", config)
        node_box.append(node)
        node.loop()
    return node, lines.lines


class Builds(EndpointFactory):
    """Builds ``cls(self, parent)``."""

    def __init__(self, cls: type) -> None:
        super().__init__()
        self.cls = cls

    def get(self, parent: AbstractNode) -> Any:
        return self.cls(self, parent)


class LoopBuilds(LoopFactory):
    def __init__(self, cls: type) -> None:
        super().__init__()
        self.cls = cls

    def get(self, parent: AbstractNode) -> Any:
        return self.cls(self, parent)


class DropsATask(Endpoint):
    """Builds a Task by hand and a page, and uses neither."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "drops")
        self.task_handlers = {(TaskType.event, "Go"): self.go}

    def begin(self) -> None:
        self.schedule(tasks.event("go"))  # the handler is for "Go"

    def go(self, task: Task, key: TaskId) -> SomeTasks:
        Task(TaskType.event, "went")
        self.page("went", True)
        return None


class StateInLoop(ThreadLoop):
    """Sets self.state in loop(), not in __init__: only reading the class finds it."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "state_in_loop")

    def loop(self) -> None:
        self.state = "busy"  # type: ignore[assignment]


class OwnLog(Endpoint):
    """Defines a method with the name of the component's logger."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "own_log")

    def log(self, text: str) -> None:  # type: ignore[override]
        print(text)


class SetupReturns(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "setup_returns")

    def setup(self) -> Any:
        return tasks.event("ready")

    def loop(self) -> None:
        self.set_terminate_flag("once")


class HandMadeTask(Endpoint):
    """Schedules a Task built by hand with values that are not a list."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "hand_made")
        self.task_handlers = {(TaskType.event, "speed"): self.speed}

    def begin(self) -> None:
        self.schedule(Task(TaskType.event, "speed", 5))  # type: ignore[arg-type]

    def speed(self, task: Task, key: TaskId) -> SomeTasks:
        print(task.val_list[0])
        return None


class TestMechanisms(unittest.TestCase):
    def test_dropped_work_and_a_name_differing_in_capitals_are_said(self) -> None:
        _, lines = run_node([Builds(DropsATask)], until=["Did you mean 'Go'?"])
        text = "\n".join(lines)
        self.assertIn("builds a task, `Task(TaskType.event, 'went')`, and drops it", text)
        self.assertIn("builds a page, `self.page('went', True)`", text)
        self.assertIn("self.store_page(self.page('went', True))", text)
        self.assertIn("handles the event 'go'", text)
        self.assertIn("Did you mean 'Go'?", text)

    def test_an_assignment_outside_init_is_found_in_the_class(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            Node("silence", Config({"silence": [LoopBuilds(StateInLoop)]}))
        message = str(caught.exception)
        self.assertIn("uses the name 'state'", message)
        self.assertIn("in StateInLoop.loop", message)
        self.assertIn('self.state = "busy"', message)
        self.assertIn("self.stateinloop_state", message)

    def test_a_method_named_like_snrs_is_an_error_in_test_mode_too(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            Node("silence", Config({"silence": [Builds(OwnLog)]}, Mode.TEST))
        self.assertIn("'log' is already Endpoint's property log", str(caught.exception))
        self.assertIn("def log(self, text: str)", str(caught.exception))

    def test_a_hook_return_in_setup_is_said(self) -> None:
        _, lines = run_node([LoopBuilds(SetupReturns)])
        self.assertTrue(
            any("SetupReturns.setup() returns `tasks.event('ready')`" in m for m in lines),
            lines,
        )

    def test_a_hand_made_task_with_values_not_a_list_is_named_when_it_fails(self) -> None:
        with self.assertRaises(HandlerError) as caught:
            # The failing handler ends the node; the timeout is only a bound.
            run_node([Builds(HandMadeTask)], timeout_ms=5000)
        self.assertIn("Its val_list is 5 (int), not a list", str(caught.exception))
        self.assertIn("Task(TaskType.event, 'speed', [value])", str(caught.exception))

    def test_snrs_own_announcements_are_not_reported(self) -> None:
        announce = StartsWith([tasks.event("comms_disconnected"), tasks.event("snr_x")])
        _, lines = run_node([announce])
        self.assertFalse([m for m in lines if "handles the event" in m], lines)

    def test_deployed_nodes_check_nothing_new(self) -> None:
        node, lines = run_node([Builds(DropsATask)], Mode.DEPLOYED)
        self.assertIsNone(node.wiring_checks)
        self.assertEqual([m for m in lines if "drops it" in m or "handles the" in m], [])
        Node("deployed", Config({"deployed": [LoopBuilds(StateInLoop)]}, Mode.DEPLOYED))

    def test_deployed_pages_skip_the_checks_debug_pages_make(self) -> None:
        debug = Node("checked", Config({"checked": [TimeoutLoopFactory(seconds=1)]}))
        with self.assertRaises(ComponentError):
            debug.page(3, "depth")  # type: ignore[arg-type]
        deployed = Node("fast", Config({"fast": [TimeoutLoopFactory(seconds=1)]}, Mode.DEPLOYED))
        self.assertEqual(deployed.page("depth", 3).data, 3)
        self.assertEqual(deployed.page(3, "depth").key, 3)  # type: ignore[arg-type]

    def test_store_data_builder_checks_its_key(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            tasks.store_data(3, "depth")  # type: ignore[arg-type]
        self.assertIn("write store_data('depth', 3)", str(caught.exception))
        self.assertIn("test_errors_silence.py", str(caught.exception))


class StartsWith(EndpointFactory):
    """An endpoint that schedules ``first`` when it begins."""

    def __init__(self, first: List[Task]) -> None:
        super().__init__()
        self.first = first

    def get(self, parent: AbstractNode) -> Endpoint:
        return _Starter(self, parent)


class _Starter(Endpoint):
    def __init__(self, factory: StartsWith, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "starter")
        self.first = factory.first

    def begin(self) -> None:
        self.schedule(self.first)


if __name__ == "__main__":
    unittest.main()
