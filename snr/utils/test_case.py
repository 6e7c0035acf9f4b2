"""`SNRTestCase`: unittest.TestCase with SNR helpers (thesis 6.5)."""

from __future__ import annotations

import os
import unittest
from typing import Any, List, Mapping, Optional, Sequence, Union, cast

from snr.core import Config, Node, TestRunner
from snr.core.components import NODE_CORE_NAME
from snr.prelude import AbstractFactory, AbstractLoop, DataKey, Mode, Page
from snr.utils.expector import Expector, K, OrderedExpector
from snr.utils.expector_endpoint import ExpectorEndpoint
from snr.utils.mock_node import MockNode
from snr.utils.temp_file import TempFile

__all__ = ["SNRTestCase"]

# unittest (and pytest) leave out the frames of modules that set this, so a
# failed expectation points at the test's own line, not at SNR's.
__unittest = True


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

    timeout_s: float = 2.0
    """The default time limit of ``run_test_node``, in seconds (set more on a slow test class)."""

    def expector(self, expectations: Mapping[K, int]) -> Expector[K]:
        """An `Expector` that fails this test when unmet."""
        return Expector(expectations, self)

    def ordered_expector(self, expectations: Sequence[K]) -> OrderedExpector[K]:
        """An `OrderedExpector` that fails this test when unmet."""
        return OrderedExpector(expectations, self)

    def get_config(self, factories: Sequence[AbstractFactory], mode: Mode = Mode.TEST) -> Config:
        """A config with one role, ``"test"``, holding ``factories``."""
        return Config({self.role: list(factories)}, mode=mode)

    def run_test_node(
        self,
        factories: Sequence[AbstractFactory],
        mode: Mode = Mode.TEST,
        timeout_s: Optional[float] = None,
        expect_timeout: bool = False,
    ) -> Node:
        """Build a node from ``factories``, run it until it stops, and return it.

        The node must stop by itself; one still running after ``timeout_s``
        fails the test (docs/utilities.md, "Ending a node under test").

        Args:
            factories: the components of the node (its role is ``self.role``).
            mode: the node's mode (TEST: failures stop the node and fail the test).
            timeout_s: the time limit in seconds; None for ``self.timeout_s``.
            expect_timeout: run until the time limit on purpose (the test
                fails if the node stopped before it).

        Returns:
            The stopped node, to inspect its datastore.

        Example::

            with self.expector({(TaskType.store_page, "out"): 4}) as expector:
                node = self.run_test_node([
                    ListReplayerFactory([0, 1, 2, 4], "in"),
                    MovingAvgFilterFactory("in", "out", 2),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ])
            self.run_test_node([DummyEndpointFactory()], timeout_s=0.2, expect_timeout=True)
        """
        limit = self.timeout_s if timeout_s is None else timeout_s
        runner = TestRunner(self.role, self.get_config(factories, mode), limit)
        runner.run()
        node = cast(Node, runner.node)
        if runner.timed_out and not expect_timeout:
            self.fail(_timed_out_message(node, limit, runner.alive_at_timeout))
        if expect_timeout and not runner.timed_out:
            self.fail(
                f"The {node.role!r} node was expected to run until its time limit of "
                f"{limit:g} s, but it stopped earlier: {node.terminate_reason}. Leave "
                "out expect_timeout=True if the node should stop by itself."
            )
        return node

    def mock_node(self, mode: Mode = Mode.TEST) -> MockNode:
        """A `MockNode` for testing a component's handlers directly."""
        return MockNode(mode=mode)

    def temp_file(
        self,
        name: Optional[str] = None,
        contents_or_overwrite: Union[str, bool, None] = None,
        cleanup: bool = True,
        *,
        suffix: Optional[str] = None,
        contents: Optional[str] = None,
        filename: Optional[str] = None,
        overwrite: bool = False,
    ) -> TempFile:
        """A file's path in a fresh temp folder, removed after the test.

        ``temp_file(suffix="", contents=None)`` names the file ``file`` +
        ``suffix``; the 2021 call ``temp_file(filename, overwrite, cleanup)``
        still works (docs/utilities.md).

        Returns:
            A `TempFile` (a ``str`` path with helpers).

        Example::

            path = self.temp_file(".jsonl")           # '/tmp/snr-test-.../file.jsonl'
            script = self.temp_file("_main.py", "print('hi')\n")
            with self.temp_file() as f:               # 2021 style
                with f.open() as out:
                    out.write("data")
        """
        import shutil  # here, not at the top: most tests need no files
        import tempfile

        if isinstance(contents_or_overwrite, str):  # a bool is overwrite, which changes nothing
            if contents is not None:
                raise TypeError("temp_file() got the contents twice, by position and keyword.")
            contents = contents_or_overwrite
        if name is not None:
            if suffix is not None or filename is not None:
                raise TypeError(
                    f"temp_file({name!r}, ...) got a name by position and suffix= or "
                    "filename= too; give one of them."
                )
            if name == "" or name.startswith((".", "_")):
                suffix = name
            else:
                filename = name
        elif filename is not None and suffix is not None:
            raise TypeError("temp_file() takes suffix= or filename=, not both.")
        basename = filename or f"file{suffix or ''}"
        parts = basename.replace("\\", "/").split("/")
        if os.path.isabs(basename) or ".." in parts:
            raise ValueError(
                f"temp_file({basename!r}): give a file name inside the temp folder, "
                "e.g. temp_file('log.txt'), not an absolute path or one with '..'."
            )
        folder = tempfile.mkdtemp(prefix="snr-test-")
        if cleanup:
            self.addCleanup(shutil.rmtree, folder, True)
        path = os.path.join(folder, basename)
        os.makedirs(os.path.dirname(path), exist_ok=True)  # for a name like "logs/run.jsonl"
        if contents is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(contents)
        return TempFile(path, self, cleanup)

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
        assert page is not None
        self.assertEqual(page.key, key, msg)
        self.assertEqual(page.data, data, msg)
        if origin is not None:
            self.assertEqual(page.origin, origin, msg)


def _timed_out_message(node: Node, limit_s: float, alive: Sequence[str]) -> str:
    """Why a test failed when its node was still running at the time limit."""
    parts: List[str] = []
    waiting: List[str] = []
    for name, component in node.components.items():
        if name == NODE_CORE_NAME:
            continue
        kind = type(component).__name__
        if isinstance(component, AbstractLoop):
            kind += ", still running" if name in alive else ", finished"
        parts.append(f"{name} ({kind})")
        if isinstance(component, ExpectorEndpoint):
            problems = component.expector.problems()
            if problems:
                seen = component.expector.seen_instead()
                waiting.append(
                    f"It waited the whole time limit, and the expectations of {name} were "
                    f"still not met: {'; '.join(problems)}.{f' {seen}' if seen else ''}"
                )
            elif not component.exit_when_satisfied:
                waiting.append(
                    f"{name} was satisfied but was made without exit_when_satisfied=True, "
                    "so it did not stop the node."
                )
    held = ", ".join(parts) if parts else "no components besides the node core"
    return " ".join(
        [
            f"The {node.role!r} node was still running when its time limit of {limit_s:g} s "
            "ran out, so the test cannot tell whether its work was done.",
            f"Components: {held}.",
            *waiting,
            "Make the node stop when the work is done: "
            "ExpectorEndpointFactory(expector, exit_when_satisfied=True) stops it once "
            'every expectation is met, and a handler can return tasks.terminate("done"). '
            "If the node needs longer, pass a larger timeout_s=...; if running until the "
            "limit is the point of the test, pass expect_timeout=True.",
        ]
    )
