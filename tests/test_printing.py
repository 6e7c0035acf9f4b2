"""How pages and tasks print: a short line for people, the full repr for debugging."""

import time
import unittest

from snr import Page, Task, TaskType, tasks
from snr.std_mods.utils import format_task


class TestPagePrinting(unittest.TestCase):
    def test_str_names_key_data_origin_and_age(self) -> None:
        page = Page("depth", 2.5, "robot", time.time() - 0.3)
        self.assertRegex(str(page), r"^Page 'depth' = 2\.5 from 'robot' \(0\.[34] s ago\)$")

    def test_repr_is_the_dataclass_repr_with_every_field(self) -> None:
        page = Page("depth", 2.5, "robot", 12.5, process=False)
        self.assertEqual(
            repr(page),
            "Page(key='depth', data=2.5, origin='robot', created_at_s=12.5, process=False)",
        )

    def test_ages_in_minutes_hours_then_a_date(self) -> None:
        now = time.time()
        self.assertIn("(5.0 min ago)", str(Page("k", 1, "r", now - 300)))
        self.assertIn("(2.0 h ago)", str(Page("k", 1, "r", now - 7200)))
        self.assertIn("(made 1970-01-01 00:00:00 UTC)", str(Page("k", 1, "r", 0.0)))

    def test_a_page_from_a_clock_that_is_ahead_says_so(self) -> None:
        self.assertIn("s in the future: the clocks differ", str(Page("k", 1, "r", time.time() + 5)))

    def test_long_data_is_cut_short_but_repr_keeps_it(self) -> None:
        page = Page("big", list(range(10_000)), "r", time.time())
        self.assertLess(len(str(page)), 1100)
        self.assertIn("...", str(page))
        self.assertIn("9999", repr(page))
        buttons = {f"button_{i}": 0 for i in range(21)}  # a game pad's, shown whole
        self.assertIn("'button_20': 0}", str(Page("pad", buttons, "r", time.time())))

    def test_a_bad_time_still_prints(self) -> None:
        for when in [float("nan"), "yesterday", 1e300]:
            page = Page("k", 1, "r", when)  # type: ignore[arg-type]
            self.assertIn(f"created_at_s={when!r}", str(page))


class TestTaskPrinting(unittest.TestCase):
    def test_events_print_as_thesis_figure_5_4(self) -> None:
        task = Task(TaskType.event, "button_pressed", ["A"])
        self.assertEqual(str(task), "(event, 'button_pressed'): ['A']")
        self.assertEqual(format_task(task), str(task))

    def test_pages_inside_a_task_print_short(self) -> None:
        page = Page("depth", 2.5, "robot", time.time())
        self.assertEqual(
            str(tasks.store_page(page)),
            "(store_page, 'depth'): [Page 'depth' = 2.5 from 'robot' (0.0 s ago)]",
        )
        self.assertIn("Page(key='depth'", repr(tasks.store_page(page)))

    def test_one_formatter_for_tasks_and_ids(self) -> None:
        store = tasks.store_page(Page("depth", 2.5, "robot", time.time()))
        self.assertEqual(format_task(store, values="data"), "(store_page, 'depth'): 2.5")
        self.assertEqual(format_task(store, values="none"), "(store_page, 'depth')")
        self.assertEqual(format_task(tasks.event("b", [1]), values="data"), "(event, 'b'): [1]")
        self.assertEqual(format_task((TaskType.event, "go")), "(event, 'go')")
        self.assertEqual(format_task(TaskType.terminate), "(terminate)")
        odd = Task(TaskType.event, "x", "not a list")  # type: ignore[arg-type]
        self.assertEqual(format_task(odd), "(event, 'x'): 'not a list'")


if __name__ == "__main__":
    unittest.main()
