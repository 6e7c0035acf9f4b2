"""Expectors: say which tasks a test expects, and fail when they don't happen.

An expector counts the keys it is told about (usually task ids, from an
`ExpectorEndpoint` in the node under test; any hashable key works). Used as a
context manager, it checks on exit that every expectation was met exactly,
however the node stopped (thesis 5.2.3).
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

from snr.core.checks.error_text import closest_match
from snr.prelude import TaskId, TaskName, TaskType
from snr.prelude.task import format_task

if TYPE_CHECKING:  # unittest and multiprocessing cost ~20 ms to import
    import unittest

__all__ = [
    "Expectations",
    "Expector",
    "MultiProcExpector",
    "OrderedExpector",
    "closest_key",
    "fail",
    "format_key",
]

# unittest (and pytest) leave out the frames of modules that set this, so a
# failed expectation points at the test's own line, not at SNR's.
__unittest = True

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

        format_key((TaskType.event, "beep"))   # "(event, 'beep')"
        format_key("beep")                     # "'beep'"
    """
    if isinstance(key, TaskType) or (
        isinstance(key, tuple) and len(key) == 2 and isinstance(key[0], TaskType)
    ):
        return format_task(cast(TaskId, key))
    return repr(key)


def _name_of(key: Hashable) -> Optional[str]:
    """The name part of a key: a task id's name, or the key itself if it is a str."""
    if isinstance(key, str):
        return key
    if isinstance(key, tuple) and len(key) == 2 and isinstance(key[1], str):
        return key[1]
    return None


def _kind_of(key: Hashable) -> Hashable:
    """What must match besides the name: a task id's type (None for a str key)."""
    return key[0] if isinstance(key, tuple) and len(key) == 2 else None


def closest_key(missing: K, seen: Sequence[K]) -> Optional[K]:
    """The key in ``seen`` most like ``missing``, or None: for "did you mean" in failures.

    A key of the same task type with a name spelled almost the same (or the
    same but for capitals) comes first, then the same name under another type.

    Example::

        closest_key((TaskType.store_page, "out"),
                    [(TaskType.store_page, "in"), (TaskType.store_page, "Out")])
        # (TaskType.store_page, 'Out')
    """
    name = _name_of(missing)
    if name is None:
        return None
    same_kind = {_name_of(k): k for k in seen if _kind_of(k) == _kind_of(missing)}
    names = [n for n in same_kind if n is not None]
    same_but_case = [n for n in names if n.lower() == name.lower()]
    guess = same_but_case[0] if same_but_case else closest_match(name, names)
    if guess is not None:
        return same_kind[guess]
    return next((k for k in seen if _name_of(k) == name), None)


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
        self,
        expectations: Mapping[K, int],
        testcase: Optional[unittest.TestCase] = None,
    ) -> None:
        self.expectations: Dict[K, int] = dict(expectations)
        self.counts: Dict[K, int] = {key: 0 for key in self.expectations}
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
                f"{format_key(k)}: expected {n}, saw {self.counts[k]}"
                + (self._closest_seen(k) if self.counts[k] < n else "")
                for k, n in self.expectations.items()
                if self.counts[k] != n
            ]

    def _closest_seen(self, key: K) -> str:
        guess = closest_key(key, list(self.others))
        if guess is None:
            return ""
        return f" (closest seen instead: {format_key(guess)}, {_times(self.others[guess])})"

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
        shown = ", ".join(f"{format_key(k)} {_times(n)}" for k, n in others[:20])
        more = f" and {len(others) - 20} more" if len(others) > 20 else ""
        return f"Seen but not expected: {shown}{more}."

    def assert_satisfied(self) -> None:
        """Fail the test unless every expectation was met exactly."""
        problems = self.problems()
        if problems:
            seen = self.seen_instead()
            fail(
                self.testcase,
                "Expectations not met:\n  " + "\n  ".join(problems) + (f"\n{seen}" if seen else ""),
            )

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


def _keys(keys: Sequence[Hashable]) -> str:
    return ", ".join(map(format_key, keys))


def _times(n: int) -> str:
    return "once" if n == 1 else f"{n} times"


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
        super().call(key)
        if key in self.counts:
            with self._lock:
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
                    return [
                        f"at position {i}: expected {format_key(want)}, saw {format_key(got)} "
                        f"(expected order: {_keys(self.order)}; seen order: {_keys(self.seen)})"
                    ]
            n = len(self.seen)
            if n < len(self.order):
                closest = self._closest_seen(self.order[n])
                return [f"missing at the end: {_keys(self.order[n:])}{closest}"]
            return [f"unexpected extra at the end: {_keys(self.seen[len(self.order) :])}"]


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
            index = self._keys.index(key)
            with self._shared.get_lock():
                self._shared[index] += 1
        else:
            super().call(key)  # seen only in this process, unlike the counts

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
