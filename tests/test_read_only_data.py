"""Read-only page data (snr.core.checks.read_only): refuses every change, reads as plain data."""

from __future__ import annotations

import copy
import json
import pickle
import unittest
from typing import Any, Callable, List, Tuple

from snr import Config, Mode, Node, Page, TimeoutLoopFactory, tasks
from snr.core.checks.read_only import ReadOnlyDict, ReadOnlyList, freeze
from tests.quiet import captured_logs


class TestFreeze(unittest.TestCase):
    def test_lists_and_dicts_at_every_depth_become_read_only(self) -> None:
        data = freeze({"pose": [1.0, 2.0], "ranges": [[0.5], [0.7]], "n": 3}, "robot")
        self.assertIsInstance(data, ReadOnlyDict)
        self.assertIsInstance(data["pose"], ReadOnlyList)
        self.assertIsInstance(data["ranges"][1], ReadOnlyList)
        self.assertEqual(data, {"pose": [1.0, 2.0], "ranges": [[0.5], [0.7]], "n": 3})
        self.assertEqual(data["ranges"][1].key, "robot")  # a nested list names its page

    def test_the_producers_own_list_is_not_the_pages(self) -> None:
        mine = [1.0, 2.0]
        data = freeze(mine, "scan")
        mine.append(3.0)  # the loop that stored it keeps a list of its own
        self.assertEqual(data, [1.0, 2.0])

    def test_values_that_cannot_change_and_other_objects_pass_as_they_are(self) -> None:
        marker = {1, 2}  # a set: not JSON page data, left to the student
        for value in (3.2, 7, "ok", None, True, b"x", (1, 2), marker):
            with self.subTest(value=value):
                self.assertIs(freeze(value, "k"), value)

    def test_a_tuple_holding_a_list_is_rebuilt(self) -> None:
        data = freeze((1, [2]), "k")
        self.assertEqual(data, (1, [2]))
        self.assertIsInstance(data[1], ReadOnlyList)

    def test_it_reads_serialises_and_copies_as_plain_data(self) -> None:
        data = freeze({"pose": [1.0, 2.0]}, "robot")
        self.assertEqual(json.dumps(data), '{"pose": [1.0, 2.0]}')
        self.assertEqual(str(data), "{'pose': [1.0, 2.0]}")
        for copied in (pickle.loads(pickle.dumps(data)), copy.copy(data), copy.deepcopy(data)):
            self.assertIs(type(copied), dict)
            self.assertEqual(copied, {"pose": [1.0, 2.0]})
        self.assertIs(type(copy.deepcopy(data)["pose"]), list)  # all of it the student's own
        self.assertIs(type(list(data["pose"])), list)
        self.assertIs(type(data["pose"][:]), list)
        self.assertEqual(sorted(freeze([3, 1], "k")), [1, 3])


class TestEveryChangeIsRefused(unittest.TestCase):
    def refused(self, change: Callable[[], Any]) -> str:
        with self.assertRaises(TypeError) as caught:
            change()
        return str(caught.exception)

    def test_every_changing_list_method(self) -> None:
        data = freeze([3.0, 1.0], "scan")
        changes: List[Tuple[str, Callable[[], Any]]] = [
            (".append()", lambda: data.append(1.0)),
            (".extend()", lambda: data.extend([1.0])),
            (".insert()", lambda: data.insert(0, 1.0)),
            (".pop()", lambda: data.pop()),
            (".remove()", lambda: data.remove(3.0)),
            (".clear()", lambda: data.clear()),
            (".sort()", lambda: data.sort()),
            (".reverse()", lambda: data.reverse()),
            ("setting an item", lambda: data.__setitem__(0, 2.0)),
            ("del", lambda: data.__delitem__(0)),
            ("+=", lambda: data.__iadd__([1.0])),
            ("*=", lambda: data.__imul__(2)),
        ]
        for what, change in changes:
            with self.subTest(what):
                message = self.refused(change)
                self.assertIn(f"The data of page 'scan' is read-only: {what} would change", message)
                self.assertIn("mine = list(task.val_list[0].data)", message)
                self.assertIn("mine = list(self.get_data('scan'))", message)
        self.assertEqual(data, [3.0, 1.0])  # nothing changed

    def test_every_changing_dict_method(self) -> None:
        data = freeze({"x": 1.0}, "pose")
        changes: List[Tuple[str, Callable[[], Any]]] = [
            (".update()", lambda: data.update(y=2.0)),
            (".pop()", lambda: data.pop("x")),
            (".popitem()", lambda: data.popitem()),
            (".clear()", lambda: data.clear()),
            (".setdefault()", lambda: data.setdefault("y", 2.0)),
            ("setting an item", lambda: data.__setitem__("y", 2.0)),
            ("del", lambda: data.__delitem__("x")),
            ("|=", lambda: data.__ior__({"y": 2.0})),
        ]
        for what, change in changes:
            with self.subTest(what):
                message = self.refused(change)
                self.assertIn(f"The data of page 'pose' is read-only: {what} would change", message)
                self.assertIn("mine = dict(task.val_list[0].data)", message)
        self.assertEqual(data, {"x": 1.0})

    def test_sort_and_reverse_name_the_copy_that_does_it(self) -> None:
        data = freeze([3.0, 1.0], "scan")
        self.assertIn(
            "sorted(data) gives a sorted copy. Otherwise copy it", self.refused(data.sort)
        )
        self.assertIn("data[::-1] gives a reversed copy", self.refused(data.reverse))

    def test_augmented_assignment_at_a_students_line(self) -> None:
        data = freeze({"ranges": [0.5]}, "lidar")
        ranges = data["ranges"]
        with self.assertRaises(TypeError) as caught:
            ranges += [0.7]
        self.assertIn("+= would change it for every handler of 'lidar'", str(caught.exception))


if __name__ == "__main__":
    unittest.main()


class TestTheNodeStoresReadOnlyData(unittest.TestCase):
    """DEBUG and TEST store read-only data; DEPLOYED stores it as it is (each node runs 0.2 s)."""

    def stored(self, mode: Mode, data: Any) -> Any:
        node = Node("robot", Config({"robot": [TimeoutLoopFactory(seconds=0.2)]}, mode=mode))
        node.store_data("scan", data)
        with captured_logs("snr.robot"):
            node.loop()
        return node.get_data("scan")

    def test_each_mode(self) -> None:
        for mode, kind in (
            (Mode.DEBUG, ReadOnlyList),
            (Mode.TEST, ReadOnlyList),
            (Mode.DEPLOYED, list),
        ):
            with self.subTest(mode):
                mine = [1.0, [2.0]]
                data = self.stored(mode, mine)
                self.assertIs(type(data), kind)
                self.assertEqual(data, [1.0, [2.0]])
                if mode is not Mode.DEPLOYED:
                    self.assertIsNot(data, mine)  # the loop's own list is not the page's
                    self.assertIs(type(data[1]), ReadOnlyList)

    def test_a_burst_of_pages_is_read_only_too(self) -> None:
        node = Node("robot", Config({"robot": [TimeoutLoopFactory(seconds=0.2)]}))
        pages = [Page("scan", [float(i)], "other", 0.0) for i in range(3)]
        node.schedule(tasks.store_pages(pages))
        with captured_logs("snr.robot"):
            node.loop()
        self.assertIs(type(node.get_data("scan")), ReadOnlyList)
        self.assertEqual(node.get_data("scan"), [2.0])
