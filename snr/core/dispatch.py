"""The node's dispatch: which handlers run for a task, and running them.

`HandlerTable` answers thesis 4.4.1's two-phase match (``(type, name)``, then
``type``) ahead of time for every registered task id, so a task needs one or
two dict look-ups however many components the node has. `HandlerRunner` is the
one place where SNR calls a student's task handler: it stores a
``store_page`` task's page first, runs the handlers in component order (timed
unless DEPLOYED without a profiler), queues what they return and hands a
failure to the node's `snr.core.checks.failures.FailureReport`. docs/design.md
("Dispatch: a handler table, not a scan") tells the rest, bursts included.

Example::

    table = HandlerTable()
    table.rebuild(node.components.values())
    table.lookup(TaskType.event, "ping")   # [(handler, key, component, cell), ...]
"""

from __future__ import annotations

import time
from typing import (
    TYPE_CHECKING,
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Optional,
    Protocol,
    Tuple,
    cast,
)

from snr.core.checks.handler_checks import (
    check_burst_handlers,
    check_entry,
    check_handler,
    check_task_id,
)
from snr.prelude.abstract import AbstractComponent, AbstractProfiler
from snr.prelude.names import StatsCell, TaskId, TaskType
from snr.prelude.task import BurstHandler, Task, TaskHandler, TaskHandlerMap

if TYPE_CHECKING:
    from snr.core.checks.failures import FailureReport
    from snr.core.task_queue import TaskQueue

__all__ = ["BurstEntry", "Entry", "HandlerMap", "HandlerRunner", "HandlerTable", "Handlers"]
__all__ += ["check_burst_handlers", "check_handler", "check_task_id"]

Entry = Tuple[TaskHandler, TaskId, AbstractComponent, StatsCell]
"""One matched handler: the function, the id it matched under, its component,
and its profiler cell ``[times_called, total_s]``."""

BurstEntry = Tuple[BurstHandler, AbstractComponent, StatsCell]
"""A burst handler that may serve a run of ``store_page`` tasks under one key,
its component, and the profiler cell of the same component's task handler."""

_STORE_PAGE = TaskType.store_page
_EVENT = TaskType.event
_MAX_BURST = 256  # store_page tasks a burst handler gets at most in one call


def _nothing() -> None:
    pass


class HandlerMap(Dict[TaskId, TaskHandler]):
    """A ``task_handlers`` dict that checks its entries and reports changes.

    So the node hears of ``self.task_handlers[id] = f`` as of ``= {...}``.

    Example::

        handlers = HandlerMap(owner_class=MyEndpoint, on_change=print)
        handlers[(TaskType.event, "go")] = my_handler    # checked, then reported
    """

    def __init__(
        self,
        items: Optional[TaskHandlerMap] = None,
        *,
        owner_class: type = object,
        on_change: Optional[Callable[[], None]] = None,
    ) -> None:
        super().__init__()
        self._owner_class = owner_class
        self._on_change: Callable[[], None] = _nothing  # filling it is no change
        self.update(items or {})
        self._on_change = on_change or _nothing

    def __setitem__(self, key: TaskId, handler: TaskHandler) -> None:
        check_entry(key, handler, self._owner_class)
        super().__setitem__(key, handler)
        self._on_change()

    def __delitem__(self, key: TaskId) -> None:
        super().__delitem__(key)
        self._on_change()

    def update(self, *args: Any, **kwargs: Any) -> None:
        for key, handler in dict(*args, **kwargs).items():
            self[key] = handler

    def pop(self, key: TaskId, *default: Any) -> Any:
        result = super().pop(key, *default)
        self._on_change()
        return result

    def popitem(self) -> Tuple[TaskId, TaskHandler]:
        result = super().popitem()
        self._on_change()
        return result

    def setdefault(self, key: TaskId, default: Any = None) -> Any:
        if key not in self:
            self[key] = default
        return self[key]

    def clear(self) -> None:
        super().clear()
        self._on_change()


class HandlerTable:
    """Precomputed two-phase matches for every registered task id.

    Each entry carries its handler's profiler cell.

    Example::

        table = HandlerTable(profiler)
        table.rebuild(components)
        for handler, key, component, cell in table.lookup(TaskType.event, "go"): ...
    """

    def __init__(self, profiler: Optional[AbstractProfiler] = None) -> None:
        self.table: Dict[TaskId, List[Entry]] = {}
        #: ``(TaskType.store_page, key)`` -> the burst handler for a run of those
        #: tasks, where one component alone handles them and declares one
        #: (`AbstractComponent.burst_handlers`). Refilled in place, as ``table``.
        self.bursts: Dict[TaskId, BurstEntry] = {}
        self.profiler = profiler

    def lookup(self, task_type: TaskType, name: str) -> List[Entry]:
        """The handlers to run for a task, in component order (maybe empty)."""
        entries = self.table.get((task_type, name))
        if entries is None:
            entries = self.table.get(task_type, [])
        return entries

    def rebuild(self, components: Iterable[AbstractComponent]) -> None:
        """Recompute the whole table from the components, in order.

        The dicts are refilled in place, so a caller holding ``table`` sees the
        new contents; lists are new, so a pass iterating an old list is safe.
        """
        self.table.clear()
        self.bursts.clear()
        for component in components:
            self.add(component)

    def add(self, component: AbstractComponent) -> None:
        """Extend the table for a component added after all the others.

        Never raises for a student's mistake: it runs between two tasks, where
        nothing could report it. `check_burst_handlers` refuses those earlier.
        """
        handlers = component.task_handlers
        table = self.table
        for key in handlers:
            if isinstance(key, tuple) and key not in table:
                # A new specific id first inherits every earlier component's
                # type-level handler, exactly as the two-phase match would.
                table[key] = list(table.get(key[0], []))
        for key, handler in handlers.items():
            entry: Entry = (handler, key, component, self._cell(handler, key))
            table.setdefault(key, []).append(entry)
            if isinstance(key, TaskType):
                # Fallback: this type-level handler also serves every specific
                # id of its type that this component did not register itself.
                for specific in [k for k in table if isinstance(k, tuple) and k[0] is key]:
                    if specific not in handlers:
                        table[specific].append(entry)
        # Only the ids this component handles can have changed (a type-level
        # store_page handler joins every specific id of that type).
        self._find_bursts(table if _STORE_PAGE in handlers else handlers)

    def _find_bursts(self, keys: Iterable[TaskId]) -> None:
        """Say again, for each of ``keys``, whether a burst handler serves it."""
        bursts, table = self.bursts, self.table
        for key in keys:
            if not isinstance(key, tuple) or key[0] is not _STORE_PAGE:
                continue
            bursts.pop(key, None)
            entries = table.get(key)
            if entries is None or len(entries) != 1:
                continue  # no one, or more than one component: page by page
            _, matched, component, cell = entries[0]
            burst = component.burst_handlers.get(matched)  # None for a type-level match
            if burst is not None:
                bursts[key] = (burst, component, cell)

    def _cell(self, handler: TaskHandler, key: TaskId) -> StatsCell:
        if self.profiler is None:
            return [0, 0.0]  # timed for slow-handler reports only
        return self.profiler.task_cell(key, getattr(handler, "__module__", None) or "?")


class Handlers(Protocol):
    """What the runner reads of the node's components: their handler table, kept current.

    The node's `snr.core.components.ComponentSet` is one; the runner needs no more of it.

    Example::

        if components.table_stale:   # a component was added, removed or changed
            components.refresh_table()
        entries = components.table.table.get(task.id(), [])
    """

    table: HandlerTable
    table_stale: bool

    def refresh_table(self) -> None:
        """Rebuild ``table`` from the components, with every change made since."""


class HandlerRunner:
    """Runs handlers, queues their tasks, and hands failures to the node's failure report.

    Args:
        queue: where tasks come from and returned tasks go.
        components: the node's components, as `Handlers` (their handler table).
        failures: the node's `snr.core.checks.failures.FailureReport`.
        timed: time every handler (DEBUG/TEST, or a profiler is on).

    Example::

        runner.run_queued()
        runner.failures.failure   # the HandlerError/LoopError that stopped the node, or None

    Attributes:
        running: False once the node is stopping or pausing: `run_queued`
            returns after the current task.
        slow_handler_s: handlers slower than this are reported (not in DEPLOYED).
        on_unhandled: None, or (DEBUG) called with each event no handler matched.
        store_page: the node core's `store_page_handler`, run before a
            ``store_page`` task's handlers.
    """

    def __init__(
        self,
        queue: TaskQueue,
        components: Handlers,
        failures: FailureReport,
        timed: bool = True,
        slow_handler_s: float = 0.1,
    ) -> None:
        self.queue = queue
        self.components = components
        self.failures = failures
        self.running = True
        self.timed = timed
        self.slow_handler_s = slow_handler_s
        #: Called with an event that no handler matched (set by a DEBUG node).
        self.on_unhandled: Optional[Callable[[Task], None]] = None
        #: Stores a store_page task's page before its handlers (set by the node).
        self.store_page: Optional[TaskHandler] = None

    def run_queued(self, max_tasks: int = 100_000) -> None:
        """Run queued tasks until the queue is empty, the node stops, or ``max_tasks`` ran.

        Urgent tasks first, then oldest first: each task's handlers run in
        component order and what they return is queued. The node's hot path.

        Example::

            node.schedule(tasks.event("go"))
            runner.run_queued()   # every handler of (event, 'go'), and what follows
        """
        normal, urgent = self.queue.normal, self.queue.urgent
        components = self.components
        lookup = components.table.table.get
        bursts = components.table.bursts  # refilled in place when the table changes
        timed, clock, slow_s = self.timed, time.perf_counter, self.slow_handler_s
        for _ in range(max_tasks):
            lane = urgent or normal  # urgent tasks first
            if not lane:
                return
            task = lane.popleft()
            if components.table_stale:  # what the last task changed applies now
                components.refresh_table()
            if task.type is _STORE_PAGE:
                self.store_first(task)  # the node core's part, before any handler
                # A run for a burst handler starts only from the normal lane: a
                # paused node runs urgent tasks one at a time, `execute_task` one task.
                if bursts and lane is normal and normal and normal[0].name == task.name:
                    burst = bursts.get((_STORE_PAGE, task.name))
                    if burst is not None and normal[0].type is _STORE_PAGE:
                        self.run_burst(task, burst)
                        if not self.running:
                            return
                        continue
            # Two-phase match: the task's (type, name), else its type (entries are never []).
            entries = lookup((task.type, task.name)) or lookup(task.type)
            if entries is None:
                if self.on_unhandled is not None and task.type is _EVENT:
                    self.on_unhandled(task)  # DEBUG: an event nobody handles
                continue
            for handler, key, component, cell in entries:
                if timed:
                    started = clock()
                try:
                    result = handler(task, key)
                except Exception as error:
                    self.failures.handler_failed(handler, task, component, error)
                    continue
                if timed:
                    took = clock() - started
                    cell[0] += 1
                    cell[1] += took
                    if took > slow_s:
                        self.failures.report_slow(handler, task, took)
                if isinstance(result, Task):
                    (urgent if result.priority else normal).append(result)
                elif result is not None:
                    self.queue_all(self.check_result(result, handler, task))
            if not self.running:
                return

    def run_burst(self, first: Task, burst: BurstEntry) -> None:
        """Run ``burst``'s handler for ``first`` and the run of tasks like it behind it.

        ``first`` and the ``store_page`` tasks under its key at the head of
        the queue (at most `_MAX_BURST`), each page stored first, go to the
        burst handler in one call; its result is queued as a handler's is.

        Example (what `run_queued` does when the table has a burst handler)::

            burst = components.table.bursts.get((TaskType.store_page, "depth"))
            if burst is not None:
                runner.run_burst(task, burst)   # task and the "depth" pages behind it
        """
        handler, component, cell = burst
        normal = self.queue.normal
        store_first = self.store_first
        name = first.name
        run = [first]
        while self.running and normal and len(run) < _MAX_BURST:  # a failed store stops it
            task = normal[0]
            if task.type is not _STORE_PAGE or task.name != name:
                break
            normal.popleft()
            store_first(task)
            run.append(task)
        named = cast(TaskHandler, handler)  # reported by its name, as a task handler is
        started = time.perf_counter()
        try:
            result = handler(run)
        except Exception as error:
            self.failures.handler_failed(named, first, component, error, run_size=len(run))
            return
        if self.timed:
            self._count(named, first, cell, time.perf_counter() - started, len(run))
        self.queue_all(self.check_result(result, named, first))

    def run(
        self,
        handler: TaskHandler,
        task: Task,
        key: TaskId,
        component: Optional[AbstractComponent],
        cell: Optional[StatsCell] = None,
    ) -> Optional[List[Task]]:
        """Run one handler, timed and checked; return its tasks (not queued)."""
        started = time.perf_counter()
        try:
            result = handler(task, key)
        except Exception as error:
            self.failures.handler_failed(handler, task, component, error)
            return None
        self._count(handler, task, cell or [0, 0.0], time.perf_counter() - started)
        return self.check_result(result, handler, task)

    def _count(
        self, handler: TaskHandler, task: Task, cell: StatsCell, took: float, calls: int = 1
    ) -> None:
        """Add a call that took ``took`` s to ``cell``; report it if it was slow."""
        cell[0] += calls
        cell[1] += took
        if took > self.slow_handler_s:
            self.failures.report_slow(handler, task, took)

    def store_first(self, task: Task) -> Optional[Task]:
        """For a ``store_page`` task: store its page now, queue and return what follows.

        A page that cannot be stored is reported as a handler's failure.

        Example::

            runner.store_first(tasks.store_page(page))   # (process_data, key) or None
        """
        store_page = self.store_page
        if task.type is not _STORE_PAGE or store_page is None:
            return None
        try:
            follow_up = store_page(task, _STORE_PAGE)
        except Exception as error:
            owner = getattr(store_page, "__self__", None)
            self.failures.handler_failed(store_page, task, owner, error)
            return None
        if isinstance(follow_up, Task):
            self.queue.normal.append(follow_up)
            return follow_up
        return None

    def queue_all(self, tasks: Optional[List[Task]]) -> None:
        """Queue tasks a handler returned, in order (urgent ones jump ahead)."""
        if tasks:
            normal, urgent = self.queue.normal, self.queue.urgent
            for task in tasks:
                (urgent if task.priority else normal).append(task)

    def check_result(self, result: Any, handler: TaskHandler, task: Task) -> Optional[List[Task]]:
        """``result`` as a list of tasks; a wrong value is reported and dropped."""
        if result is None:
            return None
        if isinstance(result, Task):
            return [result]
        if isinstance(result, list) and all(isinstance(t, Task) for t in result):
            return result
        self.failures.bad_result(result, handler, task)
        return None
