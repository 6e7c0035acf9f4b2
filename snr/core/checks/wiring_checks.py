"""`WiringChecks`: in DEBUG mode, say when a task can never reach a handler.

A task no handler matches is dropped without a word (the thesis's rule), but an
*event* nothing handles is almost always a mistake, as is a handler registered
under the wrong kind of task (docs/errors.md, 15). The run loop calls
`unhandled` for a task no handler matched; the node's wiring check calls
`check_never_ran`. Events SNR's components announce for whoever cares are
never reported.

Example::

    checks = WiringChecks(node.log, node.role, table, node.datastore)
    checks.unhandled(tasks.event("strat"))
    # Nothing on node 'robot' handles the event 'strat' ... Did you mean 'start'?
"""

from __future__ import annotations

import logging
from typing import Mapping, Set, Tuple

from snr.core.checks.error_text import closest_key, short_repr
from snr.core.checks.student_code import describe_callable
from snr.core.dispatch import HandlerTable
from snr.prelude import DataKey, Page, Task, TaskName, TaskType

__all__ = ["WiringChecks"]

_OPTIONAL_EVENTS: Set[TaskName] = {
    "comms_connected",
    "comms_disconnected",
    "button_pressed",
    "button_released",
}  # announced by SNR's components whether or not anything listens

_BUILDER_OF = {
    "terminate": "tasks.terminate('why')",
    "reload": "tasks.reload_component('name')",
    "store_page": "tasks.store_page(page)",
    "store_data": "self.store_data_task(key, value)",
    "process_data": "tasks.process_data(page)",
}

_FOOTER = "(Said once per name, in DEBUG mode only.)"


class WiringChecks:
    """Finds events nothing handles and handlers nothing can reach (DEBUG mode).

    Args:
        log: where warnings go (the node's logger).
        role: the node's role, for messages.
        table: the node's handler table.
        datastore: the node's datastore (to tell data keys from event names).

    Example::

        checks.unhandled(task)      # from the run loop, for a task with no handler
        checks.check_never_ran()    # a few seconds after the node started
    """

    MAX_REPORTS = 100

    def __init__(
        self,
        log: logging.Logger,
        role: str,
        table: HandlerTable,
        datastore: Mapping[DataKey, Page],
    ) -> None:
        self.log = log
        self.role = role
        self.table = table
        self.datastore = datastore
        self._reported: Set[Tuple[TaskType, str]] = set()

    def unhandled(self, task: Task) -> None:
        """Warn, once per name, about an event no handler on this node matches."""
        if task.type is not TaskType.event:
            return  # a page or process_data nobody handles is normal
        name = task.name
        if (
            not isinstance(name, str)
            or name in _OPTIONAL_EVENTS
            or name.startswith("snr_")
            or (TaskType.event, name) in self._reported
            or len(self._reported) >= self.MAX_REPORTS
        ):
            return
        self._reported.add((TaskType.event, name))
        shown = f"values {short_repr(task.val_list, 80)}" if task.val_list else "no values"
        self.log.warning(
            f"Nothing on node {self.role!r} handles the event {name!r} ({shown}), so it was "
            f"dropped. {self._why_unhandled(name)} {_FOOTER}"
        )

    def _why_unhandled(self, name: str) -> str:
        if name in _BUILDER_OF:
            return (
                f"tasks.event({name!r}) makes an event called {name!r}, not a {name} "
                f"task: use {_BUILDER_OF[name]}."
            )
        other_kinds = [k for k in self.table.table if isinstance(k, tuple) and k[1] == name]
        if other_kinds or name in self.datastore:
            kind = other_kinds[0][0] if other_kinds else TaskType.store_page
            return (
                f"{name!r} is a data key here (a handler waits for (TaskType.{kind.name}, "
                f"{name!r})), and data reaches handlers only when it is stored: "
                f"self.store_data({name!r}, value) in a loop, or return "
                f"self.store_data_task({name!r}, value) from a handler."
            )
        events = sorted(
            key[1]
            for key in self.table.table
            if isinstance(key, tuple)
            and key[0] is TaskType.event
            and not key[1].startswith("snr_")
            and key[1] not in _CORE_EVENTS
        )
        guess = closest_key(name, events)
        listened = ", ".join(repr(e) for e in events) or "none"
        if guess is not None:
            return (
                f"Did you mean {guess!r}? Events handled here: {listened}. Event names "
                "must match exactly (capitals too)."
            )
        return (
            f"Events handled here: {listened}. If a component should handle it, check that "
            "its factory is in this role's list in the config, and that it registers "
            f"(TaskType.event, {name!r}) in task_handlers."
        )

    def check_never_ran(self) -> None:
        """Warn about handlers that have not run and cannot: an event that is a data key, a
        process_data handler of pages stored with ``process=False``."""
        # Each handler once, under the id it was registered for (a type-level handler
        # also sits in the lists of its type's specific ids).
        for task_id, entries in list(self.table.table.items()):
            for handler, registered, _, cell in entries:
                if registered != task_id or cell[0] or not isinstance(task_id, tuple):
                    continue
                kind, key = task_id
                page = self.datastore.get(key)
                if page is None or task_id in self._reported:
                    continue
                if kind is TaskType.event:
                    text = (
                        f"{describe_callable(handler)} handles the event {key!r}, but {key!r} "
                        "is a data key: data is stored, not announced, so this handler never "
                        f"runs. Register it as (TaskType.store_page, {key!r}) to run on every "
                        "page stored under it."
                    )
                elif kind is TaskType.process_data and not page.process:
                    text = (
                        f"{describe_callable(handler)} handles process_data for {key!r}, but "
                        f"the pages under {key!r} are stored with process=False, which skips "
                        "process_data, so this handler never runs. Store them with "
                        f"process=True (the default), or register (TaskType.store_page, {key!r})."
                    )
                else:
                    continue
                self._reported.add(task_id)
                self.log.warning(f"{text} {_FOOTER}")


# Events handled by the node core: not names a student would mean.
_CORE_EVENTS = {"add_component", "remove_component"}
