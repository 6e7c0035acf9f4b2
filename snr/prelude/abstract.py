"""The interfaces of SNR (thesis 6.2.4-6.2.10) as abstract base classes.

Students subclass ``Endpoint``, ``ThreadLoop`` and their factories instead;
these let SNR's parts depend on interfaces and annotate ``parent: AbstractNode``.

Example::

    class MyEndpoint(Endpoint):
        def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
            super().__init__(factory, parent, "my_endpoint")
"""

from __future__ import annotations

import inspect
import logging
from abc import ABCMeta, abstractmethod
from types import MappingProxyType, ModuleType
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Protocol, Sequence

from snr.prelude.names import ComponentName, DataKey, Mode, Role, StatsCell, TaskId, TaskType
from snr.prelude.page import Page
from snr.prelude.student_code import caller_location
from snr.prelude.task import BurstHandler, SomeTasks, Task, TaskHandler, TaskHandlerMap

__all__ = ["AbstractComponent", "AbstractConfig", "AbstractEndpoint", "AbstractFactory"]
__all__ += ["AbstractLoop", "AbstractMultiRunner", "AbstractNode", "AbstractProfiler"]
__all__ += ["AbstractRunner", "AbstractTaskQueue", "ComponentsByRole", "Datastore"]


class _FriendlyABCMeta(ABCMeta):
    """ABCMeta whose missing-method error names the class, its line and the fix (thesis 7.3)."""

    def __call__(cls, *args: Any, **kwargs: Any) -> Any:
        if cls.__abstractmethods__:
            from snr.prelude.abstract_errors import missing_methods_error  # loaded only now

            raise missing_methods_error(cls, caller_location())
        return super().__call__(*args, **kwargs)

    @property
    def __signature__(cls) -> inspect.Signature:
        """``cls.__init__``'s signature without ``self``, for ``help()`` (not ``__call__``'s).

        Example::

            >>> import inspect, snr
            >>> print(inspect.signature(snr.TimeoutLoopFactory))
            (seconds: 'float' = 0.0, ms: 'float' = 0.0, name: 'Optional[str]' = None) -> None
        """
        # mypy warns about __init__ on an instance; here it is the class: sound.
        init = inspect.signature(cls.__init__)  # type: ignore[misc]
        parameters = list(init.parameters.values())[1:]  # drop self
        return init.replace(parameters=parameters, return_annotation=None)


class _FriendlyABC(metaclass=_FriendlyABCMeta):
    """Base of SNR's interfaces: an ``abc.ABC`` with friendlier errors."""

    __slots__ = ()


class AbstractProfiler(_FriendlyABC):
    """Collects how often and how long each handler and loop ran.

    Example::

        print(node.profiler.dump())
    """

    @abstractmethod
    def task_cell(self, task_id: TaskId, where: str) -> StatsCell:
        """The ``[times_called, total_s]`` cell of a handler for ``task_id`` in ``where``."""

    @abstractmethod
    def loop_cell(self, name: ComponentName) -> StatsCell:
        """The ``[times_called, total_s]`` cell of the loop called ``name``."""

    @abstractmethod
    def dump(self) -> str:
        """The table of thesis listing 5.2, as text."""

    @abstractmethod
    def add_report(self, name: str, report: Callable[[], str]) -> None:
        """Add a section to ``dump()``: ``report()``'s text under ``name`` (replaces one)."""


class AbstractTaskQueue(_FriendlyABC):
    """A thread-safe FIFO of tasks; high-priority tasks jump ahead.

    Example::

        queue.schedule(tasks.event("go"))
        queue.get(timeout_s=0.1)   # Task(TaskType.event, 'go', ...)
    """

    @abstractmethod
    def schedule(self, t: SomeTasks) -> None:
        """Queue a task or a list of tasks (from any thread)."""

    @abstractmethod
    def get(self, timeout_s: Optional[float] = None) -> Optional[Task]:
        """The next task, waiting up to ``timeout_s``; None if there is none."""

    @abstractmethod
    def __len__(self) -> int:
        """How many tasks are waiting."""


class Datastore(Protocol):
    """What a node keeps its pages in: the newest page under each key (thesis 4.2, 6.3.1).

    The four methods of a ``dict`` the node uses (SNR's own *is* a ``dict``);
    a class of yours with them can take its place (docs/assignments.md, lesson 5).

    Example::

        store = dict()                 # SNR's own; or MyDatastore()
        store["depth"] = page          # the node core stores a page
        store.get("depth")             # that page; None for a key never stored
        list(store), len(store)        # ["depth"], 1: the keys, first stored first
        Config({"robot": [...]}, datastore=MyDatastore)
    """

    def __setitem__(self, key: DataKey, page: Page, /) -> None:
        """Keep ``page`` as the newest under ``key`` (``page.key``), in place of the one before."""

    def get(self, key: DataKey, /) -> Optional[Page]:
        """The page stored last under ``key``, or None if none ever was."""

    def __iter__(self) -> Iterator[DataKey]:
        """Every key that has a page, each once, in the order each was first stored."""

    def __len__(self) -> int:
        """How many keys have a page."""


class AbstractNode(_FriendlyABC):
    """The interface components see of their node (thesis 6.2.6).

    Attributes:
        role: this node's role, e.g. ``"urov"``.
        config: the config it was built from.
        mode: DEBUG, TEST or DEPLOYED.
        components: every endpoint and loop, by name, in start order.
        log: the node's logger (``logging.Logger``).
        profiler: the profiler, or None when profiling is off.
        datastore: the newest page for each data key, read-only (only the
            node writes it): read with ``get_page``, store with ``store_data``.

    Example::

        node = Node("robot", config)
        node.loop()                 # runs until a terminate task
    """

    role: Role
    config: AbstractConfig
    mode: Mode
    components: Dict[ComponentName, AbstractComponent]
    log: logging.Logger
    profiler: Optional[AbstractProfiler]
    datastore: Mapping[DataKey, Page]

    @abstractmethod
    def loop(self) -> None:
        """Begin every component, then run tasks until terminated."""

    @abstractmethod
    def set_terminate_flag(self, reason: str) -> None:
        """Ask the node to stop after the current task (any thread)."""

    @abstractmethod
    def terminate(self) -> None:
        """Stop every component and join every thread; safe to call twice."""

    @abstractmethod
    def is_terminated(self) -> bool:
        """True once the node has been asked to stop."""

    @abstractmethod
    def get_task_handlers(self, task: Task) -> List[tuple[TaskHandler, TaskId]]:
        """Every handler that matches ``task``, in component order."""

    def is_handled(self, task_type: TaskType, name: str) -> bool:
        """True if some handler would run now for a task with this type and name.

        Example::

            node.is_handled(TaskType.process_data, "depth_m")   # a filter waits for it?
        """
        return bool(self.get_task_handlers(Task(task_type, name)))

    @abstractmethod
    def handle_task(self, handler: TaskHandler, task: Task, key: TaskId) -> Optional[List[Task]]:
        """Run one handler, with profiling and error reporting."""

    @abstractmethod
    def execute_task(self, t: Task) -> None:
        """Run every matching handler for ``t`` and queue what they return."""

    @abstractmethod
    def build_component(self, factory: AbstractFactory) -> Optional[AbstractComponent]:
        """Ask ``factory`` for a component for this node, explaining a wrong ``get()``."""

    @abstractmethod
    def add_component(self, component: AbstractComponent, start: bool = True) -> None:
        """Add a component (it begins at once if the node runs)."""

    @abstractmethod
    def remove_component(self, name: ComponentName) -> None:
        """Halt, join, terminate and forget the component called ``name``."""

    @abstractmethod
    def reload_component(self, name: ComponentName = "all") -> List[ComponentName]:
        """Reload a component's source (or every one's) and rebuild it."""

    def check_wiring(self) -> None:
        """Look for handlers of data keys that nothing stores but that look misspelled."""

    def wait_for_room(self, timeout_s: float) -> bool:
        """Wait (up to ``timeout_s``) until the node's queue has room; True if it has.

        Example (a socket reader holding back)::

            while not node.wait_for_room(0.25): ...
        """
        return True

    # -- what components tell their node (called by SNR, not by students) --
    def handlers_changed(self, component: AbstractComponent) -> None:
        """``component`` changed its ``task_handlers``: look them up again before the next task.

        Example (what ``Component`` does when a handler is added)::

            self.task_handlers[(TaskType.event, "dive")] = self.dive
            # -> self.parent.handlers_changed(self)
        """

    def loop_failed(self, loop: AbstractLoop, error: BaseException) -> None:
        """``loop``'s thread ended with ``error``; the loop has stopped. Report it.

        Example (the last words of ``ThreadLoop``'s thread)::

            except BaseException as error:
                self.parent.loop_failed(self, error)
        """
        self.log.error("Loop %r stopped: it raised %s: %s", loop.name, type(error).__name__, error)

    def schedule_first(self, tasks: List[Task]) -> None:
        """Queue ``tasks`` first in line, in their order (the node's own thread only).

        Example::

            node.schedule_first([node.store_page_task(page) for page in rest])
        """
        self.schedule(tasks)

    @abstractmethod
    def schedule(self, t: SomeTasks) -> None:
        """Queue tasks (thread-safe)."""

    @abstractmethod
    def store_page_task(self, page: Page) -> Task:
        """A task that stores ``page`` when it runs."""

    @abstractmethod
    def store_data_task(self, key: DataKey, data: Any, process: bool = True) -> Task:
        """A task that stores ``data`` under ``key`` when it runs."""

    def task_store_page(self, page: Page) -> Task:
        """The thesis's name (listing 6.3) for `store_page_task`, kept as an alias."""
        return self.store_page_task(page)

    def task_store_data(self, key: DataKey, data: Any, process: bool = True) -> Task:
        """The thesis's name (listing 6.3) for `store_data_task`, kept as an alias."""
        return self.store_data_task(key, data, process)

    @abstractmethod
    def page(self, key: DataKey, data: Any, process: bool = True) -> Page:
        """A new page stamped with this node's role and the time."""

    @abstractmethod
    def store_data(self, key: DataKey, data: Any, process: bool = True) -> None:
        """Queue storing ``data`` under ``key`` (thread-safe)."""

    @abstractmethod
    def get_page(self, key: DataKey) -> Optional[Page]:
        """The newest page stored under ``key``, or None."""

    @abstractmethod
    def get_data(self, key: DataKey) -> Optional[Any]:
        """The newest data stored under ``key``, or None."""

    @abstractmethod
    def get_time_s(self) -> float:
        """Seconds since this node was created."""

    @abstractmethod
    def write_page(self, page: Page) -> None:
        """Put ``page`` in the datastore now (from the node's own thread only)."""


class AbstractComponent(_FriendlyABC):
    """What endpoints and loops have in common (thesis 6.2.5).

    Example::

        isinstance(my_endpoint, AbstractComponent)   # True
    """

    factory: AbstractFactory
    parent: AbstractNode
    name: ComponentName
    #: Handlers for a run of ``store_page`` tasks under one key, in one call, by
    #: their ``task_handlers`` id (docs/design.md, "Bursts"); students need none.
    burst_handlers: Mapping[TaskId, BurstHandler] = MappingProxyType({})

    @property
    @abstractmethod
    def task_handlers(self) -> TaskHandlerMap:
        """Which handler runs for which task id."""

    @task_handlers.setter
    @abstractmethod
    def task_handlers(self, handlers: TaskHandlerMap) -> None: ...

    @abstractmethod
    def begin(self) -> None:
        """Called once when the node starts running (or the component is added)."""

    @abstractmethod
    def join(self, timeout_s: Optional[float] = None) -> None:
        """Wait (up to ``timeout_s``) for any thread the component runs to end."""

    @abstractmethod
    def halt(self) -> None:
        """The component is about to be removed: save state on the factory."""

    @abstractmethod
    def terminate(self) -> None:
        """The component will not be reloaded: release files, sockets, devices."""

    @abstractmethod
    def store_page(self, page: Page) -> None:
        """Queue storing a page on the parent node."""

    def is_alive(self) -> bool:
        """True while a thread of the component runs (endpoints have none)."""
        return False


class AbstractEndpoint(AbstractComponent):
    """A component whose code runs only in task handlers, on the node's thread.

    Example: subclass ``snr.Endpoint``.
    """


class AbstractLoop(AbstractComponent):
    """A component with its own thread that calls ``loop()`` over and over.

    Example: subclass ``snr.ThreadLoop``.
    """

    @abstractmethod
    def setup(self) -> None:
        """Runs once on the loop's thread before the first ``loop()``."""

    @abstractmethod
    def loop(self) -> None:
        """One pass of the loop's work; called repeatedly on its thread."""

    @abstractmethod
    def set_terminate_flag(self, reason: str = "") -> None:
        """Stop this loop after the current pass."""

    @abstractmethod
    def is_terminated(self) -> bool:
        """True once this loop has been asked to stop."""

    def where_running(self) -> str:
        """The line the loop's thread is running now, e.g. ``sensor.py:12 `read()```.

        Used to say where a loop that will not stop is blocked; "" if unknown.
        """
        return ""

    def start_thread(self) -> None:
        """Called by the node to start the loop: ``begin()``, then its thread (`ThreadLoop`).

        Example (what the node does for each loop as it starts)::

            loop.start_thread()
        """
        self.begin()

    def cancel_stop(self) -> None:
        """Take back a request to stop: the loop carries on (a reload was refused).

        Example (a loop that did not stop in time to be reloaded)::

            loop.set_terminate_flag("reloading")
            loop.join(1.0)
            if loop.is_alive():
                loop.cancel_stop()   # the old version keeps running
        """


class AbstractFactory(_FriendlyABC):
    """Builds a component for a node, and can reload the component's code.

    Example::

        class MyFactory(EndpointFactory):
            def get(self, parent: AbstractNode) -> MyEndpoint:
                return MyEndpoint(self, parent)
    """

    reload_targets: List[ModuleType]

    @abstractmethod
    def get(self, parent: AbstractNode) -> Optional[AbstractComponent]:
        """A new component for ``parent``, or None to add nothing."""

    @abstractmethod
    def reload(self) -> None:
        """Re-read the source of ``reload_targets`` (``importlib.reload``)."""


ComponentsByRole = Dict[Role, Sequence[AbstractFactory]]
"""A whole system: for every role, the factories that build its components."""


class AbstractConfig(_FriendlyABC):
    """The blueprint of a whole system: which factories each role gets.

    Example::

        config.get("urov")   # [SocketsServerFactory(...), ...]
    """

    mode: Mode
    datastore: Callable[[], Datastore] = dict
    """What makes each node's datastore (`Config(datastore=...)`)."""
    node_core: Optional[AbstractFactory] = None
    """The factory of each node's core endpoint; None: SNR's own."""

    @abstractmethod
    def get(self, role: Role) -> List[AbstractFactory]:
        """The factories for ``role``; a clear ConfigError for unknown roles."""

    @abstractmethod
    def get_profiler(self) -> Optional[AbstractProfiler]:
        """A fresh profiler for a node, or None when profiling is off."""

    @abstractmethod
    def roles(self) -> List[Role]:
        """Every role the config knows, in the order written."""


class AbstractRunner(_FriendlyABC):
    """Builds a node from a config and runs it until it stops.

    Example::

        snr.SynchronousRunner("robot", config).run()
    """

    @abstractmethod
    def run(self) -> None:
        """Run until the node terminates or Ctrl-C."""


class AbstractMultiRunner(_FriendlyABC):
    """Runs several nodes (roles) at once, e.g. one process each.

    Example::

        snr.MultiProcRunner(["topside", "urov"], config).run()
    """

    @abstractmethod
    def run(self) -> None:
        """Run every node until all have stopped, or Ctrl-C."""
