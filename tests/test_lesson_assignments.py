"""Lessons 5 to 7: a datastore, a node core and a task queue of the student's own.

``Config(datastore=..., node_core=...)`` puts a student's class where SNR's
own part goes (docs/assignments.md); lesson 7's queue is graded with threads
of the grader's own (there is no seam for the queue). Here: SNR's own
datastore (a ``dict``), node core and task queue pass the lessons' graders,
which are SNR's own tests of those parts; each solution passes and each
starter fails with checks that say why; the mistakes a student makes in each
part are said where they are made (snr/core/checks/seam_checks.py) or fail
the check that names them; and the default path is SNR's own parts, untouched.
"""

from __future__ import annotations

import contextlib
import io
import logging
import shutil
import sys
import tempfile
import time
import unittest
from pathlib import Path
from typing import Dict, Iterator, List, Optional

from snr import Config, Mode, Node, Page, SNRError, TimeoutLoopFactory
from snr.core import NodeCore, NodeCoreEndpoint, NodeCoreFactory
from snr.core.checks.seam_checks import CheckedDatastore
from snr.extras.lessons import lesson
from snr.extras.lessons.command import grade_file
from snr.extras.lessons.grading import Check
from snr.extras.lessons.l05_datastore.grader import grade_datastore
from snr.extras.lessons.l05_datastore.solution import HashDatastore
from snr.extras.lessons.l06_node_core.grader import grade_core
from snr.extras.lessons.l06_node_core.solution import MyNodeCoreFactory
from snr.extras.lessons.l07_task_queue import solution as queue_solution
from snr.extras.lessons.l07_task_queue import starter as queue_starter
from snr.extras.lessons.l07_task_queue.grader import grade_queue
from snr.extras.lessons.l07_task_queue.snr_queue import SnrTaskQueue
from snr.prelude import ComponentError, ConfigError

DATASTORE, NODE_CORE, QUEUE = lesson(5), lesson(6), lesson(7)


def line_of(path: Path, text: str) -> int:
    """The number of the first line of ``path`` that contains ``text``."""
    for number, line in enumerate(path.read_text("utf-8").splitlines(), start=1):
        if text in line:
            return number
    raise AssertionError(f"{text!r} is not in {path}")


class Lossy:
    """A datastore that keeps nothing: every method there, every answer empty."""

    def __setitem__(self, key: str, page: Page) -> None:
        pass

    def get(self, key: str) -> Optional[Page]:
        return None

    def __iter__(self) -> Iterator[str]:
        return iter([])

    def __len__(self) -> int:
        return 0


def quiet_node(config: Config) -> Node:
    """``Node("a", config)``, its log kept out of the test's output."""
    logging.getLogger("snr.a").setLevel(logging.CRITICAL)
    return Node("a", config)


class TestSnrsOwnPartsPassTheGraders(unittest.TestCase):
    """SNR's test of its own datastore and node core: the graders the students' parts take."""

    def assert_all_passed(self, checks: List[Check], count: int) -> None:
        self.assertEqual([check.name for check in checks if not check.passed], [], checks)
        self.assertEqual(len(checks), count, checks)

    def test_snrs_datastore_a_dict_passes_lesson_5(self) -> None:
        checks = grade_datastore(dict, Path("snr"))
        self.assert_all_passed(checks, 8)
        self.assertEqual(checks[0].happened, "dict, made with dict() for each node")

    def test_snrs_node_core_passes_lesson_6(self) -> None:
        checks = grade_core(NodeCoreFactory(), NodeCoreEndpoint, Path("snr"))
        self.assert_all_passed(checks, 10)
        self.assertIn("NodeCoreEndpoint", checks[0].happened)

    def test_snrs_task_queue_passes_lesson_7(self) -> None:
        before = sys.getswitchinterval()
        checks = grade_queue(SnrTaskQueue, Path("snr"))
        self.assertEqual(sys.getswitchinterval(), before, "the grade puts the switch interval back")
        self.assert_all_passed(checks, 11)
        self.assertIn("SnrTaskQueue", checks[0].happened)

    def test_a_datastore_that_keeps_nothing_fails_them(self) -> None:
        failed = [check.name for check in grade_datastore(Lossy, Path("x.py")) if not check.passed]
        self.assertIn("gives back the page stored under a key", failed)
        self.assertIn("stores pages from another node", failed)


class TestSolutionsAndStarters(unittest.TestCase):
    def test_each_solution_passes_in_under_five_seconds(self) -> None:
        for one in (DATASTORE, NODE_CORE, QUEUE):
            with self.subTest(lesson=one.number):
                started = time.monotonic()
                checks = grade_file(one, one.folder / "solution.py")
                self.assertLess(time.monotonic() - started, 5.0, "a grade takes under 5 s")
                self.assertTrue(all(check.passed for check in checks), checks)

    def test_each_starter_fails_with_readable_checks(self) -> None:
        for one, first_failed, blamed in (
            (DATASTORE, "gives back the page stored under a key", "def __setitem__("),
            (NODE_CORE, "stores each page before its handlers run", "def store_page_handler("),
            (QUEUE, "gives back one thread's tasks in the order put", "def put("),
        ):
            with self.subTest(lesson=one.number):
                started = time.monotonic()
                checks = grade_file(one, one.folder / "starter.py")
                self.assertLess(time.monotonic() - started, 5.0, "a grade takes under 5 s")
                self.assertTrue(checks[0].passed and checks[1].passed, checks[:2])
                failed = [check for check in checks if not check.passed]
                self.assertGreaterEqual(len(failed), 4, "the starter holds no answer")
                for check in failed:  # each says what, why, and where to look
                    self.assertTrue(check.expected and check.happened and check.hint, check)
                    self.assertIsNotNone(check.line, check)
                self.assertEqual(failed[0].name, first_failed)
                self.assertEqual(failed[0].line, line_of(one.folder / "starter.py", blamed))


class TestStudentsMistakes(unittest.TestCase):
    """What a grade says of the mistakes a student makes in each part."""

    def setUp(self) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="snr-assignments-"))
        self.addCleanup(shutil.rmtree, self.folder, True)

    def grade(self, number: int, text: str, name: str = "mine.py") -> Dict[str, Check]:
        path = self.folder / name
        path.write_text(text, "utf-8")
        return {check.name: check for check in grade_file(lesson(number), path)}

    def solution(self, number: int, old: str, new: str) -> str:
        text = (lesson(number).folder / "solution.py").read_text("utf-8")
        self.assertIn(old, text)
        return text.replace(old, new)

    def test_renamed_copies_of_the_solutions_pass(self) -> None:
        renames = (
            (5, "HashDatastore", "Pages"),
            (6, "MyNodeCore", "Core"),
            (7, "MyTaskQueue", "Jobs"),
        )
        for number, old, new in renames:
            with self.subTest(lesson=number):
                text = self.solution(number, old, new)
                checks = self.grade(number, text, f"lesson{number}.py")
                self.assertTrue(all(check.passed for check in checks.values()), checks)
                first = next(iter(checks.values()))
                self.assertTrue(first.happened.startswith(new), first)

    def test_a_get_that_returns_the_data_is_said_by_the_node(self) -> None:
        returns = "                return page\n"
        text = self.solution(5, returns, returns.replace("page", "page.data"))
        checks = self.grade(5, text)
        ran = checks["runs without an exception"]
        self.assertFalse(ran.passed)
        self.assertIn("HashDatastore", ran.happened)
        self.assertIn("returned 6.229 (float); it should return the whole Page", ran.happened)

    def test_keys_that_are_not_strings_are_said_on_the_class_line(self) -> None:
        copy = "        return iter(list(self.order))  # a copy: the node may store"
        text = self.solution(5, copy, "        return iter([1, 2])  #")
        ran = self.grade(5, text)["runs without an exception"]
        self.assertFalse(ran.passed)
        self.assertRegex(ran.happened, r"^ComponentError: HashDatastore \(\S*mine\.py:\d+\)")
        self.assertIn("iter() returned [1, 2] (list); it should return each key", ran.happened)
        self.assertEqual(ran.line, line_of(self.folder / "mine.py", "class HashDatastore"))

    def test_an_exception_in_the_core_names_its_method_and_line(self) -> None:
        stores = "        self.pages[page.key] = page\n"
        text = self.solution(6, stores, stores.replace("page.key]", "page.kye]"))
        ran = self.grade(6, text)["runs without an exception"]
        self.assertFalse(ran.passed)
        self.assertRegex(ran.happened, r"MyNodeCore\.store_page_handler \(\S*mine\.py:\d+\)")
        self.assertIn("AttributeError: 'Page' object has no attribute 'kye'", ran.happened)
        self.assertEqual(ran.line, line_of(self.folder / "mine.py", "page.kye"))

    def test_a_grow_that_loses_pages_fails_on_its_line(self) -> None:
        moves = "                bigger[hash(key) % len(bigger)].append((key, page))\n"
        text = self.solution(5, moves, "                pass  # the pair is lost\n")
        checks = self.grade(5, text)
        many = checks["keeps 300 more keys"]
        self.assertFalse(many.passed, many)
        self.assertIn("get_data('k000') gave None", many.happened)
        self.assertEqual(many.line, line_of(self.folder / "mine.py", "def grow("))

    def test_process_data_for_every_page_fails_the_process_check(self) -> None:
        text = self.solution(6, "        if page.process:\n", "        if True:\n")
        checks = self.grade(6, text)
        self.assertFalse(checks["no process_data for a page with process false"].passed)
        self.assertTrue(checks["stores each page before its handlers run"].passed)

    def test_a_burst_stored_without_its_handlers_fails_the_comms_check(self) -> None:
        text = self.solution(
            6,
            "        return [snr_tasks.store_page(page) for page in task.val_list]\n",
            "        for page in task.val_list:\n"
            "            self.pages[page.key] = page\n"
            "        return None\n",
        )
        checks = self.grade(6, text)
        burst = checks["stores a burst of pages, each as its own store_page task"]
        self.assertFalse(burst.passed, burst)
        self.assertEqual(burst.happened, "none handled")
        self.assertIn("STORE_PAGES", burst.hint)
        self.assertTrue(checks["stores pages from another node, in order"].passed)

    def test_a_store_page_handler_returning_a_list_is_said(self) -> None:
        text = self.solution(
            6,
            "            return Task(TaskType.process_data, page.key, [page])\n",
            "            return [Task(TaskType.process_data, page.key, [page])]\n",
        )
        ran = self.grade(6, text)["runs without an exception"]
        self.assertFalse(ran.passed)
        self.assertIn("store_page_handler returns the page's process_data task", ran.happened)


class TestQueueMistakes(unittest.TestCase):
    """Lesson 7: each typical mistake in a task queue fails the check that names it."""

    def setUp(self) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="snr-queue-"))
        self.addCleanup(shutil.rmtree, self.folder, True)

    def grade(self, old: str, new: str) -> Dict[str, Check]:
        """Grade the solution with ``old`` replaced by ``new``: each check, by name."""
        text = (QUEUE.folder / "solution.py").read_text("utf-8")
        self.assertIn(old, text)
        path = self.folder / "mine.py"
        path.write_text(text.replace(old, new), "utf-8")
        started = time.monotonic()
        checks = {check.name: check for check in grade_file(QUEUE, path)}
        self.assertLess(time.monotonic() - started, 8.0, "a failing grade is bounded too")
        return checks

    def failed(self, checks: Dict[str, Check]) -> List[str]:
        return [name for name, check in checks.items() if not check.passed]

    def line(self, text: str) -> int:
        return line_of(self.folder / "mine.py", text)

    def wait_block(self) -> str:
        """The solution's ``wait`` from ``with self.changed:`` to its sleep."""
        text = (QUEUE.folder / "solution.py").read_text("utf-8")
        start = text.index("        with self.changed:\n            # Checked under the lock")
        end = text.index("self.changed.wait(left)", start) + len("self.changed.wait(left)")
        return text[start:end]

    def test_a_busy_wait_fails_the_idle_check_saying_so(self) -> None:
        spins = """        while not self.urgent and not self.normal and not self.closed:
            if time.monotonic() > deadline:  # checks again and again: a busy wait
                return"""
        checks = self.grade(self.wait_block(), spins)
        self.assertEqual(self.failed(checks), ["an idle consumer uses no CPU"])
        idle = checks["an idle consumer uses no CPU"]
        self.assertRegex(idle.happened, r"^wait\(0\.4\) used 0\.\d\d s of CPU in 0\.\d\d s: it ")
        self.assertIn("busy waiting", idle.happened)
        self.assertIn("self.changed.wait(left)", idle.hint)
        self.assertEqual(idle.line, self.line("def wait("))

    def test_a_check_outside_the_lock_loses_a_wake_up(self) -> None:
        outside = """        while not self.urgent and not self.normal and not self.closed:
            left = deadline - time.monotonic()
            if left <= 0:
                return
            with self.changed:  # the lock taken only to sleep: a put can slip in before
                self.changed.wait(left)"""
        checks = self.grade(self.wait_block(), outside)
        self.assertEqual(self.failed(checks), ["no wake-up is lost"])
        lost = checks["no wake-up is lost"]
        self.assertIn("was put as the consumer went to sleep, and it slept on for", lost.happened)
        self.assertIn("under one lock", lost.hint)
        self.assertEqual(lost.line, self.line("def wait("))

    def test_a_put_that_forgets_to_notify_leaves_wait_asleep(self) -> None:
        checks = self.grade(
            "            self.changed.notify_all()  # the consumer may be sleeping in wait\n", ""
        )
        wakes = checks["wait sleeps until a task comes, and returns as soon as one does"]
        self.assertFalse(wakes.passed)
        self.assertIn("(at its timeout: nothing woke it)", wakes.happened)
        self.assertIn("put calls self.changed.notify_all()", wakes.hint)
        self.assertEqual(wakes.line, self.line("def put("))
        self.assertTrue(checks["an idle consumer uses no CPU"].passed)

    def test_a_put_that_never_waits_fails_the_full_queue_checks(self) -> None:
        checks = self.grade("len(self.normal) >= self.capacity", "False")
        room = checks["put waits while the queue is full, and goes on when there is room"]
        self.assertFalse(room.passed)
        self.assertEqual(room.happened, "put returned True at once, with the queue full")
        self.assertFalse(checks["put gives up after max_wait_s"].passed)
        self.assertTrue(
            checks["many producers: every task taken once, each producer's in order"].passed
        )

    def test_an_exception_stops_the_grade_at_its_line(self) -> None:
        checks = self.grade(
            "            lane = self.urgent or self.normal\n            if not lane:\n"
            "                return None\n            task = lane.popleft()",
            "            task = self.normal.popleft()",
        )
        ran = checks["runs without an exception"]
        self.assertFalse(ran.passed)
        self.assertIn("IndexError: pop from an empty deque", ran.happened)
        self.assertEqual(ran.line, self.line("task = self.normal.popleft()"))
        self.assertEqual(len(checks), 2, "the grade stops there")

    def test_the_queue_runs_between_loops_and_a_node(self) -> None:
        for module, said in (
            (queue_solution, "each loop's once, in order."),
            (queue_starter, "were put (put returned True) but never came out of the queue."),
        ):
            with self.subTest(module=module.__name__):
                out = io.StringIO()
                log = logging.getLogger("snr.queue_demo")  # "terminated: Timeout", at the end
                self.addCleanup(log.setLevel, log.level)
                log.setLevel(logging.CRITICAL)
                with contextlib.redirect_stdout(out):
                    module.main(["task_queue.py", "--seconds", "0.3"], module.MyTaskQueue)
                self.assertRegex(out.getvalue(), r"^4 loops put [\d,]+ tasks into a MyTaskQueue")
                self.assertIn(said, out.getvalue())


class TestTheSeams(unittest.TestCase):
    """Config(datastore=..., node_core=...): SNR's own by default; a student's checked."""

    def config(self, **seams: object) -> Config:
        return Config({"a": [TimeoutLoopFactory(seconds=0)]}, mode=Mode.TEST, **seams)  # type: ignore[arg-type]

    def test_the_defaults_are_snrs_own_parts_untouched(self) -> None:
        config = Config({"a": [TimeoutLoopFactory(seconds=0)]})
        self.assertIs(config.datastore, dict)
        self.assertIsInstance(config.node_core, NodeCoreFactory)
        node = quiet_node(config)
        self.assertIs(type(node.pages), dict)
        core = node.components["node_core"]
        self.assertIsInstance(core, NodeCoreEndpoint)
        self.assertNotIn("store_page_handler", vars(core), "SNR's own is not wrapped")

    def test_a_students_datastore_is_checked_in_test_and_bare_when_deployed(self) -> None:
        checked = quiet_node(self.config(datastore=HashDatastore)).pages
        self.assertIsInstance(checked, CheckedDatastore)
        timeout = [TimeoutLoopFactory(seconds=0)]
        deployed = Config({"a": timeout}, Mode.DEPLOYED, datastore=HashDatastore)
        self.assertIs(type(quiet_node(deployed).pages), HashDatastore)

    def test_a_students_parts_run_a_node(self) -> None:
        node = quiet_node(self.config(datastore=HashDatastore, node_core=MyNodeCoreFactory()))
        node.loop()
        self.assertEqual(node.terminate_reason, "Timeout")
        self.assertEqual(type(node.components["node_core"]).__name__, "MyNodeCore")

    def test_an_instance_for_a_class_and_a_class_for_a_factory_are_said(self) -> None:
        with self.assertRaises(ConfigError) as said:
            self.config(datastore=HashDatastore())
        self.assertIn("the class, as in Config(..., datastore=HashDatastore)", str(said.exception))
        with self.assertRaises(ConfigError) as said:
            self.config(node_core=MyNodeCoreFactory)
        self.assertIn("node_core=MyNodeCoreFactory()), an instance", str(said.exception))

    def test_a_datastore_without_a_method_is_named(self) -> None:
        class NoLen:
            def __setitem__(self, key: str, page: Page) -> None:
                pass

            def get(self, key: str) -> Optional[Page]:
                return None

            def __iter__(self) -> Iterator[str]:
                return iter([])

        with self.assertRaises(ConfigError) as said:
            quiet_node(self.config(datastore=NoLen))
        self.assertIn("NoLen", str(said.exception))
        self.assertIn("has no __len__: a datastore needs __setitem__, get", str(said.exception))

    def test_a_core_that_is_not_one_is_told_to_extend_node_core(self) -> None:
        from snr import Endpoint, EndpointFactory

        class Named(EndpointFactory):
            def get(self, parent: object) -> Endpoint:
                return Endpoint(self, parent, "brain")  # type: ignore[arg-type]

        with self.assertRaises(ConfigError) as said:
            quiet_node(self.config(node_core=Named()))
        self.assertIn("named 'brain': a node core is named 'node_core'", str(said.exception))
        self.assertIn("Extend snr.core.NodeCore", str(said.exception))

    def test_a_node_core_without_store_page_handler_names_it(self) -> None:
        class Half(NodeCore):
            pass

        class HalfFactory(NodeCoreFactory):
            def get(self, parent: object) -> NodeCore:  # type: ignore[override]
                return Half(self, parent)  # type: ignore[abstract, arg-type]

        with self.assertRaises(ComponentError) as said:
            quiet_node(self.config(node_core=HalfFactory()))
        self.assertIn("store_page_handler", str(said.exception))

    def test_a_task_the_core_does_not_handle_is_warned_once(self) -> None:
        class Mute(NodeCore):
            def store_page_handler(self, task: object, key: object) -> None:
                return None

        class MuteFactory(NodeCoreFactory):
            def get(self, parent: object) -> NodeCore:  # type: ignore[override]
                return Mute(self, parent)  # type: ignore[arg-type]

        with self.assertLogs("snr.a", logging.WARNING) as logs:
            Node("a", self.config(node_core=MuteFactory()))
        said = "\n".join(logs.output)
        self.assertIn("The node core Mute handles no terminate task: the node will not stop", said)
        self.assertEqual(len(logs.output), 5, logs.output)

    def test_a_wrong_answer_is_an_snr_error(self) -> None:
        class DataNotPage(HashDatastore):
            def get(self, key: str) -> Optional[Page]:
                page = super().get(key)
                return None if page is None else page.data

        store = CheckedDatastore(DataNotPage())
        store["depth"] = Page("depth", 2.5, "robot", 0.0)
        with self.assertRaises(SNRError) as said:
            store.get("depth")
        self.assertIn("get('depth') returned 2.5 (float)", str(said.exception))


if __name__ == "__main__":
    unittest.main()
