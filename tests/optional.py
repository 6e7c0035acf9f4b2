"""Test tools from the dev extra: without them, the tests that need them skip.

``pip install -e .`` installs SNR alone, and ``python -m unittest`` must still
pass then (e.g. on a Raspberry Pi). ``pip install -e '.[dev]'`` adds pytest,
hypothesis and pdoc; a test that needs one says so and skips when it is missing::

    from tests.optional import given, needs, settings, st

    @needs("pdoc")
    class TestDocsBuild(unittest.TestCase): ...

    @settings(max_examples=50)
    @given(st.binary())  # without hypothesis: skipped, with the reason
    def test_any_bytes(self, raw: bytes) -> None: ...

Module-level strategies (``st.lists(...) | st.none()``) still build without
hypothesis: they become a stand-in that nothing ever draws from.
"""

from __future__ import annotations

import importlib.util
import unittest
from typing import Any, Callable, Dict, Iterator, TypeVar

from snr.prelude.install import install_hint

__all__ = [
    "EXTRA_FOR",
    "HAVE_HYPOTHESIS",
    "HealthCheck",
    "example",
    "given",
    "needs",
    "pytest_marks_only",
    "reason",
    "settings",
    "st",
]

T = TypeVar("T")
Decorated = TypeVar("Decorated", bound=Callable[..., Any])  # a test function or class


EXTRA_FOR: Dict[str, str] = {
    "matplotlib": "plot",
    "mcap": "mcap",
    "orjson": "fast",
    "pdoc": "docs",
    "pygame": "controller",
    "serial": "serial",
    "websockets": "view",
    "zenoh": "zenoh",
}
"""The extra that installs each optional module the tests import; any other is in ``dev``."""


def reason(module: str) -> str:
    """Why a test skips, with the line that installs ``module`` (SNR's messages use it too).

    Example::

        reason("zenoh")       # "needs zenoh: pip install 'snr-robotics[zenoh]'"
        reason("hypothesis")  # "needs hypothesis: pip install 'snr-robotics[dev]'"
    """
    return f"needs {module}: {install_hint(EXTRA_FOR.get(module, 'dev'))}"


def needs(module: str) -> Callable[[Decorated], Decorated]:
    """Skips a test or test class (with the reason) when ``module`` is not installed.

    Example::

        @needs("pdoc")
        def test_the_guide_renders(self) -> None: ...
    """
    installed = importlib.util.find_spec(module) is not None
    return unittest.skipUnless(installed, reason(module))


HAVE_HYPOTHESIS = importlib.util.find_spec("hypothesis") is not None
"""True when hypothesis is installed (the property tests run)."""

if HAVE_HYPOTHESIS:
    from hypothesis import HealthCheck, example, given, settings
    from hypothesis import strategies as st
else:

    class _NoStrategy:
        """Stands in for hypothesis' ``strategies`` and any strategy built from them.

        Every call, attribute and ``|`` gives the stand-in back, so module-level
        strategy definitions still run; the tests that would draw from them skip.
        """

        def __getattr__(self, name: str) -> _NoStrategy:
            return self

        def __call__(self, *args: Any, **kwargs: Any) -> _NoStrategy:
            return self

        def __or__(self, other: Any) -> _NoStrategy:
            return self

        __ror__ = __or__

        def __iter__(self) -> Iterator[Any]:
            return iter(())  # list(HealthCheck) is empty

    # hypothesis' names are a module, an enum and classes; the stand-ins are not.
    st = _NoStrategy()  # type: ignore[assignment]
    HealthCheck = _NoStrategy()  # type: ignore[assignment, misc]

    def given(  # type: ignore[no-redef]
        *args: Any, **kwargs: Any
    ) -> Callable[[Decorated], Decorated]:
        """Skips the test: without hypothesis there is nothing to draw examples from."""
        return unittest.skip(reason("hypothesis"))

    def settings(*args: Any, **kwargs: Any) -> Callable[[T], T]:  # type: ignore[no-redef]
        """Leaves the test as it is (its settings only matter to hypothesis)."""
        return lambda test: test

    # Explicit examples are drawn by hypothesis too.
    example = settings  # type: ignore[assignment, misc]


class _MarkMaker:
    def __getattr__(self, name: str) -> Callable[..., Callable[[T], T]]:
        return lambda *args, **kwargs: lambda test: test


class _PytestMarksOnly:
    """Stands in for ``pytest`` where a test only uses marks (as 2021 tests did).

    ``pytest.mark.timeout(0.2)`` leaves the test unchanged: only pytest reads
    marks, so ``python -m unittest`` runs the test the same with or without it::

        try:
            import pytest
        except ImportError:  # a plain install
            from tests.optional import pytest_marks_only as pytest
    """

    mark = _MarkMaker()


pytest_marks_only = _PytestMarksOnly()
