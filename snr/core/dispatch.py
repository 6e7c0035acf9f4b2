"""The node's handler table: which handlers run for a task, found in O(1).

Thesis 4.4.1 matches a task against every endpoint in turn: first by
``(type, name)``, then by ``type``. That costs time for every endpoint on every
task. Here the same answer is computed ahead of time (thesis 8.1): for every
task id that any component registered, the table holds the list of handlers
that the two-phase match would find, in component order. A task then needs one
or two dict look-ups, however many components the node has.

The table is rebuilt when a component is removed or reloaded or changes its
``task_handlers`` (the mapping is a :class:`HandlerMap` that reports changes),
and extended in place when a component is added at the end.

Example::

    table = HandlerTable()
    table.rebuild(node.components.values())
    table.lookup(TaskType.event, "ping")   # [(handler, key, component, cell), ...]
"""

from __future__ import annotations

from typing import (
    Any,
    Callable,
    Dict,
    Hashable,
    Iterable,
    List,
    Mapping,
    Optional,
    Tuple,
)

from snr.core.checks.handler_checks import (
    check_burst_handlers,
    check_entry,
    check_handler,
    check_task_id,
)
from snr.prelude import (
    AbstractComponent,
    AbstractProfiler,
    BurstHandler,
    StatsCell,
    TaskHandler,
    TaskId,
    TaskType,
)

__all__ = [
    "BurstEntry",
    "Entry",
    "HandlerMap",
    "HandlerTable",
    "check_burst_handlers",
    "check_handler",
    "check_task_id",
]

Entry = Tuple[TaskHandler, TaskId, AbstractComponent, StatsCell]
"""One matched handler: the function, the id it matched under, its component,
and its profiler cell ``[times_called, total_s]``."""

BurstEntry = Tuple[BurstHandler, AbstractComponent, StatsCell]
"""A burst handler that may serve a run of ``store_page`` tasks under one key,
its component, and the profiler cell of the same component's task handler."""

_STORE_PAGE = TaskType.store_page


class HandlerMap(Dict[TaskId, TaskHandler]):
    """A ``task_handlers`` dict that checks its entries and reports changes.

    Endpoints store their handlers in one of these, so a student can keep
    writing ``self.task_handlers = {...}`` or ``self.task_handlers[id] = f``
    and the node still hears about every change.

    Example::

        handlers = HandlerMap(owner_class=MyEndpoint, on_change=print)
        handlers[(TaskType.event, "go")] = my_handler    # checked, then reported
    """

    def __init__(
        self,
        items: Optional[Mapping[TaskId, TaskHandler]] = None,
        *,
        owner_class: type = object,
        on_change: Optional[Callable[[], None]] = None,
    ) -> None:
        super().__init__()
        self._owner_class = owner_class
        self._on_change = on_change
        if items:
            for key, handler in items.items():
                check_entry(key, handler, owner_class)
                super().__setitem__(key, handler)

    def _changed(self) -> None:
        if self._on_change is not None:
            self._on_change()

    def __setitem__(self, key: TaskId, handler: TaskHandler) -> None:
        check_entry(key, handler, self._owner_class)
        super().__setitem__(key, handler)
        self._changed()

    def __delitem__(self, key: TaskId) -> None:
        super().__delitem__(key)
        self._changed()

    def update(self, *args: Any, **kwargs: Any) -> None:
        for key, handler in dict(*args, **kwargs).items():
            self[key] = handler

    def pop(self, key: TaskId, *default: Any) -> Any:
        result = super().pop(key, *default)
        self._changed()
        return result

    def popitem(self) -> Tuple[TaskId, TaskHandler]:
        result = super().popitem()
        self._changed()
        return result

    def setdefault(self, key: TaskId, default: Any = None) -> Any:
        if key not in self:
            self[key] = default
        return self[key]

    def clear(self) -> None:
        super().clear()
        self._changed()


class HandlerTable:
    """Precomputed two-phase matches for every registered task id.

    Each entry carries the profiler's cell for its handler, fetched once here,
    so timing a handler costs the node two additions and no look-up.

    Example::

        table = HandlerTable(profiler)
        table.rebuild(components)
        for handler, key, component, cell in table.lookup(TaskType.event, "go"): ...
    """

    def __init__(self, profiler: Optional[AbstractProfiler] = None) -> None:
        self.table: Dict[Hashable, List[Entry]] = {}
        #: ``(TaskType.store_page, key)`` -> the burst handler for a run of those
        #: tasks, where one component alone handles them and declares one
        #: (`AbstractComponent.burst_handlers`). Refilled in place, as ``table``.
        self.bursts: Dict[Hashable, BurstEntry] = {}
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

    def _find_bursts(self, keys: Iterable[Hashable]) -> None:
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
