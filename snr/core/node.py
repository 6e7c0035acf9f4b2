"""`Node`: one running program on one device (thesis 4.2, 6.3.1).

A node owns a task queue, a datastore of pages and its components. The thread
that calls :meth:`Node.loop` alone writes the datastore and runs handlers; loop
threads use the thread-safe ``schedule``, ``store_data`` and ``get_page``.
The node core endpoint (``node_core``) stores pages and manages components
(thesis 4.3.2); ``Config(datastore=..., node_core=...)`` can replace both
(docs/assignments.md). Three helpers do the rest (docs/design.md)::

    Node ──► ComponentSet   build, add, remove, reload, start and stop components;
      │                     keep the HandlerTable in step with them
      ├────► HandlerRunner  run a task's handlers, time them, queue what they
      │                     return; its FailureReport (checks/failures.py) puts
      │                     failures into words
      └────► NodeChecks     wire in the checks for silent mistakes (key hints,
                            wiring checks, watchdog: DEBUG mode)
"""

from __future__ import annotations

import dataclasses
import enum
import logging
import threading
from abc import abstractmethod
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Optional

from snr.core import tasks
from snr.core.checks import life_cycle
from snr.core.checks.explain import check_node_args, check_page_args, wrong_thread_error
from snr.core.clock import clock_of
from snr.core.components import NODE_CORE_NAME, ComponentSet
from snr.core.dispatch import HandlerRunner, HandlerTable
from snr.core.endpoint import Endpoint
from snr.core.factory import EndpointFactory
from snr.core.logs import ensure_log_handler, level_for_mode
from snr.core.task_queue import TaskQueue
from snr.core.timer import Timer
from snr.prelude.abstract import (
    AbstractComponent,
    AbstractConfig,
    AbstractFactory,
    AbstractLoop,
    AbstractNode,
    Datastore,
)
from snr.prelude.names import ComponentName, DataKey, Mode, Role, TaskId, TaskType
from snr.prelude.page import Page
from snr.prelude.task import SomeTasks, Task, TaskHandler, TaskHandlerMap

if TYPE_CHECKING:  # DEBUG helpers, imported when a node turns them on (see __init__)
    from snr.core.checks.key_hints import MissingKeyHints
    from snr.core.checks.node_checks import NodeChecks
    from snr.core.checks.watchdog import Watchdog
    from snr.core.checks.wiring_checks import WiringChecks

__all__ = ["NODE_CORE_NAME", "Node", "NodeCore", "NodeCoreEndpoint", "NodeCoreFactory", "NodeState"]

_PROCESS_DATA = TaskType.process_data
_STORE_PAGE = TaskType.store_page


class NodeState(enum.Enum):
    """Where a node is in its life: CREATED → RUNNING → TERMINATING → TERMINATED.

    Example::

        node.state is NodeState.TERMINATED
    """

    CREATED = "created"
    RUNNING = "running"
    TERMINATING = "terminating"
    TERMINATED = "terminated"


class Node(AbstractNode):
    """Builds its components from the config's factories for ``role`` and runs them.

    Args:
        role: which part of the config this node is, e.g. ``"urov"``.
        config: the system's `Config`.

    Example::

        node = Node("test", Config({"test": [TimeoutLoopFactory(seconds=0.1)]}))
        node.loop()           # returns once the timeout terminates the node
        node.is_terminated()  # True

    Attributes:
        datastore: the newest page for each data key, read-only (get_page reads it).
        pages: the `Datastore` behind it (a dict unless the config names
            another), which only the node writes.
        queue: the task queue (bounded: see `TaskQueue`).
        components: every endpoint and loop by name, in start order.
        state: the `NodeState`.
        terminate_reason: why the node stopped, once it has.
        key_hints: DEBUG: the `MissingKeyHints` (a data key read, never stored).
        wiring_checks: DEBUG: the `snr.core.checks.wiring_checks.WiringChecks`
            (events nothing handles, handlers nothing reaches).
        step_mode: the `snr.core.checks.step_mode.StepMode` a console uses to
            pause and step the node.
        watchdog: DEBUG: the `snr.core.checks.watchdog.Watchdog` that says when
            the node is stuck (set it to None before ``loop()`` to switch it off).
    """

    key_hints: Optional[MissingKeyHints]
    wiring_checks: Optional[WiringChecks]
    watchdog: Optional[Watchdog]
    idle_wake_s: Optional[float] = None
    """How long an idle node sleeps at most (None: until a task comes or it is stopped)."""
    max_queued_tasks: int = 10_000
    """The queue's high-water mark: loops wait (then drop) above it; see `TaskQueue`."""

    def __init__(self, role: Role, config: AbstractConfig) -> None:
        # Read second (snr/core/checks/); here, not on top, to keep `import snr` light:
        from snr.core.checks.failures import FailureReport
        from snr.core.checks.read_only import NodeDatastore
        from snr.core.checks.seam_checks import checked_core, checked_datastore
        from snr.core.checks.step_mode import StepMode

        check_node_args(Node, role, config)
        self.role = role
        self.config = config
        self.mode = config.mode
        ensure_log_handler()
        self.log = logging.getLogger(f"snr.{role}")
        if self.log.level == logging.NOTSET:
            self.log.setLevel(level_for_mode(self.mode))
        self.profiler = config.get_profiler()
        clock = clock_of(config)  # the wall's, or one it takes turns on (a SimClock)
        self.timer = Timer(clock)
        self._page_time: Callable[[], float] = clock.stamp
        self.queue = TaskQueue(high_water=self.max_queued_tasks, log=self.log)
        # Config(datastore=...): dict, or a student's. Written by the node alone;
        # components see it read-only:
        self.pages: Datastore = checked_datastore(config.datastore, self)
        self.datastore: Mapping[DataKey, Page] = NodeDatastore(self.pages, role, self.queue)
        self.state = NodeState.CREATED
        self.terminate_reason: Optional[str] = None
        self._stop_requested = False
        self._components = ComponentSet(self, HandlerTable(self.profiler), join_timeout_s=1.0)
        self.components = self._components.by_name
        self._failures = FailureReport(role, self.mode, self.log, self.set_terminate_flag)
        timed = self.profiler is not None or self.mode is not Mode.DEPLOYED
        self._runner = HandlerRunner(self.queue, self._components, self._failures, timed)
        self.step_mode = StepMode(self.queue, self._runner, self._lookup, self.is_terminated)
        # The checks for silent mistakes (snr/core/checks/, read second): NodeChecks
        # sets key_hints, wiring_checks and watchdog in DEBUG mode, and reads each
        # component's class in DEBUG and TEST. A DEPLOYED node does not load them.
        self.key_hints = self.wiring_checks = self.watchdog = None
        self._checks: Optional[NodeChecks] = None
        if self.mode is not Mode.DEPLOYED:
            from snr.core.checks.node_checks import NodeChecks

            self._checks = NodeChecks(self, self._components, self._runner)
        factory = config.node_core or NodeCoreFactory()
        core: NodeCore = checked_core(self.build_component(factory), factory, self)
        self._core = core
        self.add_component(core, start=False)
        self._runner.store_page = core.store_page_handler  # pages are stored before handlers
        core.pages = self.pages
        if self.mode is not Mode.DEPLOYED:
            from snr.core.checks.read_only import freeze

            core.freeze = freeze
        for factory in config.get(role):
            component = self.build_component(factory)
            if component is not None:
                self.add_component(component, start=False)
        # Built: in line for its first turn, if its clock hands out turns.
        self._clock_turn = clock.node_turn(role, self.queue, self.is_terminated)
        if self._clock_turn is not None:
            self.queue.use_waiter(self._clock_turn)

    @property
    def join_timeout_s(self) -> float:
        """How long stopping waits for each loop's thread (1 s)."""
        return self._components.join_timeout_s

    @join_timeout_s.setter
    def join_timeout_s(self, seconds: float) -> None:
        self._components.join_timeout_s = seconds

    @property
    def slow_handler_s(self) -> float:
        """In DEBUG/TEST mode, handlers slower than this (0.1 s) are reported."""
        return self._runner.slow_handler_s

    @slow_handler_s.setter
    def slow_handler_s(self, seconds: float) -> None:
        self._runner.slow_handler_s = seconds

    # ------------------------------------------------------------------
    # Control flow (thesis listing 6.1)
    # ------------------------------------------------------------------
    def loop(self) -> None:
        """Begin every component, then run tasks until the node terminates.

        Raises:
            NodeStateError: the node already ran.
            HandlerError / LoopError: in DEBUG and TEST mode, after an orderly
                shutdown, when a handler or loop failed.
        """
        if self.state is not NodeState.CREATED:
            raise life_cycle.ran_twice_error(self.role, self.state.value)
        self.state = NodeState.RUNNING
        self.queue.owner_thread = threading.get_ident()
        if self._checks is not None:
            self._checks.start(self.queue.owner_thread)
        try:
            if self._clock_turn is not None:
                self._clock_turn.begin()
            self._components.start_all(lambda: not self._stop_requested)
            self._run_tasks()
        except KeyboardInterrupt:
            self.set_terminate_flag("interrupted by user (Ctrl-C)")
            raise
        except Exception as error:  # e.g. a server that cannot listen
            self.set_terminate_flag(f"{type(error).__name__} (below)")
            raise
        finally:
            try:
                self.terminate()
            finally:
                if self._clock_turn is not None:
                    self._clock_turn.end()
        if self._failures.failure is not None:
            raise self._failures.failure

    def check_wiring(self) -> None:
        """In DEBUG mode, warn about handlers of data keys that look misspelled.

        Runs once by itself a few seconds after the node starts; also about
        handlers that can never run (see
        `snr.core.checks.wiring_checks.WiringChecks.check_never_ran`).
        """
        if self._checks is not None:
            self._checks.check_wiring()

    def set_terminate_flag(self, reason: str) -> None:
        """Ask the node to stop after the current task; safe from any thread."""
        if not self._stop_requested:
            self._stop_requested = True
            self.terminate_reason = reason
        self._runner.running = False
        self.queue.close()

    def is_terminated(self) -> bool:
        """True once the node has been asked to stop (or has stopped)."""
        return self._stop_requested

    def terminate(self) -> None:
        """Halt, join and terminate every component, newest first. Idempotent.

        Only the node's thread may call it while the node runs; other threads
        use ``set_terminate_flag`` or schedule ``tasks.terminate(reason)``.
        """
        if self.state in (NodeState.TERMINATING, NodeState.TERMINATED):
            return
        self._check_owner_thread("terminate")
        if not self._stop_requested:
            self.set_terminate_flag("terminate() called")
        self.state = NodeState.TERMINATING
        if self._checks is not None:  # stopping loops and waiting for them is no mistake
            self._checks.stop()
        self._components.shutdown()
        self._failures.repeats.flush()
        dropped = self.queue.clear()
        if dropped:
            self.log.debug("Dropped %d queued tasks at shutdown", dropped)
        self.state = NodeState.TERMINATED
        self.log.info("Node %r terminated: %s", self.role, self.terminate_reason)

    # ------------------------------------------------------------------
    # Task execution (thesis listing 6.2)
    # ------------------------------------------------------------------
    def _run_tasks(self) -> None:
        queue = self.queue
        run_queued = self._runner.run_queued
        step_mode = self.step_mode
        watchdog = self.watchdog  # DEBUG: it dozes while the node idles
        while not self._stop_requested:
            if step_mode.paused:  # a console paused the node
                step_mode.run_paused(self.idle_wake_s)
                continue
            run_queued()
            if not (self._stop_requested or queue):
                queue.wait(self.idle_wake_s)  # a producer's task or stop wakes it
                if watchdog is not None and watchdog.dozing and queue:
                    watchdog.wake()

    def get_task_handlers(self, task: Task) -> List[tuple[TaskHandler, TaskId]]:
        """Every (handler, matched task id) for ``task``, in component order."""
        return [(entry[0], entry[1]) for entry in self._lookup(task)]

    def is_handled(self, task_type: TaskType, name: str) -> bool:
        """True if some handler would run now for a task with this type and name.

        Example::

            node.is_handled(TaskType.process_data, "depth_m")   # a filter waits for it?
        """
        table = self._table().table
        return (task_type, name) in table or task_type in table

    def _lookup(self, task: Task) -> List[Any]:
        return self._table().lookup(task.type, task.name)

    def _table(self) -> HandlerTable:
        if self._components.table_stale:
            self._components.refresh_table()
        return self._components.table

    def handle_task(self, handler: TaskHandler, task: Task, key: TaskId) -> Optional[List[Task]]:
        """Run one handler with timing and error reporting; its tasks as a list."""
        self._check_owner_thread("handle_task")
        owner = getattr(handler, "__self__", None)
        component = owner if isinstance(owner, AbstractComponent) else None
        cell = None
        if self.profiler is not None:
            cell = self.profiler.task_cell(key, getattr(handler, "__module__", None) or "?")
        return self._runner.run(handler, task, key, component, cell)

    def execute_task(self, t: Task) -> None:
        """Run every handler matching ``t`` now and queue what they return.

        Only the node's own thread may call this; loops use ``schedule``.
        """
        self._check_owner_thread("execute_task")
        self.queue.urgent.appendleft(t)  # first in line: the next task to run
        self._runner.run_queued(max_tasks=1)

    def loop_failed(self, loop: AbstractLoop, error: BaseException) -> None:
        """``loop``'s thread ended with ``error``: a failure, reported as a handler's is.

        In DEBUG and TEST mode the node stops and ``loop()`` raises a
        `LoopError`; DEPLOYED logs it. ``sys.exit()`` or Ctrl-C in a loop stop
        the node in every mode. Called by the loop's thread as it ends.
        """
        self._failures.loop_failed(loop, error)

    # ------------------------------------------------------------------
    # Scheduling (thesis listing 6.3)
    # ------------------------------------------------------------------
    def schedule(self, t: SomeTasks) -> None:
        """Queue a task or a list of tasks; safe from any thread.

        From a loop's thread this waits while the node's queue is full (see
        `TaskQueue`), so a loop cannot run ahead of its node.
        """
        self.queue.schedule(t)

    def schedule_first(self, tasks: List[Task]) -> None:
        """Queue ``tasks`` first in line, in their order; the node's own thread only.

        Example (the node core putting back the pages of a burst it splits)::

            node.schedule_first([node.store_page_task(page) for page in rest])
        """
        self._check_owner_thread("schedule_first")
        self.queue.normal.extendleft(reversed(tasks))

    def wait_for_room(self, timeout_s: float) -> bool:
        """Wait (up to ``timeout_s``) until the queue is below its high-water mark.

        Example (a socket reader that stops reading while the node is behind)::

            while not node.wait_for_room(0.25):
                if closing:
                    return
        """
        return self.queue.wait_for_room(timeout_s)

    def store_page_task(self, page: Page) -> Task:
        """A task that stores ``page`` when it runs (thesis: ``task_store_page``)."""
        return Task(_STORE_PAGE, page.key, [page])

    def store_data_task(self, key: DataKey, data: Any, process: bool = True) -> Task:
        """A task that stores ``data`` under ``key`` when it runs (thesis: ``task_store_data``)."""
        return Task(_STORE_PAGE, key, [self.page(key, data, process)])

    # ------------------------------------------------------------------
    # Datastore (thesis listing 6.4)
    # ------------------------------------------------------------------
    def page(self, key: DataKey, data: Any, process: bool = True) -> Page:
        """A new page from this node, stamped with the node's clock (wall or `SimClock`).

        Raises:
            ComponentError: ``key`` is not a str (key and data swapped?), or
                ``data`` is a whole `Page` (store ``page.data``). DEBUG and
                TEST modes only: DEPLOYED makes pages without these checks.
        """
        if self._checks is not None:
            check_page_args(key, data)
        return Page(key, data, self.role, self._page_time(), process)

    def store_data(self, key: DataKey, data: Any, process: bool = True) -> None:
        """Queue storing ``data`` under ``key``; safe from any thread.

        Example (in a loop)::

            self.parent.store_data("depth_m", 3.2)
        """
        self.queue.put(self.store_data_task(key, data, process))

    def get_page(self, key: DataKey) -> Optional[Page]:
        """The newest page under ``key``, or None; safe from any thread.

        In DEBUG mode, a key that stays missing gets one hint in the log (the
        keys that exist, the closest match); see `MissingKeyHints`.
        """
        page = self.pages.get(key)
        if page is None and self.key_hints is not None and self.state is NodeState.RUNNING:
            self.key_hints.missed(key, self.datastore)
        return page

    def get_data(self, key: DataKey) -> Optional[Any]:
        """The newest data under ``key``, or None; safe from any thread."""
        page = self.get_page(key)
        return None if page is None else page.data

    def get_time_s(self) -> float:
        """Seconds since this node was created (simulated seconds on a `SimClock`)."""
        return self.timer.current_s()

    def write_page(self, page: Page) -> None:
        """Put ``page`` in the datastore now; only from the node's own thread while it runs.

        For a handler that must store a page at once; others queue it (``store_data``).
        """
        self._check_owner_thread("write_page")
        self.pages[page.key] = self._core.frozen(page)

    # ------------------------------------------------------------------
    # Components (the work is done by ComponentSet)
    # ------------------------------------------------------------------
    def build_component(self, factory: AbstractFactory) -> Optional[AbstractComponent]:
        """``factory.get(self)``, with any mistake in ``get()`` explained.

        Raises:
            ComponentError: ``get()`` raised or returned something that is not
                a component.
        """
        return self._components.build(factory)

    def add_component(self, component: AbstractComponent, start: bool = True) -> None:
        """Add a component; it begins at once if the node is running.

        Raises:
            ComponentError: the component is broken (e.g. missed super().__init__).
            ConfigError: another component already has its name.
        """
        self._check_owner_thread("add_component")
        self._components.add(component, start)

    def remove_component(self, name: ComponentName) -> None:
        """Halt, join, terminate and forget the component called ``name``."""
        self._check_owner_thread("remove_component")
        self._components.remove(name)

    def reload_component(self, name: ComponentName = "all") -> List[ComponentName]:
        """Reload the source of one component (or ``"all"``) and rebuild it.

        A reload that fails leaves the old component running and logs why.
        Returns the names of the rebuilt components.
        """
        self._check_owner_thread("reload_component")
        return self._components.reload(name)

    def handlers_changed(self, component: AbstractComponent) -> None:
        """``component`` changed its ``task_handlers``: the table is rebuilt before the next task.

        Raises:
            ComponentError: a burst handler of the component lost its task handler.
        """
        self._components.handlers_changed(component)

    def _check_owner_thread(self, method: str) -> None:
        if self.state is NodeState.RUNNING and threading.get_ident() != self.queue.owner_thread:
            raise wrong_thread_error(self.role, method)

    def __repr__(self) -> str:
        return f"<Node {self.role!r} {self.state.value}, {len(self.components)} components>"


class NodeCore(Endpoint):
    """What a node needs of its core endpoint: the interface of `Config(node_core=...)`.

    SNR's own is `NodeCoreEndpoint`; one of your own (the course's
    docs/assignments.md, lesson 6) extends this class, and must:

    * store pages: `store_page_handler`, which the node calls for each
      ``store_page`` task before that task's handlers;
    * handle ``tasks.store_pages(pages)``, a burst of pages (from another node,
      over comms) to store in order, each as its own ``store_page`` task would;
    * handle ``terminate`` (stop the node: ``parent.set_terminate_flag``),
      ``reload`` (``parent.reload_component``) and the ``ADD_COMPONENT`` and
      ``REMOVE_COMPONENT`` events (``parent.build_component``,
      ``parent.add_component``, ``parent.remove_component``).

    This class names itself ``node_core`` and handles SNR's own two events
    (``CAUGHT_UP``, ``CHECK_WIRING``); add your handlers to ``task_handlers``.

    Example::

        class MyNodeCore(NodeCore):
            def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent)
                self.task_handlers.update({TaskType.terminate: self.stop, ...})

            def store_page_handler(self, task: Task, key: TaskId) -> SomeTasks:
                page = task.val_list[0]
                self.pages[page.key] = page
                ...

        Config({"robot": [...]}, node_core=MyNodeCoreFactory())
    """

    pages: Datastore
    """The node's datastore (``node.pages``), set by the node: the core alone writes it."""
    freeze: Optional[Callable[[Any, DataKey], Any]] = None
    """DEBUG and TEST: makes a page's data read-only as it is stored (None: DEPLOYED)."""

    def __init__(self, factory: AbstractFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, NODE_CORE_NAME)
        self.task_handlers = {
            (TaskType.event, tasks.CAUGHT_UP): self.caught_up_handler,
            (TaskType.event, tasks.CHECK_WIRING): self.check_wiring_handler,
        }

    @abstractmethod
    def store_page_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Put the task's page in ``pages``; then return its ``process_data`` task, if asked.

        The run loop calls it for every ``store_page`` task before the task's
        handlers. Returns ``Task(TaskType.process_data, page.key, [page])``
        when ``page.process`` is true and some handler waits for it, else None.

        Example::

            core.store_page_handler(tasks.store_page(page), (TaskType.store_page, "depth"))
        """

    def frozen(self, page: Page) -> Page:
        """``page``, its data made read-only first in DEBUG and TEST modes (``freeze``)."""
        if self.freeze is not None:
            page.data = self.freeze(page.data, page.key)
        return page

    def caught_up_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Everything scheduled before this task was handled: set the event it carries."""
        for value in task.val_list:
            if isinstance(value, threading.Event):
                value.set()
        return None

    def check_wiring_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Look for wiring mistakes: the node's own check, or the checks it carries.

        Comms send it with a link's check (a function) in ``val_list``, to run
        on the node's thread; without one, the node checks its handlers' keys.
        """
        checks = [value for value in task.val_list if callable(value)]
        if not checks:
            self.parent.check_wiring()
        for check in checks:
            check()
        return None


class NodeCoreEndpoint(NodeCore):
    """SNR's own node core: stores pages and manages components for its node.

    Example (what it does for you)::

        node.schedule(tasks.store_data("depth", 3.0))   # → datastore["depth"]
        node.schedule(tasks.terminate("done"))          # → node stops
    """

    def __init__(self, factory: AbstractFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent)  # pages: set by the node once it is built
        handlers: TaskHandlerMap = {
            (TaskType.event, tasks.STORE_PAGES): self.store_pages_handler,
            (TaskType.event, tasks.ADD_COMPONENT): self.add_component_handler,
            (TaskType.event, tasks.REMOVE_COMPONENT): self.remove_component_handler,
            TaskType.reload: self.reload_handler,
            TaskType.terminate: self.terminate_handler,
        }
        self.task_handlers.update(handlers)

    def store_page_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Put the task's page in the datastore; then process_data if asked (see `NodeCore`)."""
        page = task.page()
        if page is None:
            self.err(life_cycle.NOT_A_PAGE, task.name, task.val_list)
            return None
        if not page.origin:  # made by tasks.store_data(), which has no node
            page = task.val_list[0] = dataclasses.replace(page, origin=self.parent.role)
        if self.freeze is not None:  # DEBUG, TEST (DEPLOYED pays only this test)
            page.data = self.freeze(page.data, page.key)
        self.pages[page.key] = page
        # Its process_data task only if some handler waits for it.
        if page.process and self.parent.is_handled(_PROCESS_DATA, page.key):
            return Task(_PROCESS_DATA, page.key, [page])
        return None

    def store_pages_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Store a burst of pages (`tasks.store_pages`) in order, in one handler call.

        As one ``store_page`` task a page would. From the first page whose key
        other handlers store too, the rest go back first in line, a task each.
        """
        node, pages, freeze = self.parent, self.pages, self.freeze
        processed: List[Task] = []
        wanted: Dict[DataKey, bool] = {}  # per key, asked once a burst: is it processed?
        burst = task.val_list
        for index, page in enumerate(burst):
            # Page by page from here when the usual handler must explain or fix
            # the page, or when a handler besides this core stores its key.
            if not (isinstance(page, Page) and page.origin) or (
                page.key not in wanted and node.is_handled(_STORE_PAGE, page.key)
            ):
                # One store_page task each, first in line, in order.
                rest = [Task(_STORE_PAGE, str(getattr(p, "key", "")), [p]) for p in burst[index:]]
                node.schedule_first(rest)
                break
            if freeze is not None:
                page.data = freeze(page.data, page.key)
            pages[page.key] = page
            if page.key not in wanted:
                wanted[page.key] = node.is_handled(_PROCESS_DATA, page.key)
            if page.process and wanted[page.key]:
                processed.append(Task(_PROCESS_DATA, page.key, [page]))
        return processed

    def add_component_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Build a component with the factory in the task and add it."""
        factory = task.val_list[0] if task.val_list else None
        if not isinstance(factory, AbstractFactory):
            self.err("add_component needs a factory, got %r", factory)
            return None
        component = self.parent.build_component(factory)
        if component is not None:
            self.parent.add_component(component)
        return None

    def remove_component_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Remove the component named in the task."""
        for name in task.val_list:
            self.parent.remove_component(str(name))
        return None

    def reload_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Reload the component named by the task (or ``"all"``)."""
        self.parent.reload_component(task.name or "all")
        return None

    def terminate_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Stop the node once this task has been handled by everyone."""
        self.parent.set_terminate_flag(task.name)
        return None


class NodeCoreFactory(EndpointFactory):
    """Builds the node core endpoint (every node makes one itself)."""

    def get(self, parent: AbstractNode) -> NodeCoreEndpoint:
        return NodeCoreEndpoint(self, parent)
