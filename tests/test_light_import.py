"""``import snr`` stays light: heavy modules load only when they are used.

Nothing here is timed (``bench/bench_import.py`` measures the time); the
tests check *which* modules a fresh interpreter has loaded.
"""

import dataclasses
import json
import os
import subprocess
import sys
import unittest
from typing import Dict, List

from snr import Page, Task, TaskType
from snr.prelude import TaskPriority

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Loaded only by the code that needs them: Page/Task (de)serialization,
# SNRTestCase, the ready-made components and the extras (any module of
# snr.extras loads the package snr.extras first).
HEAVY = [
    "dataclasses_json",
    "marshmallow",
    "unittest",
    "snr.std_mods",
    "snr.extras",
    "snr.extras.compat2021",
    "multiprocessing",
    "argparse",
]

# Loaded by the first use, not by ``import snr``: the testing utilities, the
# words for an abstract class built, and the helpers read second that only a
# built node needs (the last four).
FIRST_USE = [
    "snr.utils",
    "snr.prelude.abstract_errors",
    "snr.core.checks.read_only",
    "snr.core.checks.failures",
    "snr.core.checks.seam_checks",
    "snr.core.checks.step_mode",
]


def loaded_after(code: str, modules: List[str]) -> Dict[str, bool]:
    """Which of ``modules`` a fresh interpreter has loaded after running ``code``."""
    script = (
        f"{code}\nimport json, sys\nprint(json.dumps({{m: m in sys.modules for m in {modules!r}}}))"
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]))
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=60,
        check=True,
    )
    loaded: Dict[str, bool] = json.loads(result.stdout.strip().splitlines()[-1])
    return loaded


class TestLightImport(unittest.TestCase):
    def test_import_snr_loads_none_of_the_heavy_modules(self) -> None:
        loaded = loaded_after("import snr", HEAVY)
        self.assertEqual([m for m, yes in loaded.items() if yes], [])

    def test_import_snr_leaves_what_a_node_or_a_test_needs_for_their_first_use(self) -> None:
        self.assertEqual([m for m, yes in loaded_after("import snr", FIRST_USE).items() if yes], [])
        config = "snr.Config({'robot': [snr.TimeoutLoopFactory(seconds=1)]}, mode=snr.Mode.TEST)"
        node = f"import snr\nsnr.Node('robot', {config})"
        self.assertEqual([m for m, yes in loaded_after(node, FIRST_USE[2:]).items() if not yes], [])
        loaded = loaded_after("import snr\nsnr.SimClock", ["snr.utils"])
        self.assertEqual(loaded, {"snr.utils": True})

    def test_from_snr_import_star_does_not_load_dataclasses_json(self) -> None:
        loaded = loaded_after("from snr import *", ["dataclasses_json", "marshmallow"])
        self.assertEqual([m for m, yes in loaded.items() if yes], [])

    def test_the_json_backend_is_chosen_when_first_used_not_at_import(self) -> None:
        """Finding the backends reads the entry points (importlib.metadata, ~13 ms)."""
        loaded = loaded_after("from snr import *", ["importlib.metadata"])
        self.assertEqual(loaded, {"importlib.metadata": False})
        code = "from snr.std_mods import codec\ncodec.dump_json({'a': 1})"
        self.assertEqual(loaded_after(code, ["importlib.metadata"]), {"importlib.metadata": True})

    def test_serialize_loads_dataclasses_json_and_round_trips(self) -> None:
        code = (
            "import snr\n"
            "from snr.prelude import TaskPriority\n"
            "page = snr.Page('depth', {'m': [1.5, 2]}, 'urov', 12.5, process=False)\n"
            "assert snr.Page.deserialize(page.serialize()) == page\n"
            "task = snr.Task(snr.TaskType.event, 'go', [1], TaskPriority.high)\n"
            "assert snr.Task.deserialize(task.serialize()) == task\n"
        )
        self.assertEqual(loaded_after(code, ["dataclasses_json"]), {"dataclasses_json": True})

    def test_lazy_names_load_on_first_use(self) -> None:
        code = (
            "import snr\n"
            "assert snr.SNRTestCase.__name__ == 'SNRTestCase'\n"
            "assert snr.TimeoutLoopFactory.__name__ == 'TimeoutLoopFactory'\n"
            "assert snr.SocketsPair is snr.std_mods.comms.SocketsPair\n"
            "assert snr.MPExpector is snr.MultiProcExpector\n"
        )
        self.assertEqual(
            loaded_after(code, ["unittest", "snr.std_mods", "snr.extras.compat2021"]),
            {"unittest": True, "snr.std_mods": True, "snr.extras.compat2021": True},
        )

    def test_unknown_names_still_raise_attribute_error(self) -> None:
        import snr

        with self.assertRaises(AttributeError):
            snr.NoSuchThing  # noqa: B018


class TestPageAndTaskStillDataclassJson(unittest.TestCase):
    """Page and Task keep every dataclasses-json method and dataclass behaviour."""

    page = Page("depth", {"m": [1.5, 2]}, origin="urov", created_at_s=12.5, process=False)
    task = Task(TaskType.event, "go", [1, "a"], TaskPriority.high)

    def test_json_and_dict_methods(self) -> None:
        text = self.page.to_json()
        self.assertEqual(text, self.page.serialize())
        self.assertEqual(json.loads(text)["origin"], "urov")
        self.assertEqual(Page.from_json(text), self.page)
        self.assertEqual(self.page.to_dict()["data"], {"m": [1.5, 2]})
        self.assertEqual(Page.from_dict(self.page.to_dict()), self.page)
        self.assertEqual(self.task.to_dict(encode_json=True)["type"], "event")
        self.assertEqual(Task.from_dict(self.task.to_dict()), self.task)
        self.assertIn('\n  "key"', self.page.to_json(indent=2))

    def test_from_json_infers_missing_fields_when_asked(self) -> None:
        text = '{"key": "k", "data": 1, "origin": "a", "created_at_s": 0}'
        self.assertTrue(Page.from_json(text, infer_missing=True).process)
        again = Task.from_json('{"type": "event", "name": "x"}', infer_missing=True)
        self.assertEqual(again, Task(TaskType.event, "x"))

    def test_schema(self) -> None:
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # dataclasses-json notes the string annotations
            self.assertEqual(Page.schema().dump(self.page)["key"], "depth")

    def test_is_a_data_class_json_mixin_once_loaded(self) -> None:
        from dataclasses_json import DataClassJsonMixin

        self.page.to_json()
        self.assertIsInstance(self.page, DataClassJsonMixin)
        self.assertTrue(issubclass(Task, DataClassJsonMixin))

    def test_dataclass_behaviour(self) -> None:
        self.assertTrue(dataclasses.is_dataclass(Page))
        self.assertEqual([f.name for f in dataclasses.fields(Task)][:2], ["type", "name"])
        changed = dataclasses.replace(self.page, data=3)
        self.assertEqual((changed.data, changed.key), (3, "depth"))
        self.assertNotEqual(changed, self.page)
        self.assertIsNone(Page.__hash__)  # mutable dataclasses are unhashable, as before


if __name__ == "__main__":
    unittest.main()


# Packages only an extra brings (serial, controller, view, mcap, zenoh, docs, fast).
OPTIONAL_PACKAGES = ["serial", "pygame", "mcap", "websockets", "zenoh", "pdoc", "orjson"]

IMPORT_EVERY_MODULE_WITHOUT_EXTRAS = f"""
import importlib, importlib.abc, pkgutil, sys

class NoExtras(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {OPTIONAL_PACKAGES!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None

sys.meta_path.insert(0, NoExtras())
import snr
failed = []
for info in pkgutil.walk_packages(snr.__path__, "snr."):
    if info.name in ("snr.__main__",):
        continue
    try:
        importlib.import_module(info.name)
    except ImportError as error:
        failed.append(f"{{info.name}}: {{error}}")
print("\\n".join(failed) or "all imported")
"""


class TestModulesImportWithoutExtras(unittest.TestCase):
    def test_every_snr_module_imports_without_the_optional_packages(self) -> None:
        # The docs build imports every module; a plain `pip install .` has no extras.
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]))
        result = subprocess.run(
            [sys.executable, "-c", IMPORT_EVERY_MODULE_WITHOUT_EXTRAS],
            capture_output=True,
            text=True,
            env=env,
            cwd=ROOT,
            timeout=60,
        )
        self.assertEqual(result.stdout.strip(), "all imported", result.stdout + result.stderr)
