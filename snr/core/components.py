"""`ComponentSet`: a node's endpoints and loops, and their life cycle.

It builds, adds, removes, hot-reloads, starts and stops components and keeps
the node's handler table in step, on the node's thread. A reload that fails
keeps the old component running and logs why with the file and line; a loop
that does not stop in ``join_timeout_s`` is not reloaded (two would run).

Example::

    components = ComponentSet(node, HandlerTable(), join_timeout_s=1.0)
    components.add(components.build(factory))
    components.start_all(keep_going=lambda: True)
    ...
    components.shutdown()
"""

from __future__ import annotations

import time
from typing import Any, Callable, Dict, List, Optional, Set

from snr.core.checks import explain, life_cycle
from snr.core.checks.handler_checks import check_burst_handlers
from snr.core.dispatch import HandlerTable
from snr.prelude.abstract import AbstractComponent, AbstractFactory, AbstractLoop, AbstractNode
from snr.prelude.errors import SNRError
from snr.prelude.names import ComponentName

__all__ = ["NODE_CORE_NAME", "ComponentSet"]

NODE_CORE_NAME = "node_core"
"""The component name of every node's core endpoint (`NodeCoreEndpoint`)."""


class ComponentSet:
    """The components of one node, in start order, and the table of their handlers.

    Args:
        node: the node they belong to (for its role and log).
        table: the handler table to keep in step.
        join_timeout_s: how long stopping waits for a loop's thread.

    Example::

        components.add(endpoint)          # begins it too if the set is running
        components.reload("depth_filter") # ['depth_filter'] if rebuilt

    Attributes:
        by_name: the components by name, in start order (the node's ``components``).
        table: the `HandlerTable`; `refresh_table` it while ``table_stale``.
        running: True between `start_all` and `shutdown`.
        check_added: DEBUG and TEST: reads each component's class as it is added.
    """

    def __init__(self, node: AbstractNode, table: HandlerTable, join_timeout_s: float) -> None:
        self.node = node
        self.table = table
        self.join_timeout_s = join_timeout_s
        self.by_name: Dict[ComponentName, AbstractComponent] = {}
        self.running = False
        self.table_stale = True
        self._none_told: Set[Any] = set()  # factories' get() already said to return None
        #: Called with each component before it is added (set by the node in DEBUG
        #: and TEST mode to read the student's class; see `check_component`).
        self.check_added: Optional[Callable[[AbstractComponent], None]] = None

    # -- building ----------------------------------------------------------
    def build(self, factory: AbstractFactory) -> Optional[AbstractComponent]:
        """``factory.get(node)``, with any mistake in it explained.

        Raises:
            ComponentError: ``get()`` raised, or returned something that is not a
                component, or the factory skipped ``super().__init__()``.
        """
        if not hasattr(factory, "reload_targets"):
            raise explain.factory_without_init(factory)
        component: Any  # get() is typed, but a student's get() may return anything
        try:
            component = factory.get(self.node)
        except SNRError:
            raise
        except Exception as error:
            explain.raise_get_failure(factory, error, self.node.role)
        if component is None:
            role, log = self.node.role, self.node.log
            explain.warn_get_returned_none(factory, role, self.running, self._none_told, log)
            return None
        if not isinstance(component, AbstractComponent):
            raise explain.wrong_get_result_error(factory, component)
        return component

    # -- adding and removing ------------------------------------------------
    def add(self, component: AbstractComponent, start: bool = True) -> None:
        """Add ``component`` last; it begins at once if the set is running.

        Raises:
            ComponentError: the component skipped ``super().__init__``.
            ConfigError: another component already has its name.
        """
        if not hasattr(component, "name") or (
            not hasattr(component, "_task_handlers") and not hasattr(component, "parent")
        ):
            raise explain.component_without_init(component)
        if self.check_added is not None:
            self.check_added(component)
        check_burst_handlers(component)
        other = self.by_name.get(component.name)
        if other is not None:
            raise explain.name_taken_error(self.node.role, component, other)
        self.by_name[component.name] = component
        self.table_stale = True  # the table is rebuilt before the next task
        if start and self.running:
            self.start(component)

    def remove(self, name: ComponentName) -> None:
        """Halt, join, terminate and forget the component called ``name``.

        The node's core (``node_core``) is never removed: the refusal is logged.
        """
        component = self._find("remove component", name)
        if component is None:
            return
        del self.by_name[name]
        self.stop(component)
        self._warn_if_alive(component)
        self.call_safely("terminate", component)
        self.table_stale = True

    def _find(self, action: str, name: ComponentName) -> Optional[AbstractComponent]:
        """The component called ``name``; None, with the refusal logged, for node_core or none."""
        component = None if name == NODE_CORE_NAME else self.by_name.get(name)
        if component is None:
            life_cycle.not_found(self.node.log, action, name, self.node.role, self.by_name)
        return component

    # -- hot reload ---------------------------------------------------------
    def reload(self, name: ComponentName = "all") -> List[ComponentName]:
        """Reload the source of one component (or ``"all"``) and rebuild it.

        Returns the names of the rebuilt components; one that fails keeps
        running and the log says why. ``node_core`` is never reloaded.

        Example::

            components.reload("depth_filter")   # ['depth_filter']
        """
        if name == "all":
            named = self.by_name.items()
            targets = [c for n, c in named if c.factory.reload_targets and n != NODE_CORE_NAME]
        else:
            component = self._find("reload", name)
            targets = [] if component is None else [component]
        return [old.name for old in targets if self._reload_one(old)]

    def _reload_one(self, old: AbstractComponent) -> bool:
        log = self.node.log
        try:
            old.factory.reload()
        except Exception as error:
            life_cycle.reload_refused(log, "source", old, error)
            return False
        if self.running and not self._stop_for_reload(old):
            return False
        new = self._build_replacement(old)
        if new is None:
            self._resume(old)
            return False
        self.call_safely("terminate", old)
        items = [
            (new.name if n == old.name else n, new if c is old else c)
            for n, c in self.by_name.items()
        ]
        self.by_name.clear()  # refilled in place: the node's `components` is this dict
        self.by_name.update(items)
        self.table_stale = True
        if self.running:
            try:
                self.start(new)
            except SNRError as error:
                life_cycle.reload_refused(log, "start", old, error, new)
                return False
        log.info("Reloaded %r", new.name)
        return True

    def _stop_for_reload(self, old: AbstractComponent) -> bool:
        """Halt ``old`` and wait for its thread; False (and it resumes) if it will not stop."""
        self.stop(old)
        if not old.is_alive():
            return True
        life_cycle.still_running(self.node.log, old, self.join_timeout_s, reload=True)
        if isinstance(old, AbstractLoop):
            old.cancel_stop()
        return False

    def _build_replacement(self, old: AbstractComponent) -> Optional[AbstractComponent]:
        """A new component from ``old``'s factory, or None (logged) if that fails."""
        try:
            new = self.build(old.factory)
        except Exception as error:
            life_cycle.reload_refused(self.node.log, "build", old, error)
            return None
        if new is None:
            life_cycle.reload_refused(self.node.log, "none", old)
            return None
        if new.name != old.name and new.name in self.by_name:
            life_cycle.reload_refused(self.node.log, "name", old, new=new)
            return None
        return new

    def _resume(self, old: AbstractComponent) -> None:
        if not self.running:
            return
        try:
            _begin(old)
        except Exception as error:
            life_cycle.reload_refused(self.node.log, "restart", old, error)

    # -- starting and stopping ----------------------------------------------
    def start_all(self, keep_going: Callable[[], bool]) -> None:
        """Start every component in order while ``keep_going()`` says so."""
        self.running = True
        for component in list(self.by_name.values()):
            if not keep_going():
                break
            self.start(component)

    def start(self, component: AbstractComponent) -> None:
        """Begin ``component`` (a loop also starts its thread).

        Raises:
            ComponentError: its ``begin()`` raised; the message shows where.
        """
        try:
            _begin(component)
        except SNRError:
            raise
        except Exception as error:
            raise explain.start_failure(component, error) from error

    def stop(self, component: AbstractComponent) -> None:
        """Halt ``component`` and wait (up to ``join_timeout_s``) for its thread."""
        self.call_safely("halt", component)
        component.join(self.join_timeout_s)

    def shutdown(self) -> None:
        """Halt every component (newest first), join their threads, then terminate them."""
        self.running = False
        components = list(self.by_name.values())[::-1]
        for component in components:
            self.call_safely("halt", component)
        deadline = time.monotonic() + self.join_timeout_s
        for component in components:
            component.join(max(0.0, deadline - time.monotonic()))
        for component in components:
            self._warn_if_alive(component)
            self.call_safely("terminate", component)

    def _warn_if_alive(self, component: AbstractComponent) -> None:
        if component.is_alive():
            life_cycle.still_running(self.node.log, component, self.join_timeout_s, reload=False)

    def call_safely(self, what: str, component: AbstractComponent) -> None:
        """Halt or terminate (``what``) ``component``; log (never raise) what goes wrong."""
        try:
            _halt(component) if what == "halt" else component.terminate()
        except Exception:
            life_cycle.call_failed(self.node.log, component, what)

    # -- the handler table ----------------------------------------------------
    def handlers_changed(self, component: AbstractComponent) -> None:
        """``component`` changed its ``task_handlers``: rebuild the table before the next task.

        Raises:
            ComponentError: a burst handler of the component lost its task handler.
        """
        if self.by_name.get(component.name) is component:
            self.table_stale = True
            check_burst_handlers(component)

    def refresh_table(self) -> None:
        """Rebuild the table from the components, with every change made since it was built."""
        self.table.rebuild(self.by_name.values())
        self.table_stale = False


def _begin(component: AbstractComponent) -> None:
    # Errors pass as raised: `ComponentSet.start` words them, a reload's restart logs them.
    (component.start_thread if isinstance(component, AbstractLoop) else component.begin)()


def _halt(component: AbstractComponent) -> None:
    if isinstance(component, AbstractLoop):
        component.set_terminate_flag("node stopping")
    component.halt()
