"""The node core endpoint: the node's own handlers (thesis 4.3.2).

It is the first component of every node, named ``node_core``. It stores pages
(then sends ``process_data`` when asked), adds, removes and reloads
components, and stops the node on a terminate task.
"""

from __future__ import annotations

import dataclasses
import threading
from typing import Any, Dict, List

from snr.core import tasks
from snr.core.endpoint import Endpoint
from snr.core.factory import EndpointFactory
from snr.prelude import (
    AbstractFactory,
    AbstractNode,
    DataKey,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)

__all__ = ["NODE_CORE_NAME", "NodeCoreEndpoint", "NodeCoreFactory"]

_PROCESS_DATA = TaskType.process_data
_STORE_PAGE = TaskType.store_page

NODE_CORE_NAME = "node_core"
"""The component name of every node's core endpoint."""


class NodeCoreEndpoint(Endpoint):
    """Stores pages and manages components for its node.

    Example (what it does for you)::

        node.schedule(tasks.store_data("depth", 3.0))   # → datastore["depth"]
        node.schedule(tasks.terminate("done"))          # → node stops
    """

    def __init__(self, factory: AbstractFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, NODE_CORE_NAME)
        self.node = parent
        self.pages: Dict[DataKey, Page] = {}  # the node's own dict (node.pages), set by the node
        self.task_handlers = {
            (TaskType.event, tasks.STORE_PAGES): self.store_pages_handler,
            (TaskType.event, tasks.ADD_COMPONENT): self.add_component_handler,
            (TaskType.event, tasks.REMOVE_COMPONENT): self.remove_component_handler,
            (TaskType.event, tasks.CAUGHT_UP): self.caught_up_handler,
            (TaskType.event, tasks.CHECK_WIRING): self.check_wiring_handler,
            TaskType.reload: self.reload_handler,
            TaskType.terminate: self.terminate_handler,
        }

    def store_page_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Put the task's page in the datastore; then process_data if asked.

        Not in the handler table: the node's run loop calls it for every
        ``store_page`` task before the task's handlers (``HandlerRunner``), so
        they all find the page stored.
        """
        page = task.page()
        if page is None:
            self.err(
                "A store_page task for %r carries %r instead of a Page; dropped it. "
                "Make these tasks with tasks.store_page(page) or self.store_data_task().",
                task.name,
                task.val_list,
            )
            return None
        if not page.origin:  # made by tasks.store_data(), which has no node
            page = dataclasses.replace(page, origin=self.node.role)
            task.val_list[0] = page
        self.pages[page.key] = page  # node.write_page, on the node's own thread
        # The page's process_data task, only if some handler waits for it: a
        # page nobody processes (a sender's page, say) costs no task.
        if page.process and self.node.is_handled(_PROCESS_DATA, page.key):
            return Task(_PROCESS_DATA, page.key, [page])
        return None

    def store_pages_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Store a burst of pages (`tasks.store_pages`) in order, in one handler call.

        Each page is stored and its ``process_data`` task queued, exactly as
        its own ``store_page`` task would have done, but without a dispatch
        per page. When a page's key has ``store_page`` handlers besides this
        core (a comms component forwarding it, a recorder), that page and the
        ones after it go back to the front of the queue as one ``store_page``
        task each, so every handler sees them in the usual order.
        """
        node, pages = self.node, self.pages
        processed: List[Task] = []
        wanted: Dict[DataKey, bool] = {}  # per key, asked once a burst: is it processed?
        burst = task.val_list
        for index, page in enumerate(burst):
            # Page by page from here when the usual handler must explain or fix
            # the page, or when a handler besides this core stores its key.
            if not (isinstance(page, Page) and page.origin) or (
                page.key not in wanted and node.is_handled(_STORE_PAGE, page.key)
            ):
                self._store_one_by_one(burst[index:])
                break
            pages[page.key] = page  # node.write_page, on the node's own thread
            if page.key not in wanted:
                wanted[page.key] = node.is_handled(_PROCESS_DATA, page.key)
            if page.process and wanted[page.key]:
                processed.append(Task(_PROCESS_DATA, page.key, [page]))
        return processed

    def _store_one_by_one(self, pages: List[Any]) -> None:
        """Queue one store_page task per page, first in line, in order."""
        one_each = [Task(TaskType.store_page, str(getattr(p, "key", "")), [p]) for p in pages]
        self.node.schedule_first(one_each)

    def add_component_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Build a component with the factory in the task and add it."""
        factory = task.val_list[0] if task.val_list else None
        if not isinstance(factory, AbstractFactory):
            self.err("add_component needs a factory, got %r", factory)
            return None
        component = self.node.build_component(factory)
        if component is not None:
            self.node.add_component(component)
        return None

    def remove_component_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Remove the component named in the task."""
        for name in task.val_list:
            self.node.remove_component(str(name))
        return None

    def caught_up_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Everything scheduled before this task was handled: set the event it carries."""
        for value in task.val_list:
            if isinstance(value, threading.Event):
                value.set()
        return None

    def check_wiring_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Look for wiring mistakes: the node's own check, or the checks it carries.

        A comms component sends this event with its check of one link (a
        function to call) in ``val_list``, so the check runs on the node's
        thread; without one, the node checks its handlers' keys.
        """
        checks = [value for value in task.val_list if callable(value)]
        if not checks:
            self.node.check_wiring()
        for check in checks:
            check()
        return None

    def reload_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Reload the component named by the task (or ``"all"``)."""
        self.node.reload_component(task.name or "all")
        return None

    def terminate_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Stop the node once this task has been handled by everyone."""
        self.node.set_terminate_flag(task.name)
        return None


class NodeCoreFactory(EndpointFactory):
    """Builds the node core endpoint (every node makes one itself)."""

    def get(self, parent: AbstractNode) -> NodeCoreEndpoint:
        return NodeCoreEndpoint(self, parent)
