"""Mistakes caught by the rule they break, not by the catalogue entry they came from.

The catalogue entries of docs/errors.md for these rules (NEW_ENTRIES) are run
as printed and compared line by line and in order, as
`tests.test_errors_catalogue` compares its sections. The tests after them try
each rule on fresh mistakes, written as a student would, that no entry shows.
"""

from __future__ import annotations

import copy
import re
import textwrap
import threading
import time
import unittest
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

import tests.test_errors_catalogue as catalogue_tests
import tests.test_errors_silence as silence
from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
)
from snr.core.checks.error_text import closest_match, exception_text
from snr.core.checks.explain import page_hint
from snr.core.checks.watchdog import Watchdog
from snr.prelude import ComponentError, DatastoreWriteError, SNRError
from tests.helpers import settle_the_heap
from tests.quiet import captured_logs

NEW_ENTRIES = ["15n", "15o", "15p", "15q", "16p", "16q", "16r", "16s", "16t", "16u", "16v"]


class TestNewEntriesLineByLine(unittest.TestCase):
    """Each new entry prints exactly the page's lines, in order."""

    entries: Dict[str, silence.Entry]

    @classmethod
    def setUpClass(cls) -> None:
        cls.entries = silence.catalogue()

    def check(self, label: str) -> None:
        entry = self.entries[label]
        if label in silence.AS_A_PROCESS:
            lines, status = silence.run_process(entry.program)
        else:
            wanted = [c for c in map(silence.comparable, entry.output) if c is not None]
            lines, status = silence.run_program(entry.program, wanted)
        shown = [c for c in map(catalogue_tests.as_shown, entry.output) if c is not None]
        printed = [c for c in map(catalogue_tests.as_on_the_page, lines) if c is not None]
        self.assertTrue(
            catalogue_tests.matches(shown, printed),
            f"{label}: printed instead:\n" + "\n".join(lines),
        )
        self.assertEqual(status, entry.status, label)


silence.add_entry_tests(TestNewEntriesLineByLine, NEW_ENTRIES)


FRESH = Path(__file__).parent / "data" / "fresh_mistakes"
"""Fresh mistakes, no catalogue entry's: each ``NAME.py`` is a whole program, run as
``python robot.py robot``, and ``NAME.txt`` is what a student sees, as docs/errors.md shows it."""
FRESH_AS_A_PROCESS = {"synchronous_runner_never_run"}  # said as the interpreter exits


class TestFreshMistakesLineByLine(unittest.TestCase):
    """Each fresh mistake prints exactly the lines of its ``.txt``, in order."""

    def check(self, name: str) -> None:
        program = (FRESH / f"{name}.py").read_text("utf-8")
        shown_text = (FRESH / f"{name}.txt").read_text("utf-8").splitlines()
        status = int(shown_text[-1])
        output = shown_text[1:-2]  # between "$ python robot.py robot" and "$ echo $?"
        if name in FRESH_AS_A_PROCESS:
            lines, printed_status = silence.run_process(program)
        else:
            wanted = [c for c in map(silence.comparable, output) if c is not None]
            lines, printed_status = silence.run_program(program, wanted)
        shown = [c for c in map(catalogue_tests.as_shown, output) if c is not None]
        printed = [c for c in map(catalogue_tests.as_on_the_page, lines) if c is not None]
        self.assertTrue(
            catalogue_tests.matches(shown, printed),
            f"{name}: printed instead:\n" + "\n".join(lines),
        )
        self.assertEqual(printed_status, status, name)


for _program in sorted(FRESH.glob("*.py")):

    def _test(self: TestFreshMistakesLineByLine, name: str = _program.stem) -> None:
        self.check(name)

    setattr(TestFreshMistakesLineByLine, f"test_{_program.stem}", _test)


# -- fresh mistakes -----------------------------------------------------------------
Builds, LoopBuilds = silence.Builds, silence.LoopBuilds  # cls(factory, parent), either kind


class CamelCase(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "camel")
        self.taskHandlers = {(TaskType.event, "go"): self.go}

    def go(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class Handles(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "handles")
        self.task_handles = {TaskType.terminate: self.stop}

    def stop(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class CountsHandled(Endpoint):
    """A counter whose name is near task_handlers: not a dict, so not a slip."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counts")
        self.task_handled = 0


class RateSlip(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "rate_slip")
        self.max_tick_rate = 20

    def loop(self) -> None:
        self.set_terminate_flag("once")


class AsyncBegin(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "async_begin")

    async def begin(self) -> None:  # type: ignore[override]
        print("never")


class AsyncTerminateHandler(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "async_handler")
        self.task_handlers = {TaskType.terminate: self.on_end}  # type: ignore[dict-item]

    async def on_end(self, task: Task, key: TaskId) -> SomeTasks:
        return None


class HookSlips(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "slips")

    def begining(self) -> None:
        print("lights on")

    def halt_(self) -> None:
        print("lights off")


def build(cls: type, mode: Mode = Mode.TEST, loop: bool = False) -> Node:
    factory = LoopBuilds(cls) if loop else Builds(cls)
    return Node("rules", Config({"rules": [factory]}, mode))


class TestNearMisses(unittest.TestCase):
    def test_the_one_rule_ignores_capitals_and_underscores(self) -> None:
        self.assertEqual(closest_match("taskHandlers", ["task_handlers"]), "task_handlers")
        self.assertEqual(closest_match("URV", ["urov", "topside"]), "urov")
        self.assertIsNone(closest_match("beginner", ["begin"], cutoff=0.8))

    def test_camel_case_and_a_dropped_letter_are_named_with_their_line(self) -> None:
        for cls, attr in ((CamelCase, "taskHandlers"), (Handles, "task_handles")):
            with self.subTest(attr), self.assertRaises(ComponentError) as caught:
                build(cls)
            message = str(caught.exception)
            self.assertIn(f"sets self.{attr}, but SNR reads self.task_handlers", message)
            self.assertIn("Did you mean self.task_handlers?", message)
            self.assertIn(f"in {cls.__name__}.__init__", message)
            self.assertIn(f"self.{attr} = ", message)

    def test_a_value_unlike_snrs_is_the_students_own_name(self) -> None:
        build(CountsHandled)  # no error: a count is not a handler mapping

    def test_a_rate_slip_in_a_loop_names_max_tick_rate_hz(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            build(RateSlip, loop=True)
        self.assertIn("SNR reads self.max_tick_rate_hz, which stays 0", str(caught.exception))

    def test_hooks_with_ing_or_a_trailing_underscore_are_said(self) -> None:
        _, lines = silence.run_node([Builds(HookSlips)])
        text = "\n".join(lines)
        self.assertIn("HookSlips.begining() is never called", text)
        self.assertIn("Did you mean begin?", text)
        self.assertIn("HookSlips.halt_() is never called", text)
        self.assertIn("Did you mean halt?", text)

    def test_deployed_nodes_do_not_look(self) -> None:
        build(CamelCase, Mode.DEPLOYED)


class TestCoroutines(unittest.TestCase):
    def test_an_async_hook_is_refused_in_test_mode(self) -> None:
        with self.assertRaises(ComponentError) as caught:
            build(AsyncBegin)
        message = str(caught.exception)
        self.assertIn("AsyncBegin.begin", message)
        self.assertIn("is an `async def`, but SNR's handlers, hooks and loop()", message)
        self.assertIn("async def begin(self)", message)

    def test_an_async_handler_is_refused_in_every_mode(self) -> None:
        for mode in Mode:
            with self.subTest(mode), self.assertRaises(ComponentError) as caught:
                build(AsyncTerminateHandler, mode)
            self.assertIn("AsyncTerminateHandler.on_end", str(caught.exception))


class TestASpinningLoop(unittest.TestCase):
    """Entry 17e: the watchdog's times cut to 0.01 s a look and 0.1 s stuck (0.2 s a window)."""

    def setUp(self) -> None:
        # A loop that stores a page every pass makes collections run all the time; over the
        # heap earlier tests left they hold the GIL long enough to stall the watchdog's looks.
        settle_the_heap(self)
        self.watched: Optional[Watchdog] = None  # set by tune(), if the program's node runs
        self.looks: List[float] = []

    # (what the run prints, what the page shows): the window and the rate vary.
    AS_ON_THE_PAGE = [
        (r"for 0\.2 s (.*) ran about [\d,]+ times", r"for 4 s \1 ran about 310,000 times")
    ]

    # The node ends as soon as the line comes; the bound only matters when it never
    # does (a loaded machine can hold up the watchdog's thread for a while).
    BOUND_S = 10.0

    def tune(self, node: AbstractNode) -> None:
        watchdog = getattr(node, "watchdog", None)
        assert watchdog is not None
        watchdog.every_s, watchdog.stuck_s = 0.01, 0.1
        node.queue.high_water = 10**7  # type: ignore[attr-defined]  # no 17d: it never fills
        self.watched = watchdog
        check = watchdog.check

        def counted_check() -> None:  # when each look was, for the message of a failure
            self.looks.append(time.monotonic())
            check()

        watchdog.check = counted_check

    def what_the_watchdog_did(self, lines: List[str]) -> str:
        """What was printed, and how often and when the watchdog looked: a failure's message."""
        looks = self.looks
        gaps = [b - a for a, b in zip(looks, looks[1:])]
        said = None if self.watched is None else self.watched.said
        return (
            "printed:\n" + "\n".join(lines) + f"\nthe watchdog looked {len(looks)} times over "
            f"{(looks[-1] - looks[0]) if looks else 0:.2f} s (longest gap "
            f"{max(gaps, default=0):.3f} s) and said {said}"
        )

    def normalised(self, lines: List[str]) -> List[str]:
        # The suite's own timeout loop waits in a `while` (17b), which the cut times notice.
        lines = [line for line in lines if "Loop 'timeout_loop'" not in line]
        kept = [c for c in map(catalogue_tests.as_on_the_page, lines) if c is not None]
        for pattern, shown in self.AS_ON_THE_PAGE:
            kept = [re.sub(pattern, shown, line) for line in kept]
        return kept

    def run_spinning(self, program_text: str) -> List[str]:
        """The lines ``program_text`` prints, run until the watchdog names a spinning loop."""
        lines, status = silence.run_program(
            program_text,
            [],
            tune=self.tune,
            done=lambda text: "has no max_tick_rate_hz" in text,
            bound_s=self.BOUND_S,
        )
        self.status = status
        return lines

    def test_17e_line_by_line(self) -> None:
        program_text, shown = docs_entry("17e")
        lines = self.run_spinning(program_text)
        status = self.status
        output = shown[1 : shown.index("$ echo $?")]
        page = [c for c in map(catalogue_tests.as_shown, output) if c is not None]
        self.assertTrue(
            catalogue_tests.matches(page, self.normalised(lines)), self.what_the_watchdog_did(lines)
        )
        self.assertEqual(status, int(shown[shown.index("$ echo $?") + 1]))

    def test_a_rate_or_a_loop_that_stores_nothing_is_not_told_off(self) -> None:
        class Ticking(ThreadLoop):
            def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "ticking", max_tick_rate_hz=2000)

            def loop(self) -> None:
                self.schedule([])

        class Counting(ThreadLoop):
            def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "counting")
                self.n = 0

            def loop(self) -> None:
                self.n += 1

        source = program(
            """
            class Scheduler(ThreadLoop):
                def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
                    super().__init__(factory, parent, "scheduler")

                def loop(self) -> None:
                    self.schedule(tasks.event("tick"))


            class SchedulerFactory(LoopFactory):
                def get(self, parent: AbstractNode) -> Scheduler:
                    return Scheduler(self, parent)


            CliRunner({"robot": [SchedulerFactory(), TimeoutLoopFactory(seconds=6)]}).run()
            """
        )
        lines = self.run_spinning(source)
        self.assertTrue(
            any("Loop 'scheduler'" in line for line in lines), self.what_the_watchdog_did(lines)
        )
        node = Node("quiet", Config({"quiet": [LoopBuilds(Ticking), LoopBuilds(Counting)]}))
        assert node.watchdog is not None
        node.watchdog.every_s, node.watchdog.stuck_s = 0.01, 0.05
        timer = threading.Timer(0.5, node.set_terminate_flag, ["enough"])
        timer.start()
        with captured_logs("snr.quiet"):
            node.loop()
        timer.cancel()
        self.assertEqual([s for s in node.watchdog.said if s.startswith("spin")], [])


def docs_entry(label: str) -> Tuple[str, List[str]]:
    """The program and the output lines of errors.md entry ``label``."""
    text = catalogue_tests.DOCS.read_text("utf-8")
    chunk = text[text.index(f"\n### {label}. ") :]
    chunk = chunk[: re.compile(r"\n##+ ").search(chunk, 5).start()]  # type: ignore[union-attr]
    program_text = chunk.split("```python\n", 1)[1].split("```", 1)[0]
    return program_text, chunk.split("```text\n", 1)[1].split("```", 1)[0].splitlines()


def program(body: str) -> str:
    return "from snr import *\n" + textwrap.dedent(body)


class TestRunnerNeverRan(unittest.TestCase):
    """Run as processes: the message comes as the interpreter exits."""

    def said(self, source: str) -> List[str]:
        lines, _ = silence.run_process(source)
        return [line for line in lines if "never ran" in line]

    def test_a_runner_built_in_a_function_of_the_program_is_named(self) -> None:
        source = program(
            """
            def main() -> None:
                config = Config({"robot": [TimeoutLoopFactory(seconds=1)]})
                SynchronousRunner("robot", config)

            main()
            """
        )
        said = self.said(source)
        self.assertEqual(len(said), 1, said)
        self.assertIn("SynchronousRunner built at robot.py:5 in main never ran", said[0])

    def test_a_runner_that_ran_is_not_named(self) -> None:
        source = program('CliRunner({"robot": [TimeoutLoopFactory(ms=1)]}).run()\n')
        self.assertEqual(self.said(source), [])

    def test_a_runner_inspected_in_a_test_is_not_named(self) -> None:
        source = program(
            """
            import unittest

            class TestConfig(unittest.TestCase):
                def test_roles(self) -> None:
                    runner = CliRunner({"robot": [TimeoutLoopFactory(seconds=1)]})
                    self.assertEqual(runner.config.roles(), ["robot"])

            unittest.main(argv=["robot.py"])
            """
        )
        self.assertEqual(self.said(source), [])

    def test_a_program_that_died_of_an_error_is_told_only_that(self) -> None:
        source = program(
            """
            runner = CliRunner({"robot": [TimeoutLoopFactory(seconds=1)]})
            print(1 / 0)
            """
        )
        lines, status = silence.run_process(source)
        self.assertEqual([line for line in lines if "never ran" in line], [])
        self.assertIn("ZeroDivisionError: division by zero", lines)
        self.assertEqual(status, 1)

    def test_deployed_mode_says_nothing(self) -> None:
        source = program(
            'config = Config({"robot": [TimeoutLoopFactory(seconds=1)]}, Mode.DEPLOYED)\n'
            'SynchronousRunner("robot", config)\n'
            'print("built")\n'
        )
        lines, status = silence.run_process(source)
        self.assertEqual((lines, status), (["built"], 0))


def _unpack(page: Any) -> object:
    left, right = page
    return (left, right)


class TestAPageUsedAsItsValue(unittest.TestCase):
    """Every use of a Page as a value names the fix for where the page came from."""

    PAGE = Page("depth", 2.5, "robot", 0.0)

    def raised(self, use: Callable[[Page], object]) -> BaseException:
        try:
            use(self.PAGE)
        except TypeError as error:
            return error
        raise AssertionError("no TypeError")

    def test_every_use_gets_the_handlers_fix(self) -> None:
        uses: Dict[str, Callable[[Page], object]] = {
            "unpacking": _unpack,
            "indexing": lambda page: page[0],  # type: ignore[index]
            "iterating": lambda page: list(page),  # type: ignore[call-overload]
            "comparing": lambda page: page < 2.0,  # type: ignore[operator]
            "arithmetic": lambda page: page * 2,  # type: ignore[operator]
            "len": lambda page: len(page),  # type: ignore[arg-type]
            "formatting": lambda page: f"{page:.1f}",
        }
        for what, use in uses.items():
            with self.subTest(what):
                text = exception_text(self.raised(use))
                self.assertIn("its value is page.data, e.g. task.val_list[0].data", text)

    def test_a_page_from_get_page_gets_get_data(self) -> None:
        def on_depth(node: Any) -> object:
            return node.get_page("depth") + 1.0

        class Reads:
            def get_page(self, key: str) -> Page:
                return TestAPageUsedAsItsValue.PAGE

        error = self.raised(lambda page: on_depth(Reads()))
        text = page_hint(error, exception_text(error))
        self.assertIn("read self.get_data(key)", text)
        self.assertNotIn("val_list", text)


class TestADatastoreWrittenByAComponent(unittest.TestCase):
    """Only the node writes its datastore; anything else is refused at its line."""

    def test_a_loop_assigning_a_value_is_told_store_data_is_the_thread_safe_way(self) -> None:
        source = program(
            """
            class Depth(ThreadLoop):
                def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
                    super().__init__(factory, parent, "depth", max_tick_rate_hz=10)

                def loop(self) -> None:
                    self.parent.datastore["depth"] = 2.0


            class DepthFactory(LoopFactory):
                def get(self, parent: AbstractNode) -> Depth:
                    return Depth(self, parent)


            CliRunner({"robot": [DepthFactory(), TimeoutLoopFactory(seconds=5)]}).run()
            """
        )
        lines, status = silence.run_program(source, ["LoopError"])
        text = "\n".join(lines)
        self.assertEqual(status, 1, text)
        self.assertIn("datastore['depth'] = value at robot.py:8 in Depth.loop was refused", text)
        self.assertIn("self.store_data('depth', value); from a loop's thread", text)
        self.assertIn("thread-safe", text)
        self.assertIn('self.parent.datastore["depth"] = 2.0', text)  # the student's line

    def test_every_way_of_changing_it_is_refused_and_changes_nothing(self) -> None:
        node = Node(
            "robot", Config({"robot": [TimeoutLoopFactory(seconds=1)]}, mode=Mode.DEPLOYED)
        )  # every mode
        page = node.page("depth", 1.0)
        node.write_page(page)  # the node's own way, before it runs
        store: Any = node.datastore  # as a student writes it, untyped
        tries: List[Tuple[str, Callable[[], object]]] = [
            ("datastore['depth'] = value", lambda: store.__setitem__("depth", page)),
            ("del datastore['depth']", lambda: store.__delitem__("depth")),
            ("datastore.update()", lambda: store.update(depth=page)),
            ("datastore.pop()", lambda: store.pop("depth")),
            ("datastore.popitem()", store.popitem),
            ("datastore.clear()", store.clear),
            ("datastore.setdefault()", lambda: store.setdefault("speed", page)),
            ("datastore |= other", lambda: store.__ior__({"speed": page})),
        ]
        for what, attempt in tries:
            with self.subTest(what), self.assertRaises(DatastoreWriteError) as caught:
                attempt()
            self.assertIn(f"{what} at tests/test_errors_rules.py:", str(caught.exception))
            self.assertIn("self.store_data(", str(caught.exception))
        self.assertEqual(dict(store), {"depth": page})
        self.assertIsInstance(caught.exception, SNRError)

    def test_a_copy_is_a_plain_dict_the_copier_may_change(self) -> None:
        node = Node("robot", Config({"robot": [TimeoutLoopFactory(seconds=1)]}))
        node.write_page(node.page("depth", 1.0))
        copies: List[Any] = [copy.copy(node.datastore), copy.deepcopy(node.datastore)]
        for copied in copies:
            copied["speed"] = node.page("speed", 0.5)
            self.assertEqual(sorted(copied), ["depth", "speed"])
        self.assertEqual(list(node.datastore), ["depth"])


class TestUncaughtSNRErrors(unittest.TestCase):
    """Run as processes: what Python's report of an uncaught error becomes."""

    WRONG_MODE = program(
        """
        def build() -> Config:
            return Config({"robot": [TimeoutLoopFactory(seconds=1)]}, mode="test")

        build()
        """
    )

    def test_a_call_in_a_function_shows_both_student_frames_and_no_snr_frame(self) -> None:
        lines, status = silence.run_process(self.WRONG_MODE)
        text = "\n".join(lines)
        self.assertEqual(status, 1)
        self.assertIn('robot.py", line 6, in <module>', text)
        self.assertIn('robot.py", line 4, in build', text)
        self.assertIn("ConfigError: Config(mode=...) got 'test'", text)
        self.assertNotIn("snr/", text.replace("SNR_VERBOSE", ""))

    def test_snr_verbose_or_dash_dash_verbose_shows_everything(self) -> None:
        for argv in (("robot.py", "robot", "--verbose"),):
            lines, _ = silence.run_process(self.WRONG_MODE, argv)
            self.assertIn("snr.prelude.errors.ConfigError", "\n".join(lines))
            self.assertTrue(any("snr/core/config.py" in line for line in lines), lines)

    def test_other_errors_and_a_programs_own_hook_are_left_alone(self) -> None:
        lines, _ = silence.run_process(program("import json\njson.loads('{')\n"))
        self.assertTrue(any("json/decoder.py" in line for line in lines), lines)
        own = "import sys\nsys.excepthook = lambda *a: print('mine')\n" + self.WRONG_MODE
        lines, _ = silence.run_process(own)
        self.assertEqual(lines, ["mine"])


if __name__ == "__main__":
    unittest.main()
