"""Helpers that build the common tasks, so handlers read like sentences.

Example::

    from snr import tasks

    def on_button(self, task: Task, key: TaskId) -> SomeTasks:
        return [tasks.event("beep"), tasks.terminate("user pressed stop")]
"""

from __future__ import annotations

import time
from typing import Any, List, Optional

from snr.core.checks.call_checks import values_not_a_list
from snr.core.checks.explain import check_page_args
from snr.prelude.abstract import AbstractFactory
from snr.prelude.errors import ComponentError
from snr.prelude.names import ComponentName, DataKey, TaskName, TaskPriority, TaskType
from snr.prelude.page import Page
from snr.prelude.task import Task

__all__ = ["ADD_COMPONENT", "CAUGHT_UP", "CHECK_WIRING", "REMOVE_COMPONENT", "STORE_PAGES"]
__all__ += ["add_component", "event", "process_data", "reload_component", "remove_component"]
__all__ += ["store_data", "store_page", "store_pages", "terminate"]

ADD_COMPONENT: TaskName = "add_component"
"""Name of the event task that adds a component built by a factory."""

REMOVE_COMPONENT: TaskName = "remove_component"
"""Name of the event task that removes a component by name."""

CAUGHT_UP: TaskName = "snr_caught_up"
"""Event a loop schedules after ``setup()``; the node core sets the event it carries."""

CHECK_WIRING: TaskName = "snr_check_wiring"
"""Event that has the node core look for wiring mistakes: a DEBUG node's own, a few
seconds after it starts, or a comms link's, carrying its check (a function)."""

STORE_PAGES: TaskName = "snr_store_pages"
"""Name of the event task that stores several pages in order (see `store_pages`)."""


def event(name: TaskName, val_list: Optional[List[Any]] = None) -> Task:
    """An event task, e.g. ``tasks.event("button_pressed", ["A"])``.

    Raises:
        ComponentError: ``val_list`` is not a list (``tasks.event("say", "hi")``).
    """
    if val_list is None:
        return Task(TaskType.event, name, [])
    if not isinstance(val_list, list):
        raise ComponentError(values_not_a_list(name, val_list))
    return Task(TaskType.event, name, val_list)


def store_page(page: Page) -> Task:
    """A task that stores ``page`` in the node's datastore.

    Example::

        return tasks.store_page(self.page("depth_m", 3.2))
    """
    return Task(TaskType.store_page, page.key, [page])


def store_pages(pages: List[Page]) -> Task:
    """One task that stores ``pages`` in order, as one `store_page` task each would.

    For pages that arrive together (a comms link's read): handlers see the
    same as for one task a page.

    Example::

        node.schedule(tasks.store_pages([page_a, page_b]))
    """
    return Task(TaskType.event, STORE_PAGES, pages)


def store_data(key: DataKey, data: Any, process: bool = True) -> Task:
    """A task that stores ``data`` under ``key``; the node stamps its role.

    Example::

        return tasks.store_data("thruster_data", 2)

    Raises:
        ComponentError: ``key`` is not a str, or ``data`` is a whole `Page`.
    """
    check_page_args(key, data)
    page = Page(key, data, origin="", created_at_s=time.time(), process=process)
    return Task(TaskType.store_page, key, [page])


def process_data(page: Page) -> Task:
    """The task that follows a stored page whose ``process`` flag is set."""
    return Task(TaskType.process_data, page.key, [page])


def reload_component(name: ComponentName = "all") -> Task:
    """Reload one component's source code, or ``"all"`` of them.

    Example::

        node.schedule(tasks.reload_component("depth_filter"))
    """
    return Task(TaskType.reload, name)


def terminate(reason: str) -> Task:
    """Stop the node; runs before any task already waiting.

    Example::

        return tasks.terminate("Landed Safely")
    """
    return Task(TaskType.terminate, reason, priority=TaskPriority.high)


def add_component(factory: AbstractFactory) -> Task:
    """Build a component with ``factory`` and add it to the running node."""
    return Task(TaskType.event, ADD_COMPONENT, [factory])


def remove_component(name: ComponentName) -> Task:
    """Halt, terminate and remove the component called ``name``."""
    return Task(TaskType.event, REMOVE_COMPONENT, [name])
