"""`SNRTestCase`: unittest.TestCase with SNR helpers (thesis 6.5)."""

from __future__ import annotations

import os
import unittest
from typing import Any, Optional, Sequence

from snr.core import Config, Node, TestRunner
from snr.prelude import AbstractFactory, DataKey, Mode, Page, TaskId
from snr.utils.expector import Expectations, Expector, OrderedExpector
from snr.utils.mock_node import MockNode

__all__ = ["SNRTestCase"]


class SNRTestCase(unittest.TestCase):
    """A TestCase that can run a node, expect tasks and make temp files.

    Works with ``python -m unittest`` and with pytest.

    Example (thesis listing A.3)::

        class TestFilter(SNRTestCase):
            def test_filter(self) -> None:
                with self.expector({(TaskType.store_page, "out"): 4}) as expector:
                    self.run_test_node([
                        ListReplayerFactory([0, 1, 2, 4], "in"),
                        MovingAvgFilterFactory("in", "out", 2),
                        ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                    ])
    """

    role = "test"
    """The role of nodes built by ``get_config`` and ``run_test_node``."""

    def expector(self, expectations: Expectations) -> Expector:
        """An `Expector` that fails this test when unmet."""
        return Expector(expectations, self)

    def ordered_expector(self, expectations: Sequence[TaskId]) -> OrderedExpector:
        """An `OrderedExpector` that fails this test when unmet."""
        return OrderedExpector(expectations, self)

    def get_config(self, factories: Sequence[AbstractFactory], mode: Mode = Mode.TEST) -> Config:
        """A config with one role, ``"test"``, holding ``factories``."""
        return Config({self.role: list(factories)}, mode=mode)

    def run_test_node(
        self,
        factories: Sequence[AbstractFactory],
        mode: Mode = Mode.TEST,
        timeout_s: float = 10.0,
    ) -> Node:
        """Build a node from ``factories`` and run it (at most ``timeout_s``).

        A handler that raises fails the test, naming the handler and task.
        Returns the stopped node, to inspect its datastore.
        """
        runner = TestRunner(self.role, self.get_config(factories, mode), timeout_s)
        runner.run()
        assert runner.node is not None
        return runner.node

    def mock_node(self, mode: Mode = Mode.TEST) -> MockNode:
        """A `MockNode` for testing a component's handlers directly."""
        return MockNode(mode=mode)

    def temp_file(self, suffix: str = "", contents: Optional[str] = None) -> str:
        """A path in a fresh temp folder, removed after the test."""
        import shutil  # here, not at the top: most tests need no files
        import tempfile

        folder = tempfile.mkdtemp(prefix="snr-test-")
        self.addCleanup(shutil.rmtree, folder, True)
        path = os.path.join(folder, f"file{suffix}")
        if contents is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(contents)
        return path

    def assertPage(
        self,
        page: Optional[Page],
        key: DataKey,
        data: Any,
        origin: Optional[str] = None,
        msg: Optional[str] = None,
    ) -> None:
        """Assert ``page`` is a Page with this key and data (and origin)."""
        self.assertIsInstance(page, Page, msg or f"expected a Page for {key!r}, got {page!r}")
        assert isinstance(page, Page)
        self.assertEqual(page.key, key, msg)
        self.assertEqual(page.data, data, msg)
        if origin is not None:
            self.assertEqual(page.origin, origin, msg)
