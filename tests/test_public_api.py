"""The student-facing surface: `from snr import *` and its documentation."""

import inspect
import unittest

import snr
from tests.optional import reason


class TestPublicApi(unittest.TestCase):
    def test_all_is_sorted_and_importable(self) -> None:
        self.assertEqual(snr.__all__, sorted(snr.__all__))
        for name in snr.__all__:
            self.assertTrue(hasattr(snr, name), name)

    def test_lazy_names_are_exported_and_from_where_they_say(self) -> None:
        # snr/__init__.py imports these on first use (PEP 562); the table must
        # follow snr.std_mods and __all__ when names are added.
        import snr.std_mods

        lazy = snr._LAZY
        std = sorted(name for name, module in lazy.items() if module == "snr.std_mods")
        self.assertEqual(std, sorted(snr.std_mods.__all__))
        for name, module in lazy.items():
            self.assertIn(name, snr.__all__)
            self.assertIs(getattr(snr, name), getattr(__import__(module, fromlist=["_"]), name))

    def test_dir_lists_every_export(self) -> None:
        self.assertLessEqual(set(snr.__all__), set(dir(snr)))

    def test_names_the_thesis_listings_use(self) -> None:
        needed = [
            "Endpoint",
            "EndpointFactory",
            "LoopFactory",
            "ThreadLoop",
            "AbstractNode",
            "Task",
            "TaskType",
            "TaskId",
            "SomeTasks",
            "Page",
            "DataKey",
            "TaskName",
            "ComponentName",
            "ComponentsByRole",
            "Config",
            "CliRunner",
            "SynchronousRunner",
            "Node",
            "Mode",
            "Timer",
            "SNRTestCase",
            "TimeoutLoopFactory",
            "StopwatchEndpointFactory",
            "PrinterEndpointFactory",
            "ListReplayerFactory",
            "MovingAvgFilterFactory",
            "ExpecterEndpointFactory",
            "tasks",
        ]
        for name in needed:
            self.assertIn(name, snr.__all__)

    def test_every_public_name_is_documented_with_an_example(self) -> None:
        missing = []
        for name in snr.__all__:
            obj = getattr(snr, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj) or inspect.ismodule(obj)):
                continue
            if getattr(obj, "__module__", "") == "builtins":
                continue  # a type alias such as DataKey = str
            doc = inspect.getdoc(obj) or ""
            if "Example" not in doc:
                missing.append(name)
        self.assertEqual(missing, [], "public names without a docstring example")

    def test_every_module_declares_all(self) -> None:
        import pkgutil

        for info in pkgutil.walk_packages(snr.__path__, "snr."):
            if info.name.endswith("__main__"):
                continue
            with self.subTest(module=info.name):
                try:
                    module = __import__(info.name, fromlist=["_"])
                except ModuleNotFoundError as error:
                    package = (error.name or "snr").split(".")[0]
                    if package == "snr":
                        raise
                    # A module for an extra, e.g. the live view's server needs websockets.
                    self.skipTest(reason(package))
                self.assertTrue(hasattr(module, "__all__"), info.name)


if __name__ == "__main__":
    unittest.main()
