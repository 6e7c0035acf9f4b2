"""Page, Task, TaskType and the Serializable protocol."""

import re
import unittest
from typing import List

from snr import Page, Task, TaskType, tasks
from snr.prelude import Serializable, TaskPriority


class TestPage(unittest.TestCase):
    def test_round_trip(self) -> None:
        page = Page("depth", {"m": [1.5, 2]}, origin="urov", created_at_s=12.5, process=False)
        self.assertEqual(Page.deserialize(page.serialize()), page)

    def test_equality_compares_every_field(self) -> None:
        page = Page("k", 1, "a", 1.0)
        self.assertEqual(page, Page("k", 1, "a", 1.0))
        self.assertNotEqual(page, Page("k", 2, "a", 1.0))
        self.assertNotEqual(page, Page("k", 1, "b", 1.0))
        self.assertNotEqual(page, Page("k", 1, "a", 2.0))
        self.assertNotEqual(page, Page("other", 1, "a", 1.0))
        self.assertNotEqual(page, Page("k", 1, "a", 1.0, process=False))

    def test_is_serializable(self) -> None:
        self.assertIsInstance(Page("k", 1, "a", 1.0), Serializable)
        self.assertIsInstance(tasks.event("x"), Serializable)


class TestTask(unittest.TestCase):
    def test_round_trip(self) -> None:
        task = Task(TaskType.event, "button_pressed", ["A", 2], TaskPriority.high)
        again = Task.deserialize(task.serialize())
        self.assertEqual(again, task)
        self.assertIs(again.type, TaskType.event)
        self.assertIs(again.priority, TaskPriority.high)

    def test_default_val_list_is_not_shared(self) -> None:
        a, b = Task(TaskType.event, "a"), Task(TaskType.event, "b")
        a.val_list.append(1)
        self.assertEqual(b.val_list, [])

    def test_equality(self) -> None:
        self.assertEqual(tasks.event("x", [1]), tasks.event("x", [1]))
        self.assertNotEqual(tasks.event("x", [1]), tasks.event("x", [2]))
        self.assertNotEqual(tasks.event("x"), tasks.event("y"))

    def test_id(self) -> None:
        self.assertEqual(tasks.event("go").id(), (TaskType.event, "go"))

    def test_str_matches_thesis_figure(self) -> None:
        self.assertEqual(
            str(tasks.event("button_pressed", ["A"])), "(event, 'button_pressed'): ['A']"
        )


class TestTaskType(unittest.TestCase):
    def test_store_data_is_store_page(self) -> None:
        self.assertIs(TaskType.store_data, TaskType.store_page)
        self.assertEqual({(TaskType.store_data, "k"): 1}[(TaskType.store_page, "k")], 1)

    def test_members(self) -> None:
        names = {t.name for t in TaskType}
        self.assertLessEqual({"event", "store_page", "process_data", "reload", "terminate"}, names)

    def test_terminate_is_urgent(self) -> None:
        self.assertIs(tasks.terminate("bye").priority, TaskPriority.high)
        self.assertIs(tasks.event("x").priority, TaskPriority.normal)


if __name__ == "__main__":
    unittest.main()


class TestTaskPage(unittest.TestCase):
    def test_the_page_a_store_task_carries(self) -> None:
        page = Page("depth", 2.5, "robot", 0.0)
        self.assertIs(tasks.store_page(page).page(), page)

    def test_none_when_the_task_carries_no_page(self) -> None:
        for task in (
            tasks.event("go"),
            tasks.event("go", [3, Page("k", 1, "r", 0.0)]),  # a page that is not first
            Task(TaskType.store_page, "k", "not a list"),  # type: ignore[arg-type]
        ):
            with self.subTest(task=task):
                self.assertIsNone(task.page())


class TestErrorTree(unittest.TestCase):
    """snr/prelude/errors.py draws the tree of every SNR error; it must stay complete."""

    def test_every_snr_error_in_the_package_is_in_the_drawing(self) -> None:
        import importlib
        import pkgutil

        import snr
        import snr.prelude.errors as errors
        from snr.prelude.errors import SNRError

        for module in pkgutil.walk_packages(snr.__path__, "snr."):
            if module.name.endswith("__main__"):  # a program, not a module to import
                continue
            try:
                importlib.import_module(module.name)
            except ImportError:  # an optional extra that is not installed
                continue
        found: List[type] = []
        todo: List[type] = [SNRError]
        while todo:
            cls = todo.pop()
            found.append(cls)
            # Not counted: the tests' own errors; the docs builder's (a tool, not the runtime).
            subclasses: List[type] = cls.__subclasses__()
            todo.extend(
                k
                for k in subclasses
                if k.__module__.startswith("snr.")
                and not k.__module__.startswith("snr.extras.docs.")
            )
        drawing = (errors.__doc__ or "").split("The tree::", 1)[1]
        drawn = re.findall(r"(?:^ +|\+-- )([A-Z]\w+Error)\b", drawing, re.M)
        self.assertEqual(sorted(drawn), sorted(errors.__all__))
        self.assertGreaterEqual(len(found), 13)
        for cls in found:
            with self.subTest(error=cls.__name__):
                self.assertIn(cls.__name__, drawn)
                self.assertEqual(cls.__module__, "snr.prelude.errors", "define it in the tree")
