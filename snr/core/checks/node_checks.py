"""`NodeChecks`: wires the checks for silent mistakes into a node (not DEPLOYED).

`check_component` (DEBUG and TEST) reads each student class as its first
component is added; in DEBUG, ``node.key_hints``, ``node.wiring_checks`` and
``node.watchdog`` are set (None before ``node.loop()`` turns one off).

Example (what `Node` does)::

    self._checks = NodeChecks(self, components, runner)   # in __init__
    self._checks.start(threading.get_ident())             # as loop() starts
    self._checks.stop()                                   # in terminate()
"""

from __future__ import annotations

import functools
import threading
from typing import List, Mapping, Optional, Protocol, Tuple

from snr.core import tasks
from snr.core.checks.class_checks import check_component
from snr.core.checks.key_hints import MissingKeyHints
from snr.core.checks.watchdog import Watchdog, WatchedNode, queued_page_keys
from snr.core.checks.wiring_checks import WiringChecks
from snr.core.components import ComponentSet
from snr.core.dispatch import HandlerRunner
from snr.core.timer import Timer
from snr.prelude import (
    DataKey,
    Mode,
    Page,
    SomeTasks,
    TaskHandler,
    TaskType,
)

__all__ = ["CheckedNode", "NodeChecks"]

_PAGE_TASKS = (TaskType.store_page, TaskType.process_data)


class CheckedNode(WatchedNode, Protocol):
    """What `NodeChecks` reads and sets of its node: a `Node` has all of it.

    Example::

        checked: CheckedNode = Node("robot", config)
    """

    mode: Mode
    datastore: Mapping[DataKey, Page]
    timer: Timer
    wiring_checks: Optional[WiringChecks]
    watchdog: Optional[Watchdog]

    def schedule(self, t: SomeTasks) -> None:
        """Queue a task or a list of tasks; safe from any thread."""


class NodeChecks:
    """Builds a node's checks for silent mistakes and starts and stops them with it.

    Args:
        node: the node to watch; its ``key_hints``, ``wiring_checks`` and
            ``watchdog`` are set here (None outside DEBUG mode).
        components: the node's `ComponentSet` (its handler table, its
            ``check_added`` hook).
        runner: the node's `HandlerRunner` (its ``on_unhandled`` hook).

    Example::

        checks = NodeChecks(node, components, runner)
        node.key_hints is not None   # True in DEBUG mode
    """

    def __init__(self, node: CheckedNode, components: ComponentSet, runner: HandlerRunner) -> None:
        self.node = node
        self.components = components
        self._wiring_timer: Optional[threading.Timer] = None
        self._watching: Optional[Watchdog] = None
        node.key_hints = node.wiring_checks = node.watchdog = None
        if node.mode is Mode.DEBUG:
            hints = MissingKeyHints(
                node.log, node.timer.current_s, role=node.role, on_its_way=self.page_on_its_way
            )
            # The keys some handler waits for: reading them early is no mistake.
            hints.expected_keys = lambda: {key for key, _ in self.page_handlers()}
            node.key_hints = hints
            node.wiring_checks = WiringChecks(node.log, node.role, components.table, node.datastore)
            runner.on_unhandled = node.wiring_checks.unhandled
            node.watchdog = Watchdog(node)
        if node.mode is not Mode.DEPLOYED:
            # A name SNR uses raises; in DEBUG, work that can have no effect is logged once.
            warn = self._warn_once if node.mode is Mode.DEBUG else None
            components.check_added = functools.partial(check_component, warn=warn)

    def start(self, node_thread: int) -> None:
        """The node's thread starts running tasks: set the wiring check, start the watchdog."""
        hints = self.node.key_hints
        if hints is not None:
            timer = threading.Timer(
                hints.handlers_s, self.node.schedule, args=(tasks.event(tasks.CHECK_WIRING),)
            )
            timer.daemon = True
            timer.start()
            self._wiring_timer = timer
        self._watching = self.node.watchdog
        if self._watching is not None:
            timers = [self._wiring_timer] if self._wiring_timer is not None else []
            self._watching.start(node_thread, timers)

    def stop(self) -> None:
        """The node is stopping: cancel the wiring check, stop the watchdog."""
        if self._wiring_timer is not None:
            self._wiring_timer.cancel()
        if self._watching is not None:
            self._watching.stop()

    def check_wiring(self) -> None:
        """Warn about handlers of data keys that look misspelled and handlers that never ran."""
        hints = self.node.key_hints
        if hints is None:
            return
        hints.check_handlers(self.page_handlers(), self.node.datastore)
        if self.node.wiring_checks is not None:
            self.node.wiring_checks.check_never_ran()

    def page_handlers(self) -> List[Tuple[DataKey, TaskHandler]]:
        """(key, handler) for every handler registered for one data key's pages."""
        handled: List[Tuple[DataKey, TaskHandler]] = []
        for entries in list(self.components.table.table.values()):
            for handler, task_id, _, _ in entries:
                if isinstance(task_id, tuple) and task_id[0] in _PAGE_TASKS:
                    handled.append((task_id[1], handler))
        return handled

    def page_on_its_way(self, key: DataKey) -> bool:
        """True if ``key``'s page is queued, or the node's thread is stuck in a handler."""
        watchdog = self._watching
        if watchdog is not None and watchdog.handler_stuck:
            return True
        return key in queued_page_keys(self.node.queue)

    def _warn_once(self, message: str) -> None:
        self.node.log.warning("%s\n(Said once per class, in DEBUG mode only.)", message)
