"""Expectors: say which tasks a test expects, and fail when they don't happen (thesis 5.2.3).

An expector counts the keys it is told about: task ids, from an
`ExpectorEndpoint` in the node under test, or any hashable key. Used as a
context manager, it checks on exit that every expectation was met exactly.
"""

from __future__ import annotations

import threading
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
    TypeVar,
    cast,
)

from snr.core.checks.error_text import closest_key
from snr.prelude import TaskId, TaskType
from snr.prelude.task import format_task

if TYPE_CHECKING:  # unittest and multiprocessing cost ~20 ms to import
    import unittest

__all__ = ["Expector", "MultiProcExpector", "OrderedExpector", "fail"]

# unittest (and pytest) leave out the frames of modules that set this, so a
# failed expectation points at the test's own line, not at SNR's.
__unittest = True

K = TypeVar("K", bound=Hashable)
"""The type of key an expector counts (a task id unless said otherwise)."""


def _format(key: Hashable) -> str:
    """A key as a failure names it: ``(event, 'beep')`` for a task id, else its repr."""
    if isinstance(key, TaskType) or (
        isinstance(key, tuple) and len(key) == 2 and isinstance(key[0], TaskType)
    ):
        return format_task(cast(TaskId, key))
    return repr(key)


def _keys(keys: Sequence[Hashable]) -> str:
    return ", ".join(map(_format, keys))


def _times(n: int) -> str:
    return "once" if n == 1 else f"{n} times"


def _split(key: Hashable) -> Tuple[Hashable, Optional[str]]:
    """A key's type (None for a str key) and name (None when it has none)."""
    if isinstance(key, tuple) and len(key) == 2:
        return key[0], key[1] if isinstance(key[1], str) else None
    return None, key if isinstance(key, str) else None


def fail(testcase: Optional[unittest.TestCase], message: str) -> None:
    """Fail ``testcase`` with ``message`` (an AssertionError without one).

    Example::

        fail(self, "The temp file 'out.txt' does not exist; nothing wrote it.")
    """
    if testcase is not None:
        testcase.fail(message)
    raise AssertionError(message)


class Expector(Generic[K]):
    """Expects each task id (or other key) a given number of times, in any order.

    The key type can be written out, ``Expector[str]({"beep": 2}, self)``;
    it is inferred from the expectations otherwise.

    Keys it does not expect are counted in ``others``, so a failure can say
    what was seen instead.

    Example::

        with Expector({(TaskType.store_page, "out"): 4}) as expector:
            run_node_with(ExpectorEndpointFactory(expector))
        # leaving the block fails unless exactly 4 such tasks were seen

    Attributes:
        counts: how many times each expected key was seen.
        others: how many times each key it does not expect was seen.
    """

    MAX_OTHERS = 100

    def __init__(
        self, expectations: Mapping[K, int], testcase: Optional[unittest.TestCase] = None
    ) -> None:
        self.expectations: Dict[K, int] = dict(expectations)
        self.counts: Dict[K, int] = dict.fromkeys(self.expectations, 0)
        self.others: Dict[K, int] = {}
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
            elif key in self.others or len(self.others) < self.MAX_OTHERS:
                self.others[key] = self.others.get(key, 0) + 1

    def is_satisfied(self) -> bool:
        """True once every expected count has been reached."""
        with self._lock:
            return all(self.counts[k] >= n for k, n in self.expectations.items())

    def problems(self) -> List[str]:
        """One line per expectation not met exactly (empty when all are).

        A key seen too few times names the closest key seen instead, if any.
        """
        with self._lock:
            return [
                f"{_format(k)}: expected {n}, saw {self.counts[k]}"
                + (self._closest_seen(k) if self.counts[k] < n else "")
                for k, n in self.expectations.items()
                if self.counts[k] != n
            ]

    def _closest_seen(self, missing: K) -> str:
        """`` (closest seen instead: ...)``: the same type, a name like it; else the same name."""
        kind, name = _split(missing)
        if name is None:
            return ""
        same_kind = {n: k for k in self.others for t, n in [_split(k)] if t == kind and n}
        guess = closest_key(name, list(same_kind))
        if guess is not None:
            seen: Optional[K] = same_kind[guess]
        else:
            seen = next((k for k in self.others if _split(k)[1] == name), None)
        if seen is None:
            return ""
        return f" (closest seen instead: {_format(seen)}, {_times(self.others[seen])})"

    def seen_instead(self) -> str:
        """The keys seen but not expected, with counts, as one line ("" if none).

        Example::

            expector.seen_instead()
            # "Seen but not expected: (store_page, 'in') 4 times, ..."
        """
        with self._lock:
            others = list(self.others.items())
        if not others:
            return ""
        shown = ", ".join(f"{_format(k)} {_times(n)}" for k, n in others[:20])
        more = f" and {len(others) - 20} more" if len(others) > 20 else ""
        return f"Seen but not expected: {shown}{more}."

    def assert_satisfied(self) -> None:
        """Fail the test unless every expectation was met exactly."""
        problems = self.problems()
        if problems:
            seen = self.seen_instead()
            text = "Expectations not met:\n  " + "\n  ".join(problems)
            fail(self.testcase, text + (f"\n{seen}" if seen else ""))

    def __enter__(self) -> Expector[K]:
        return self

    def __exit__(self, exc_type: Any, *rest: Any) -> None:
        if exc_type is None:
            self.assert_satisfied()


class OrderedExpector(Expector[K]):
    """Expects task ids in an exact order (other, unlisted ids are ignored).

    Example::

        with OrderedExpector([(TaskType.event, "a"), (TaskType.event, "b")]) as e:
            ...
    """

    def __init__(
        self, expectations: Sequence[K], testcase: Optional[unittest.TestCase] = None
    ) -> None:
        super().__init__({key: expectations.count(key) for key in expectations}, testcase)
        self.order: List[K] = list(expectations)
        self.seen: List[K] = []

    def call(self, key: K) -> None:
        super().call(key)
        if key in self.counts:
            with self._lock:
                self.seen.append(key)

    def is_satisfied(self) -> bool:
        with self._lock:
            return self.seen[: len(self.order)] == self.order

    def problems(self) -> List[str]:
        with self._lock:
            order, seen = self.order, self.seen
            if seen == order:
                return []
            for i, (want, got) in enumerate(zip(order, seen)):
                if want != got:
                    return [
                        f"at position {i}: expected {_format(want)}, saw {_format(got)} "
                        f"(expected order: {_keys(order)}; seen order: {_keys(seen)})"
                    ]
            n = len(seen)
            if n < len(order):
                closest = self._closest_seen(order[n])
                return [f"missing at the end: {_keys(order[n:])}{closest}"]
            return [f"unexpected extra at the end: {_keys(seen[len(order) :])}"]


class MultiProcExpector(Expector[K]):
    """An `Expector` whose counts are shared between processes.

    Create it before starting the processes; the counts are in shared memory.

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

            # Shared memory made for spawned children also serves forked ones,
            # not the other way round; MultiProcRunner spawns when the test
            # process runs threads (a forked child could deadlock).
            context = multiprocessing.get_context("spawn")
        self._keys: List[K] = list(self.expectations)
        self._shared: Any = context.Array("l", len(self._keys))

    def call(self, key: K) -> None:
        if key in self.expectations:
            with self._shared.get_lock():
                self._shared[self._keys.index(key)] += 1
        else:
            super().call(key)  # seen only in this process, unlike the counts

    def _sync(self) -> None:
        with self._shared.get_lock():
            self.counts = dict(zip(self._keys, self._shared))

    def is_satisfied(self) -> bool:
        self._sync()
        return super().is_satisfied()

    def problems(self) -> List[str]:
        self._sync()
        return super().problems()

    def __getstate__(self) -> Dict[str, Any]:
        # the lock cannot be pickled; test cases stay in the test process
        return {**self.__dict__, "_lock": None, "testcase": None}

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self.__dict__.update(state, _lock=threading.Lock())
