"""Expectors: say which tasks a test expects, and fail when they don't happen.

An expector counts the task ids it is told about (usually by an
`ExpectorEndpoint` inside the node under test). Used as a context manager, it
checks on exit that every expectation was met exactly, so a test fails with a
precise message however the node stopped (thesis 5.2.3).

Expectors are generic in the type of key they count: usually a task id, but
any hashable key works, e.g. ``Expector[str]({"beep": 2})`` for a test that
counts calls itself.
"""

from __future__ import annotations

import threading
from types import TracebackType
from typing import (
    TYPE_CHECKING,
    Any,
    Dict,
    Generic,
    Hashable,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Type,
    TypeVar,
    Union,
    cast,
)

from snr.core.profiler import format_task_id
from snr.prelude import TaskId, TaskName, TaskType

if TYPE_CHECKING:  # unittest and multiprocessing cost ~20 ms to import
    import unittest

__all__ = ["Expectations", "Expector", "MultiProcExpector", "OrderedExpector", "format_key"]

Expectations = Union[
    Mapping[TaskId, int],
    Mapping[Tuple[TaskType, TaskName], int],
    Mapping[TaskType, int],
]
"""How many times each task id is expected, e.g. ``{(TaskType.event, "go"): 2}``.

A dict whose keys are all ``(type, name)`` pairs (as in thesis listing A.3)
type-checks as well as one that mixes pairs and bare task types."""

K = TypeVar("K", bound=Hashable)
"""The type of key an expector counts (a task id unless said otherwise)."""


def format_key(key: Hashable) -> str:
    """How an expectation's key is named in a failure message.

    Example::

        format_key((TaskType.event, "beep"))   # 'TaskType.event(beep)'
        format_key("beep")                     # "'beep'"
    """
    if isinstance(key, TaskType) or (
        isinstance(key, tuple) and len(key) == 2 and isinstance(key[0], TaskType)
    ):
        return format_task_id(cast(TaskId, key))
    return repr(key)


def _fail(testcase: Optional[unittest.TestCase], message: str) -> None:
    if testcase is not None:
        testcase.fail(message)
    raise AssertionError(message)


class Expector(Generic[K]):
    """Expects each task id (or other key) a given number of times, in any order.

    The key type can be written out, ``Expector[str]({"beep": 2}, self)``;
    it is inferred from the expectations otherwise.

    Example::

        with Expector({(TaskType.store_page, "out"): 4}) as expector:
            run_node_with(ExpectorEndpointFactory(expector))
        # leaving the block fails unless exactly 4 such tasks were seen
    """

    def __init__(
        self,
        expectations: Mapping[K, int],
        testcase: Optional[unittest.TestCase] = None,
    ) -> None:
        self.expectations: Dict[K, int] = {k: n for k, n in expectations.items()}
        self.counts: Dict[K, int] = {key: 0 for key in self.expectations}
        self.testcase = testcase
        self._lock = threading.Lock()

    def task_ids(self) -> List[K]:
        """The task ids (keys) this expector watches."""
        return list(self.expectations)

    def call(self, key: K) -> None:
        """Count one occurrence of ``key`` (thread-safe)."""
        with self._lock:
            if key in self.counts:
                self.counts[key] += 1

    def is_satisfied(self) -> bool:
        """True once every expected count has been reached."""
        with self._lock:
            return all(self.counts[k] >= n for k, n in self.expectations.items())

    def problems(self) -> List[str]:
        """One line per expectation not met exactly (empty when all are)."""
        with self._lock:
            return [
                f"{format_key(k)}: expected {n}, saw {self.counts[k]}"
                for k, n in self.expectations.items()
                if self.counts[k] != n
            ]

    def assert_satisfied(self) -> None:
        """Fail the test unless every expectation was met exactly."""
        problems = self.problems()
        if problems:
            _fail(self.testcase, "Expectations not met:\n  " + "\n  ".join(problems))

    def __enter__(self) -> Expector[K]:
        return self

    def __exit__(
        self,
        exc_type: Optional[Type[BaseException]],
        exc: Optional[BaseException],
        tb: Optional[TracebackType],
    ) -> None:
        if exc_type is None:
            self.assert_satisfied()


class OrderedExpector(Expector[K]):
    """Expects task ids in an exact order (other, unlisted ids are ignored).

    Example::

        with OrderedExpector([(TaskType.event, "a"), (TaskType.event, "b")]) as e:
            ...
    """

    def __init__(
        self,
        expectations: Sequence[K],
        testcase: Optional[unittest.TestCase] = None,
    ) -> None:
        counts: Dict[K, int] = {}
        for key in expectations:
            counts[key] = counts.get(key, 0) + 1
        super().__init__(counts, testcase)
        self.order: List[K] = list(expectations)
        self.seen: List[K] = []

    def call(self, key: K) -> None:
        with self._lock:
            if key in self.counts:
                self.counts[key] += 1
                self.seen.append(key)

    def is_satisfied(self) -> bool:
        with self._lock:
            return self.seen[: len(self.order)] == self.order

    def problems(self) -> List[str]:
        with self._lock:
            if self.seen == self.order:
                return []
            for i, (want, got) in enumerate(zip(self.order, self.seen)):
                if want != got:
                    return [f"at position {i}: expected {format_key(want)}, saw {format_key(got)}"]
            if len(self.seen) < len(self.order):
                missing = ", ".join(format_key(k) for k in self.order[len(self.seen) :])
                return [f"missing at the end: {missing}"]
            extra = ", ".join(format_key(k) for k in self.seen[len(self.order) :])
            return [f"unexpected extra at the end: {extra}"]


class MultiProcExpector(Expector[K]):
    """An `Expector` whose counts are shared between processes.

    Create it before starting the processes (e.g. before `MultiProcRunner`);
    the counts live in shared memory, so the test process sees what the nodes
    in child processes counted.

    Example::

        expector = MultiProcExpector({(TaskType.store_page, "ping"): 3})
        with expector:
            MultiProcRunner(["a", "b"], config).run()
    """

    def __init__(
        self,
        expectations: Mapping[K, int],
        testcase: Optional[unittest.TestCase] = None,
        context: Any = None,
    ) -> None:
        super().__init__(expectations, testcase)
        if context is None:
            import multiprocessing

            context = multiprocessing.get_context()
        ctx = context
        self._keys: List[K] = list(self.expectations)
        self._shared: Any = ctx.Array("l", len(self._keys))

    def call(self, key: K) -> None:
        if key in self.expectations:
            index = self._keys.index(key)
            with self._shared.get_lock():
                self._shared[index] += 1

    def _sync(self) -> None:
        with self._shared.get_lock():
            values = list(self._shared)
        self.counts = dict(zip(self._keys, values))

    def is_satisfied(self) -> bool:
        self._sync()
        return super().is_satisfied()

    def problems(self) -> List[str]:
        self._sync()
        return super().problems()

    def __getstate__(self) -> Dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_lock", None)
        state["testcase"] = None  # test cases stay in the test process
        return state

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()
