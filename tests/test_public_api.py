"""The student-facing surface: `from snr import *` and its documentation."""

import inspect
import unittest

import snr


class TestPublicApi(unittest.TestCase):
    def test_all_is_sorted_and_importable(self) -> None:
        self.assertEqual(snr.__all__, sorted(snr.__all__))
        for name in snr.__all__:
            self.assertTrue(hasattr(snr, name), name)

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
            module = __import__(info.name, fromlist=["_"])
            self.assertTrue(hasattr(module, "__all__"), info.name)


if __name__ == "__main__":
    unittest.main()
