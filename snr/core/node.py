"""`Node`: one running program on one device (thesis 4.2, 6.3.1).

A node owns a task queue, a datastore of pages and its components. One thread
(the one that calls :meth:`Node.loop`) owns the node's state: it is the only
thread that writes the datastore or runs task handlers. Loop threads reach the
node through the thread-safe queue (``schedule``, ``store_data``) and the
read-only ``get_page``/``get_data``.
"""

from __future__ import annotations

import enum
import logging
import threading
import time
from typing import Any, Dict, List, Optional, Set

from snr.core.dispatch import HandlerTable
from snr.core.explain import (
    THREAD_SAFE_INSTEAD,
    bad_result_hint,
    describe_bad_result,
    only_returns_none,
    task_label,
    task_values,
)
from snr.core.key_hints import MissingKeyHints
from snr.core.logs import ensure_log_handler, level_for_mode
from snr.core.node_core import NodeCoreFactory
from snr.core.task_queue import TaskQueue
from snr.core.timer import Timer
from snr.prelude import (
    AbstractComponent,
    AbstractConfig,
    AbstractFactory,
    AbstractNode,
    ComponentError,
    ComponentName,
    ConfigError,
    DataDict,
    DataKey,
    HandlerError,
    LoopError,
    Mode,
    NodeStateError,
    Page,
    Role,
    SNRError,
    SomeTasks,
    Task,
    TaskHandler,
    TaskId,
    TaskType,
    ThreadSafetyError,
)
from snr.prelude.abstract import AbstractLoop, explain_abstract_error
from snr.prelude.errors import (
    caller_location,
    describe_callable,
    describe_class,
    short_repr,
    student_frames,
    trim_runtime_frames,
)

__all__ = ["Node", "NodeState"]


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
        datastore: the newest page for each data key (read it with get_page).
        queue: the task queue.
        state: the `NodeState`.
        terminate_reason: why the node stopped, once it has.
        join_timeout_s: how long shutdown waits for each loop's thread.
        slow_handler_s: in DEBUG/TEST mode, handlers slower than this are reported.
        key_hints: in DEBUG mode, the `MissingKeyHints` that log a hint for a
            data key read but never stored (None in other modes).
    """

    join_timeout_s: float = 1.0
    slow_handler_s: float = 0.1
    idle_wake_s: float = 1.0

    def __init__(self, role: Role, config: AbstractConfig) -> None:
        if not isinstance(role, str) or not role:
            raise ConfigError(f"A node's role must be a non-empty string, not {role!r}.")
        if not isinstance(config, AbstractConfig):
            raise ConfigError(
                f"Node({role!r}, ...) needs a snr.Config as its second argument, not "
                f"{type(config).__name__}. Wrap a dict of factories: "
                "Config({'robot': [...]})."
            )
        self.role = role
        self.config = config
        self.mode = config.mode
        ensure_log_handler()
        self.log = logging.getLogger(f"snr.{role}")
        if self.log.level == logging.NOTSET:
            self.log.setLevel(level_for_mode(self.mode))
        self.profiler = config.get_profiler()
        self.timer = Timer()
        self.datastore: DataDict = {}
        self.queue = TaskQueue()
        self.components: Dict[ComponentName, AbstractComponent] = {}
        self.state = NodeState.CREATED
        self.terminate_reason: Optional[str] = None
        self._stop_requested = False
        self._running = False
        self._thread_id: Optional[int] = None
        self._failure: Optional[SNRError] = None
        self._handlers = HandlerTable()
        self._table_stale = False
        self._rebuild_needed = False
        self._pending_adds: List[AbstractComponent] = []
        self._timed = self.profiler is not None or self.mode is not Mode.DEPLOYED
        self._slow_reported: Set[Any] = set()
        self.key_hints: Optional[MissingKeyHints] = (
            MissingKeyHints(self.log, self.timer.current_s) if self.mode is Mode.DEBUG else None
        )

        self.add_component(NodeCoreFactory().get(self), start=False)
        for factory in config.get(role):
            component = self._build(factory)
            if component is None:
                self._got_none(factory)
                continue
            self.add_component(component, start=False)

    def _got_none(self, factory: AbstractFactory) -> None:
        get = type(factory).get
        if only_returns_none(get):
            raise ComponentError(
                f"{describe_callable(get)} returned None: it has no `return` with a "
                f"value, so role {self.role!r} can never get a component from it. Return "
                "what it builds: `return MyEndpoint(self, parent)`."
            )
        self.log.warning(
            "%s returned None this time, so role %r gets no component from it. If you "
            "meant to add one, check the conditions before its `return`.",
            describe_callable(get),
            self.role,
        )

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
            raise NodeStateError(
                f"Cannot run node {self.role!r}: it is {self.state.value}. A node runs "
                "once; build a new Node to run again."
            )
        self.state = NodeState.RUNNING
        self._thread_id = threading.get_ident()
        self._running = not self._stop_requested
        try:
            for component in list(self.components.values()):
                if not self._running:
                    break
                self._start(component)
            self._run_tasks()
        except KeyboardInterrupt:
            self.set_terminate_flag("interrupted by user (Ctrl-C)")
            raise
        finally:
            self.terminate()
        if self._failure is not None:
            raise self._failure

    def set_terminate_flag(self, reason: str) -> None:
        """Ask the node to stop after the current task; safe from any thread."""
        if not self._stop_requested:
            self._stop_requested = True
            self.terminate_reason = reason
        self._running = False
        self.queue.wake()

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
        self._running = False
        self.state = NodeState.TERMINATING
        components = list(self.components.values())[::-1]
        for component in components:
            self._call_safely(component, "halt")
        deadline = time.monotonic() + self.join_timeout_s
        for component in components:
            if hasattr(component, "is_alive"):
                component.join(max(0.0, deadline - time.monotonic()))
                if component.is_alive():
                    self.log.warning(
                        "Loop %r did not stop within %.1f s of shutdown. Its loop() or "
                        "setup() may be blocked (a read with no timeout, time.sleep): "
                        "use timeouts, or self.wait_s(), so it can notice it should stop.",
                        component.name,
                        self.join_timeout_s,
                    )
        for component in components:
            self._call_safely(component, "terminate")
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
        normal, urgent = queue.normal, queue.urgent
        table = self._handlers.table
        while self._running:
            if urgent:
                task = urgent.popleft()
            elif normal:
                task = normal.popleft()
            else:
                queue.wait(self.idle_wake_s)
                continue
            if self._table_stale:
                self._refresh_table()
            entries = table.get((task.type, task.name))
            if entries is None:
                entries = table.get(task.type)
                if entries is None:
                    continue
            if self._timed:
                for handler, key, component in entries:
                    self._schedule_result(self.handle_task_entry(handler, task, key, component))
                continue
            # Fast path (DEPLOYED mode without profiler): the same steps as
            # handle_task_entry with the timing left out.
            for handler, key, component in entries:
                try:
                    result = handler(task, key)
                except Exception as error:
                    self._handler_failed(handler, task, component, error)
                    continue
                if result is None:
                    continue
                if result.__class__ is Task:
                    (urgent if result.priority else normal).append(result)
                else:
                    self._schedule_result(self._check_result(result, handler, task))

    def get_task_handlers(self, task: Task) -> List[tuple[TaskHandler, TaskId]]:
        """Every (handler, matched task id) for ``task``, in component order."""
        if self._table_stale:
            self._refresh_table()
        return [(h, k) for h, k, _ in self._handlers.lookup(task.type, task.name)]

    def handle_task(self, handler: TaskHandler, task: Task, key: TaskId) -> Optional[List[Task]]:
        """Run one handler with timing and error reporting; its tasks as a list."""
        self._check_owner_thread("handle_task")
        owner = getattr(handler, "__self__", None)
        component = owner if isinstance(owner, AbstractComponent) else None
        return self.handle_task_entry(handler, task, key, component)

    def handle_task_entry(
        self,
        handler: TaskHandler,
        task: Task,
        key: TaskId,
        component: Optional[AbstractComponent],
    ) -> Optional[List[Task]]:
        """`handle_task` when the handler's component is already known."""
        started = time.perf_counter()
        try:
            result = handler(task, key)
        except Exception as error:
            self._handler_failed(handler, task, component, error)
            return None
        took = time.perf_counter() - started
        if self.profiler is not None:
            self.profiler.log_task(key, getattr(handler, "__module__", "?") or "?", took)
        if took > self.slow_handler_s and self.mode is not Mode.DEPLOYED:
            self._report_slow(handler, task, took)
        return self._check_result(result, handler, task)

    def execute_task(self, t: Task) -> None:
        """Run every handler matching ``t`` now and queue what they return.

        Only the node's own thread may call this; loops use ``schedule``.
        """
        self._check_owner_thread("execute_task")
        if self._table_stale:
            self._refresh_table()
        for handler, key, component in list(self._handlers.lookup(t.type, t.name)):
            self._schedule_result(self.handle_task_entry(handler, t, key, component))

    def _check_result(self, result: Any, handler: TaskHandler, task: Task) -> Optional[List[Task]]:
        if result is None:
            return None
        if isinstance(result, Task):
            return [result]
        if isinstance(result, list) and all(isinstance(t, Task) for t in result):
            return result
        error = HandlerError(
            f"Task handler {describe_callable(handler)} {describe_bad_result(result)} "
            f"while handling {task_label(task)}. A handler must return a Task, a list of "
            f"Tasks, or None.{bad_result_hint(result)} To store a value, return "
            "self.store_data_task(key, value); to announce something, return "
            "tasks.event('name', [value])."
        )
        self._record_failure(error)
        return None

    def _schedule_result(self, result: Optional[List[Task]]) -> None:
        if result:
            queue = self.queue
            for task in result:
                (queue.urgent if task.priority else queue.normal).append(task)

    def _handler_failed(
        self,
        handler: TaskHandler,
        task: Task,
        component: Optional[AbstractComponent],
        error: Exception,
    ) -> None:
        where = ""
        if component is not None:
            kind = "loop" if isinstance(component, AbstractLoop) else "endpoint"
            where = f" of {kind} {component.name!r}"
        frames = student_frames(error.__traceback__)
        message = (
            f"Task handler {describe_callable(handler)}{where} raised "
            f"{type(error).__name__}: {error}\nwhile handling the task {task_label(task)} "
            f"{task_values(task)}.\n"
            f"Where it happened (most recent call last):\n{frames}"
        )
        if self.mode is Mode.DEPLOYED:
            self.log.error("%s\nThe node keeps running.", message)
            return
        fix = (
            "Fix the handler as the message above says."
            if isinstance(error, SNRError)
            else "Fix the handler, or catch the error in it if it can happen in normal use "
            "(in Mode.DEPLOYED the node logs it and keeps running)."
        )
        failure = HandlerError(f"{message}\n{fix}")
        trim_runtime_frames(error)
        failure.__cause__ = error
        self._record_failure(failure)

    def _record_failure(self, error: SNRError) -> None:
        if self.mode is Mode.DEPLOYED:
            self.log.error("%s The node keeps running.", error)
            return
        if self._failure is None:
            # loop() raises this error once the node has stopped, so the log
            # gets one line now (shutdown can take a moment), not a duplicate.
            self._failure = error
            first_sentence = str(error).split("\n", 1)[0].split(". ", 1)[0].rstrip(".")
            self.log.error("Stopping node %r: %s.", self.role, first_sentence)
        else:
            self.log.error("%s", error)
        self.set_terminate_flag(f"stopped by a {type(error).__name__}")

    def _loop_failed(self, loop: AbstractComponent, error: Exception) -> None:
        frames = student_frames(error.__traceback__)
        message = (
            f"Loop {loop.name!r} ({describe_class(type(loop))}) stopped: it raised "
            f"{type(error).__name__}: {error}\nWhere it happened (most recent call last):"
            f"\n{frames}"
        )
        if self.mode is Mode.DEPLOYED:
            self.log.error("%s\nThe node keeps running without this loop.", message)
            return
        fix = (
            "Fix the loop as the message above says."
            if isinstance(error, SNRError)
            else "Fix loop() (or setup()), or catch the error there if it can happen in "
            "normal use (in Mode.DEPLOYED the node keeps running without the loop)."
        )
        failure = LoopError(f"{message}\n{fix}")
        trim_runtime_frames(error)
        failure.__cause__ = error
        self._record_failure(failure)

    def _report_slow(self, handler: TaskHandler, task: Task, took_s: float) -> None:
        func = getattr(handler, "__func__", handler)
        if func in self._slow_reported:
            return
        self._slow_reported.add(func)
        self.log.warning(
            "Task handler %s took %.3f s handling %s. While it runs the node can run "
            "no other task. Move slow or blocking work (time.sleep, waiting for a "
            "device) into a ThreadLoop, and let the handler only read and store data.",
            describe_callable(handler),
            took_s,
            task_label(task),
        )

    # ------------------------------------------------------------------
    # Scheduling (thesis listing 6.3)
    # ------------------------------------------------------------------
    def schedule(self, t: SomeTasks) -> None:
        """Queue a task or a list of tasks; safe from any thread."""
        self.queue.schedule(t)

    def task_store_page(self, page: Page) -> Task:
        """A task that stores ``page`` when it runs."""
        return Task(TaskType.store_page, page.key, [page])

    def task_store_data(self, key: DataKey, data: Any, process: bool = True) -> Task:
        """A task that stores ``data`` under ``key`` when it runs."""
        return self.task_store_page(self.page(key, data, process))

    # ------------------------------------------------------------------
    # Datastore (thesis listing 6.4)
    # ------------------------------------------------------------------
    def page(self, key: DataKey, data: Any, process: bool = True) -> Page:
        """A new page from this node, stamped with the wall-clock time."""
        return Page(key, data, self.role, time.time(), process)

    def store_data(self, key: DataKey, data: Any, process: bool = True) -> None:
        """Queue storing ``data`` under ``key``; safe from any thread."""
        self.queue.schedule(self.task_store_data(key, data, process))

    def get_page(self, key: DataKey) -> Optional[Page]:
        """The newest page under ``key``, or None; safe from any thread.

        In DEBUG mode, a key that stays missing gets one hint in the log (the
        keys that exist, the closest match); see `MissingKeyHints`.
        """
        page = self.datastore.get(key)
        if page is None and self.key_hints is not None and self.state is NodeState.RUNNING:
            self.key_hints.missed(key, self.datastore)
        return page

    def get_data(self, key: DataKey) -> Optional[Any]:
        """The newest data under ``key``, or None; safe from any thread."""
        page = self.datastore.get(key)
        if page is None:
            if self.key_hints is not None and self.state is NodeState.RUNNING:
                self.key_hints.missed(key, self.datastore)
            return None
        return page.data

    def get_time_s(self) -> float:
        """Seconds since this node was created."""
        return self.timer.current_s()

    def write_page(self, page: Page) -> None:
        """Put ``page`` in the datastore (the node core's store_page handler)."""
        self._check_owner_thread("write_page")
        self.datastore[page.key] = page

    # ------------------------------------------------------------------
    # Components
    # ------------------------------------------------------------------
    def _build(self, factory: AbstractFactory) -> Optional[AbstractComponent]:
        if not hasattr(factory, "reload_targets"):
            raise ComponentError(
                f"{describe_class(type(factory))} did not call super().__init__() in its "
                "__init__. Add "
                "`super().__init__()` (or `super().__init__(my_module)` to hot-reload "
                "my_module) as its first line."
            )
        component: Any  # get() is typed, but a student's get() may return anything
        try:
            component = factory.get(self)
        except SNRError:
            raise
        except TypeError as error:
            explained = explain_abstract_error(error)
            if explained is not None:
                raise explained from None  # Python's "abstract class" text only confuses
            raise self._get_failed(factory, error) from error
        except Exception as error:
            raise self._get_failed(factory, error) from error
        if component is None:
            return None
        if not isinstance(component, AbstractComponent):
            get = describe_callable(type(factory).get)
            if isinstance(component, type):
                raise ComponentError(
                    f"{get} returned the class {component.__name__} itself, not a "
                    f"component made from it. Call the class: `return "
                    f"{component.__name__}(self, parent)`."
                )
            raise ComponentError(
                f"{get} returned {short_repr(component)} ({type(component).__name__}), "
                "not an endpoint or loop. get() must build and return the component, "
                "e.g. `return MyEndpoint(self, parent)`."
            )
        return component

    def _get_failed(self, factory: AbstractFactory, error: Exception) -> ComponentError:
        frames = student_frames(error.__traceback__)
        trim_runtime_frames(error)
        return ComponentError(
            f"{describe_callable(type(factory).get)} raised {type(error).__name__}: "
            f"{error}\nwhile building a component for node {self.role!r}.\n"
            f"Where it happened (most recent call last):\n{frames}"
        )

    def add_component(self, component: AbstractComponent, start: bool = True) -> None:
        """Add a component; it begins at once if the node is running.

        Raises:
            ComponentError: the component is broken (e.g. missed super().__init__).
            ConfigError: another component already has its name.
        """
        self._check_owner_thread("add_component")
        if not hasattr(component, "name") or (
            not hasattr(component, "_task_handlers") and not hasattr(component, "parent")
        ):
            raise ComponentError(
                f"{describe_class(type(component))}: its __init__ did not call "
                "super().__init__(factory, parent, name). Add that line first in "
                "__init__ so SNR can give the component its name and task handlers."
            )
        name = component.name
        if name in self.components:
            other = self.components[name]
            factory = getattr(component, "factory", None)
            if getattr(other, "factory", None) is factory:
                raise ConfigError(
                    f"Node {self.role!r} got two components named {name!r} from the same "
                    f"{type(factory).__name__} object: it is listed twice in the config, "
                    "or its get() gives every component the same name. List it once, or "
                    "add another factory object that uses another name."
                )
            raise ConfigError(
                f"Node {self.role!r} already has a component named {name!r} "
                f"({describe_class(type(other))}); "
                f"{describe_class(type(component))} wants the same name. Give each "
                "component a unique name (e.g. pass a name to its factory)."
            )
        self.components[name] = component
        if self._table_stale:
            self._pending_adds.append(component)
        elif self.state is NodeState.RUNNING:
            self._pending_adds.append(component)  # applied before the next task
            self._table_stale = True
        else:
            self._handlers.add(component)
        if start and self.state is NodeState.RUNNING:
            self._start(component)

    def remove_component(self, name: ComponentName) -> None:
        """Halt, join, terminate and forget the component called ``name``."""
        self._check_owner_thread("remove_component")
        component = self.components.pop(name, None)
        if component is None:
            self.log.error(
                "Cannot remove component %r: node %r has no such component. It has: %s.",
                name,
                self.role,
                ", ".join(self.components),
            )
            return
        self._stop(component)
        self._call_safely(component, "terminate")
        self._mark_rebuild()

    def reload_component(self, name: ComponentName = "all") -> List[ComponentName]:
        """Reload the source of one component (or ``"all"``) and rebuild it.

        A reload that fails (e.g. a syntax error) leaves the old component
        running and logs why. Returns the names of the rebuilt components.
        """
        self._check_owner_thread("reload_component")
        if name == "all":
            targets = [c for c in self.components.values() if c.factory.reload_targets]
        elif name in self.components:
            targets = [self.components[name]]
        else:
            self.log.error(
                "Cannot reload %r: node %r has no such component. It has: %s.",
                name,
                self.role,
                ", ".join(self.components),
            )
            return []
        rebuilt: List[ComponentName] = []
        for old in targets:
            if self._reload_one(old):
                rebuilt.append(old.name)
        return rebuilt

    def _reload_one(self, old: AbstractComponent) -> bool:
        factory = old.factory
        try:
            factory.reload()
        except Exception as error:
            self.log.error(
                "Reloading %r failed, so the old version keeps running: %s: %s",
                old.name,
                type(error).__name__,
                error,
            )
            return False
        self._stop(old)
        try:
            new = self._build(factory)
        except Exception as error:
            self.log.error(
                "Rebuilding %r after reload failed: %s: %s. The old version stays.",
                old.name,
                type(error).__name__,
                error,
            )
            self._restart_endpoint(old)
            return False
        if new is None:
            self.log.error("%s.get() returned None on reload; keeping %r.", factory, old.name)
            self._restart_endpoint(old)
            return False
        self._call_safely(old, "terminate")
        self.components = {
            (new.name if n == old.name else n): (new if c is old else c)
            for n, c in self.components.items()
        }
        self._mark_rebuild()
        if self.state is NodeState.RUNNING:
            self._start(new)
        self.log.info("Reloaded %r", new.name)
        return True

    def _restart_endpoint(self, component: AbstractComponent) -> None:
        if not hasattr(component, "is_alive") and self.state is NodeState.RUNNING:
            self._call_safely(component, "begin")

    def _start(self, component: AbstractComponent) -> None:
        start = getattr(component, "_snr_start", component.begin)
        try:
            start()
        except SNRError:
            raise
        except Exception as error:
            frames = student_frames(error.__traceback__)
            trim_runtime_frames(error)
            raise ComponentError(
                f"{describe_class(type(component))} {component.name!r} failed to start: "
                f"{type(error).__name__}: {error}\n"
                f"Where it happened (most recent call last):\n{frames}"
            ) from error

    def _stop(self, component: AbstractComponent) -> None:
        stop = getattr(component, "_snr_stop", None)
        if stop is not None:
            try:
                stop()
            except Exception:
                self.log.exception("Error while halting %r", component.name)
            component.join(self.join_timeout_s)
        else:
            self._call_safely(component, "halt")

    def _call_safely(self, component: AbstractComponent, method: str) -> None:
        if method == "halt" and hasattr(component, "_snr_stop"):
            method = "_snr_stop"
        try:
            getattr(component, method)()
        except Exception:
            self.log.exception(
                "%s.%s() of component %r raised; carrying on with shutdown",
                type(component).__name__,
                method.strip("_").replace("snr_", ""),
                component.name,
            )

    def _component_handlers_changed(self, component: AbstractComponent) -> None:
        if self.components.get(component.name) is component:
            self._mark_rebuild()

    def _mark_rebuild(self) -> None:
        self._rebuild_needed = True
        self._table_stale = True

    def _refresh_table(self) -> None:
        if self._rebuild_needed:
            self._handlers.rebuild(self.components.values())
        else:
            for component in self._pending_adds:
                self._handlers.add(component)
        self._pending_adds = []
        self._rebuild_needed = False
        self._table_stale = False

    def _check_owner_thread(self, method: str) -> None:
        if (
            self.state is NodeState.RUNNING
            and self._thread_id is not None
            and threading.get_ident() != self._thread_id
        ):
            instead = THREAD_SAFE_INSTEAD.get(method, "self.schedule(task)")
            raise ThreadSafetyError(
                f"{method}() was called on node {self.role!r} from thread "
                f"{threading.current_thread().name!r} (at {caller_location()}), but only "
                "the node's own thread may change the node, and a loop runs on a thread "
                f"of its own. Use {instead} instead: it hands the work to the node's "
                "thread and is safe from any thread."
            )

    def __repr__(self) -> str:
        return f"<Node {self.role!r} {self.state.value}, {len(self.components)} components>"
