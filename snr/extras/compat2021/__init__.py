"""Names kept for code written against the 2021 release of SNR.

Students' and teachers' code from the original course used names that the
thesis text does not print. ``from snr import *`` still gives them, so that
code runs here. Each name below is a thin alias of today's API, or, for
the 2021 internals the thesis replaced, a placeholder that fails with an
error naming the replacement as soon as it is used. New code should use
today's names (``docs/deviations.md``, "Code written for the 2021 release").

Kept, on top of today's classes:

* ``ExpectorProtocol``: the type of an expector (``Expector``,
  ``MultiProcExpector``, ...), for an endpoint that takes one.
* ``MPExpector``: ``MultiProcExpector``, an expector child processes count into.
* ``TaskExpector`` and ``TaskExpectations``: an ``Expector`` of task ids, and
  its mapping from task id to count.
* ``MovingAvgEndpointFactory(input_key, output_key, window)``:
  ``MovingAvgFilterFactory(input, output, length)``.
* ``TestRunner(config)``: a `SynchronousRunner` of the role ``"test"`` that
  stops its node after a time limit (today's ``snr.core.TestRunner``).
* ``TextReader`` and ``PageReader`` (``TextReader(parent, name, filename)``
  with ``open()``, ``read()``, ``close()``) and
  ``TextReplayerFactory(input_filename, output_data_name, exit)``, on top of
  today's readers (`snr.extras.compat2021.readers`).
* ``RemoteConsole(server_tuple, commands)`` and ``LocalConsole(port, commands)``,
  console programs with ``run()`` (`snr.extras.compat2021.consoles`).

Today's own classes, under the names the 2021 release exported them by:
``AbstractComponent``, ``AbstractLoop``, ``AbstractMultiRunner`` and
``AbstractProfiler`` (the real base classes of today's components, runners
and profiler), ``TaskHandlerMap``, ``MovingAvgFilter`` and ``OrderedExpector``.

Elsewhere, in the classes themselves: ``Expector[str](...)`` (expectors are
generic), ``SNRTestCase.temp_file(filename, overwrite, cleanup)`` (it returns a
``snr.utils.TempFile``) and ``TimeoutLoopFactory()`` with no time.

Refused, with an error that names the replacement (`RemovedApiError`):
``Settings``, ``Context``, ``AbstractContext``, ``SocketsLoopFactory``,
``SocketsListenerFactory``, ``SocketsWrapper`` and ``Consumer``.

Example::

    from snr import *

    class TestFilter(SNRTestCase):
        def test_filter(self) -> None:
            with Expector[TaskId]({(TaskType.store_page, "out"): 2}, self) as expector:
                self.run_test_node([
                    ListReplayerFactory([1, 3], "in"),
                    MovingAvgEndpointFactory("in", "out", 2),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ])
"""

from __future__ import annotations

from types import TracebackType
from typing import (
    TYPE_CHECKING,
    Any,
    Mapping,
    NoReturn,
    Optional,
    Protocol,
    Type,
    Union,
    runtime_checkable,
)

from snr.core import Config, MovingAvgFilter, SynchronousRunner
from snr.core import TestRunner as _TimedTestRunner
from snr.extras.compat2021.consoles import LocalConsole, RemoteConsole
from snr.extras.compat2021.readers import PageReader, TextReader, TextReplayerFactory
from snr.prelude import (
    AbstractComponent,
    AbstractConfig,
    AbstractLoop,
    AbstractMultiRunner,
    AbstractProfiler,
    ComponentsByRole,
    DataKey,
    TaskHandlerMap,
    TaskId,
)
from snr.prelude.errors import RemovedApiError
from snr.std_mods.filters.moving_average import DEFAULT_FILTER_LENGTH, MovingAvgFilterFactory
from snr.utils.expector import Expector, MultiProcExpector, OrderedExpector

if TYPE_CHECKING:
    import unittest

__all__ = [
    "AbstractComponent",
    "AbstractContext",
    "AbstractLoop",
    "AbstractMultiRunner",
    "AbstractProfiler",
    "Consumer",
    "Context",
    "ExpectorProtocol",
    "LocalConsole",
    "MovingAvgEndpointFactory",
    "MovingAvgFilter",
    "MPExpector",
    "OrderedExpector",
    "PageReader",
    "RemoteConsole",
    "RemovedApiError",
    "Settings",
    "SocketsListenerFactory",
    "SocketsLoopFactory",
    "SocketsWrapper",
    "TaskExpectations",
    "TaskExpector",
    "TaskHandlerMap",
    "TestRunner",
    "TextReader",
    "TextReplayerFactory",
]


# -- kept ---------------------------------------------------------------------
@runtime_checkable
class ExpectorProtocol(Protocol):
    """What an expector does: count keys, and check the counts.

    The 2021 release's type for "an expector", as students' endpoints take
    one; every SNR expector (`Expector`, ``OrderedExpector``,
    `MultiProcExpector`) is one.

    Example::

        class BeepEndpoint(Endpoint):
            def __init__(self, factory, parent, expector: Optional[ExpectorProtocol]) -> None:
                super().__init__(factory, parent, "beep")
                self.expector = expector

            def on_beep(self, task: Task, key: TaskId) -> SomeTasks:
                if self.expector:
                    self.expector.call("beep")
                return None
    """

    def call(self, key: Any) -> None:
        """Count one occurrence of ``key``."""

    def is_satisfied(self) -> bool:
        """True once every expected count has been reached."""

    def assert_satisfied(self) -> None:
        """Fail the test unless every expectation was met exactly."""

    def __enter__(self) -> Any: ...

    def __exit__(
        self,
        exc_type: Optional[Type[BaseException]],
        exc: Optional[BaseException],
        tb: Optional[TracebackType],
    ) -> None: ...


MPExpector = MultiProcExpector
"""The 2021 name of `MultiProcExpector`: ``MPExpector[str]({"ping": 3}, self)``."""

TaskExpectations = Mapping[TaskId, int]
"""How many times each task id is expected: ``{(TaskType.event, "go"): 2}``."""


class TaskExpector(Expector[TaskId]):
    """An `Expector` of task ids, as the 2021 release named it.

    Example::

        with TaskExpector({(TaskType.store_page, "out"): 4}, self) as expector:
            self.run_test_node([..., ExpectorEndpointFactory(expector, True)])
    """

    def __init__(
        self,
        expectations: TaskExpectations,
        testcase: Optional[unittest.TestCase] = None,
    ) -> None:
        super().__init__(expectations, testcase)


class MovingAvgEndpointFactory(MovingAvgFilterFactory):
    """The 2021 release's name and arguments for `MovingAvgFilterFactory`.

    Args:
        input_key: the data key to read numbers from.
        output_key: the data key to store the average under.
        window: how many samples to average.
        name: the endpoint's name (default ``"moving_avg_filter"``).

    Example::

        MovingAvgEndpointFactory("depth_raw", "depth", window=5)
        # the same as MovingAvgFilterFactory("depth_raw", "depth", 5)
    """

    def __init__(
        self,
        input_key: DataKey,
        output_key: DataKey,
        window: int = DEFAULT_FILTER_LENGTH,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(input_key, output_key, window, name)


class TestRunner(_TimedTestRunner, SynchronousRunner):
    """The 2021 release's runner for tests: a `SynchronousRunner` of the role ``"test"``.

    ``TestRunner(config).run()`` builds the node of the role ``"test"`` and
    runs it in the calling thread until it stops, as the 2021
    ``SNRTestCase.run_test_node`` did; an error in the node reaches the
    caller. It is today's ``snr.core.TestRunner`` too, so the node is
    stopped after ``timeout_s`` (``timed_out`` then says so) instead of
    hanging a test run. Pytest does not collect it (``__test__ = False``).

    Args:
        config: a `Config` with the role ``"test"`` (or its dict of factories).
        timeout_s: the time limit in seconds.

    Example::

        config = Config({"test": [ListReplayerFactory([1], "n"), TimeoutLoopFactory(ms=50)]})
        runner = TestRunner(config)
        runner.run()
        runner.node.get_data("n")   # 1
    """

    __test__ = False

    def __init__(
        self, config: Union[AbstractConfig, ComponentsByRole], timeout_s: float = 10.0
    ) -> None:
        given: object = config  # typed, but old code may pass anything
        if isinstance(given, dict):
            given = Config(given)
        if not isinstance(given, AbstractConfig):
            today = " (today's snr.core.TestRunner takes the role first)"
            raise TypeError(
                f"TestRunner({config!r}): give the Config of the role 'test', e.g. "
                f'TestRunner(Config({{"test": [...]}})){today if isinstance(given, str) else ""}.'
            )
        super().__init__("test", given, timeout_s)
        # what SynchronousRunner's own __init__ would set; its run() is not used
        self.exit_on_error = False
        self.announce_interrupt = True
        self.on_node = None


# -- refused ------------------------------------------------------------------
class _RemovedMeta(type):
    """Fails on a removed class's attributes (``Settings.NODE_SLEEP_TIME``)."""

    def __getattr__(cls, attribute: str) -> NoReturn:
        if attribute.startswith("_"):  # tools probe for __wrapped__ etc.
            raise AttributeError(attribute)
        raise RemovedApiError(f"{cls.__name__}.{attribute}: {cls._removed_message()}")


class _Removed(metaclass=_RemovedMeta):
    """Base of the placeholders: using one raises `RemovedApiError`."""

    _replacement: str = ""

    def __init_subclass__(cls, replacement: str = "", **kwargs: Any) -> None:
        if not replacement:  # a student's subclass of a placeholder
            base = cls.__mro__[1]
            message = base._removed_message() if issubclass(base, _Removed) else ""
            raise RemovedApiError(f"class {cls.__name__}({base.__name__}): {message}")
        super().__init_subclass__(**kwargs)
        cls._replacement = replacement

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        raise RemovedApiError(f"{type(self).__name__}(...): {type(self)._removed_message()}")

    @classmethod
    def _removed_message(cls) -> str:
        return (
            f"{cls.__name__} (from the 2021 release of SNR) {cls._replacement} See "
            "docs/deviations.md, 'Code written for the 2021 release'."
        )


class Settings(
    _Removed,
    replacement=(
        "was a class of constants (debug channels, sleep times, sockets and serial "
        "timeouts, robot hardware), which does not map onto Config. The mode and "
        "profiling are Config(factories, mode=Mode.DEBUG, profile=True); a time, rate, "
        "port or baud rate is an argument of the component that uses it, e.g. "
        "SocketsPair(('localhost', 9000), dead_after_s=2) or a loop's max_tick_rate_hz."
    ),
):
    """Removed: the 2021 class of constants. Using it raises `RemovedApiError`.

    Example::

        Config({"robot": [...]}, mode=Mode.DEBUG, profile=True)  # instead of Settings
    """


class AbstractContext(
    _Removed,
    replacement=(
        "was replaced by the component itself: what a context carried (name, settings, "
        "profiler, logger) a component has as self.name, self.parent (the node), "
        "self.log, self.dbg(...) and self.parent.profiler. Where a context was passed, "
        "pass the node (an AbstractNode)."
    ),
):
    """Removed: components get their node, not a context. Raises `RemovedApiError`.

    Example::

        class MyEndpoint(Endpoint):
            def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "my_endpoint")  # no Context
    """


class Context(
    _Removed,
    replacement=(
        "was replaced by the component itself: what a context carried (name, settings, "
        "profiler, logger) a component has as self.name, self.parent (the node), "
        "self.log, self.dbg(...) and self.parent.profiler. Where a Context was made, "
        "make nothing; where one was passed, pass the node (an AbstractNode)."
    ),
):
    """Removed: components get their node, not a context. Raises `RemovedApiError`.

    Example::

        self.dbg("got %s", value)   # instead of a Context's logging
    """


class SocketsLoopFactory(
    _Removed,
    replacement=(
        "was replaced by SocketsPair(server_tuple).client(keys): "
        "make one SocketsPair(('host', port)) for the connection and give its client() "
        "to one role and its server() to the other."
    ),
):
    """Removed: use ``SocketsPair(server_tuple).client(keys)``. Raises `RemovedApiError`.

    Example::

        sockets = SocketsPair(("localhost", 9000))
        components = {"topside": [sockets.client(["controls"])], "urov": [sockets.server()]}
    """


class SocketsListenerFactory(
    _Removed,
    replacement=(
        "was replaced by SocketsPair(server_tuple).server(keys): "
        "make one SocketsPair(('host', port)) for the connection and give its server() "
        "to one role and its client() to the other."
    ),
):
    """Removed: use ``SocketsPair(server_tuple).server(keys)``. Raises `RemovedApiError`.

    Example::

        sockets = SocketsPair(("0.0.0.0", 9000))
        components = {"urov": [sockets.server(["telemetry"])]}
    """


class SocketsWrapper(
    _Removed,
    replacement=(
        "was replaced by the loops of SocketsPair(server_tuple).client(keys) and "
        ".server(keys), which connect, frame, send and reconnect for you; the "
        "frames are specified in docs/wire-format.md, and another program can use "
        "snr.std_mods.codec (encode_page, FrameDecoder) to speak them."
    ),
):
    """Removed: SocketsPair's loops frame pages for you. Raises `RemovedApiError`.

    Example::

        SocketsPair(("localhost", 9000)).client(["depth"])   # instead of a SocketsWrapper
    """


class Consumer(
    _Removed,
    replacement=(
        "ran an action on each item put in its queue, on its own thread; it was "
        "replaced by a ThreadLoop: write one (with a LoopFactory) whose loop() takes an "
        "item from a queue.Queue "
        "with a timeout and acts on it, or hand items to the node with "
        "self.store_data(key, item) and act on them in an endpoint's handler."
    ),
):
    """Removed: write a `ThreadLoop`, or store data for an endpoint. Raises `RemovedApiError`.

    Example::

        class Worker(ThreadLoop):
            def loop(self) -> None:
                item = self.items.get(timeout=0.1)   # a queue.Queue
                ...
    """
