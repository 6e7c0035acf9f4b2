"""`ComponentSet`: the part of a `Node` that holds its endpoints and loops.

`Node` inherits it: building, adding, removing, hot-reloading, starting and
stopping components, and keeping the node's handler table in step, on the
node's thread. A reload that fails keeps the old component running and logs
why with the file and line; a loop that does not stop in ``join_timeout_s``
is not reloaded (two would run).

Example::

    node.add_component(node.build_component(factory))
    node.reload_component("depth_filter")   # ['depth_filter'] if rebuilt
"""

from __future__ import annotations

import threading
import time
from typing import Any, Callable, Dict, List, Optional, Set

from snr.core.checks import explain, life_cycle
from snr.core.checks.explain import wrong_thread_error
from snr.core.checks.handler_checks import check_burst_handlers
from snr.core.dispatch import HandlerTable
from snr.core.task_queue import TaskQueue
from snr.prelude.abstract import AbstractComponent, AbstractFactory, AbstractLoop, AbstractNode
from snr.prelude.errors import SNRError
from snr.prelude.names import ComponentName

__all__ = ["NODE_CORE_NAME", "ComponentSet"]

NODE_CORE_NAME = "node_core"
"""The component name of every node's core endpoint (`NodeCoreEndpoint`)."""


class ComponentSet(AbstractNode):
    """A node's components, in start order, and the table of their handlers (`Node` is one).

    Args:
        table: the handler table to keep in step.

    Example::

        node.add_component(endpoint)          # begins it too if the node is running
        node.reload_component("depth_filter") # ['depth_filter'] if rebuilt

    Attributes:
        components: the components by name, in start order.
        table: the `HandlerTable`; `refresh_table` it while ``table_stale``.
        check_added: DEBUG and TEST: reads each component's class as it is added.
    """

    queue: TaskQueue  # whose owner_thread is the node's, once it runs
    join_timeout_s: float = 1.0
    """How long stopping waits for each loop's thread (1 s)."""

    def __init__(self, table: HandlerTable) -> None:
        self.table = table
        self.components: Dict[ComponentName, AbstractComponent] = {}
        self.table_stale = True
        self._none_told: Set[Any] = set()  # factories' get() already said to return None
        #: Called with each component before it is added (set by the node in DEBUG
        #: and TEST mode to read the student's class; see `check_component`).
        self.check_added: Optional[Callable[[AbstractComponent], None]] = None

    @property
    def running(self) -> bool:
        """True while the node runs (`Node`: its state is RUNNING).

        Only the node's thread may change the components then.
        Example: ``node.add_component(endpoint)`` begins it at once if ``node.running``.
        """
        raise NotImplementedError

    # -- building, adding and removing -------------------------------------
    def build_component(self, factory: AbstractFactory) -> Optional[AbstractComponent]:
        """``factory.get(self)``, with any mistake in ``get()`` explained.

        Raises:
            ComponentError: ``get()`` raised, or returned something that is not a
                component, or the factory skipped ``super().__init__()``.
        """
        if not hasattr(factory, "reload_targets"):
            raise explain.factory_without_init(factory)
        component: Any  # get() is typed, but a student's get() may return anything
        try:
            component = factory.get(self)
        except SNRError:
            raise
        except Exception as error:
            explain.raise_get_failure(factory, error, self.role)
        if component is None:
            explain.warn_get_returned_none(
                factory, self.role, self.running, self._none_told, self.log
            )
            return None
        if not isinstance(component, AbstractComponent):
            raise explain.wrong_get_result_error(factory, component)
        return component

    def add_component(self, component: AbstractComponent, start: bool = True) -> None:
        """Add a component last; it begins at once if the node is running.

        Raises:
            ComponentError: the component is broken (e.g. missed super().__init__).
            ConfigError: another component already has its name.
        """
        self._check_owner_thread("add_component")
        if not hasattr(component, "name") or (
            not hasattr(component, "_task_handlers") and not hasattr(component, "parent")
        ):
            raise explain.component_without_init(component)
        if self.check_added is not None:
            self.check_added(component)
        check_burst_handlers(component)
        other = self.components.get(component.name)
        if other is not None:
            raise explain.name_taken_error(self.role, component, other)
        self.components[component.name] = component
        self.table_stale = True  # the table is rebuilt before the next task
        if start and self.running:
            self._start(component)

    def remove_component(self, name: ComponentName) -> None:
        """Halt, join, terminate and forget the component called ``name``.

        The node's core (``node_core``) is never removed: the refusal is logged.
        """
        self._check_owner_thread("remove_component")
        component = self._find("remove component", name)
        if component is None:
            return
        del self.components[name]
        self._stop(component)
        self._warn_if_alive(component)
        self._call_safely("terminate", component)
        self.table_stale = True

    def _find(self, action: str, name: ComponentName) -> Optional[AbstractComponent]:
        """The component called ``name``; None, with the refusal logged, for node_core or none."""
        component = None if name == NODE_CORE_NAME else self.components.get(name)
        if component is None:
            life_cycle.not_found(self.log, action, name, self.role, self.components)
        return component

    # -- hot reload ---------------------------------------------------------
    def reload_component(self, name: ComponentName = "all") -> List[ComponentName]:
        """Reload the source of one component (or ``"all"``) and rebuild it.

        A reload that fails leaves the old component running and logs why.
        Returns the names of the rebuilt components; ``node_core`` is never reloaded.

        Example::

            node.reload_component("depth_filter")   # ['depth_filter']
        """
        self._check_owner_thread("reload_component")
        if name == "all":
            named = self.components.items()
            targets = [c for n, c in named if c.factory.reload_targets and n != NODE_CORE_NAME]
        else:
            component = self._find("reload", name)
            targets = [] if component is None else [component]
        return [old.name for old in targets if self._reload_one(old)]

    def _reload_one(self, old: AbstractComponent) -> bool:
        log = self.log
        try:
            old.factory.reload()
        except Exception as error:
            life_cycle.reload_refused(log, "source", old, error)
            return False
        if self.running:  # halt it and wait for its thread; it resumes if it will not stop
            self._stop(old)
            if old.is_alive():
                life_cycle.still_running(log, old, self.join_timeout_s, reload=True)
                if isinstance(old, AbstractLoop):
                    old.cancel_stop()
                return False
        new = self._build_replacement(old)
        if new is None:
            if self.running:
                try:
                    _start(old)
                except Exception as error:
                    life_cycle.reload_refused(log, "restart", old, error)
            return False
        self._call_safely("terminate", old)
        items = [
            (new.name if n == old.name else n, new if c is old else c)
            for n, c in self.components.items()
        ]
        self.components.clear()  # refilled in place: others may hold this dict
        self.components.update(items)
        self.table_stale = True
        if self.running:
            try:
                self._start(new)
            except SNRError as error:
                life_cycle.reload_refused(log, "start", old, error, new)
                return False
        log.info("Reloaded %r", new.name)
        return True

    def _build_replacement(self, old: AbstractComponent) -> Optional[AbstractComponent]:
        """A new component from ``old``'s factory, or None (logged) if that fails."""
        try:
            new = self.build_component(old.factory)
        except Exception as error:
            life_cycle.reload_refused(self.log, "build", old, error)
            return None
        if new is None:
            life_cycle.reload_refused(self.log, "none", old)
            return None
        if new.name != old.name and new.name in self.components:
            life_cycle.reload_refused(self.log, "name", old, new=new)
            return None
        return new

    # -- starting and stopping ----------------------------------------------
    def _start_all(self, keep_going: Callable[[], bool]) -> None:
        """Start every component in order while ``keep_going()`` says so."""
        for component in list(self.components.values()):
            if not keep_going():
                break
            self._start(component)

    def _start(self, component: AbstractComponent) -> None:
        """Begin ``component`` (a loop starts its thread); a ComponentError says where it raised."""
        try:
            _start(component)
        except SNRError:
            raise
        except Exception as error:
            raise explain.start_failure(component, error) from error

    def _stop(self, component: AbstractComponent) -> None:
        """Halt ``component`` and wait (up to ``join_timeout_s``) for its thread."""
        self._call_safely("halt", component)
        component.join(self.join_timeout_s)

    def _shutdown(self) -> None:
        """Halt every component (newest first), join their threads, then terminate them."""
        components = list(self.components.values())[::-1]
        for component in components:
            self._call_safely("halt", component)
        deadline = time.monotonic() + self.join_timeout_s
        for component in components:
            component.join(max(0.0, deadline - time.monotonic()))
        for component in components:
            self._warn_if_alive(component)
            self._call_safely("terminate", component)

    def _warn_if_alive(self, component: AbstractComponent) -> None:
        if component.is_alive():
            life_cycle.still_running(self.log, component, self.join_timeout_s, reload=False)

    def _call_safely(self, what: str, component: AbstractComponent) -> None:
        """Halt or terminate (``what``) ``component``; log (never raise) what goes wrong."""
        try:
            _halt(component) if what == "halt" else component.terminate()
        except Exception:
            life_cycle.call_failed(self.log, component, what)

    def _check_owner_thread(self, method: str) -> None:
        """While the components run, only the node's thread may call ``method``."""
        if self.running and threading.get_ident() != self.queue.owner_thread:
            raise wrong_thread_error(self.role, method)

    # -- the handler table ----------------------------------------------------
    def handlers_changed(self, component: AbstractComponent) -> None:
        """``component`` changed its ``task_handlers``: the table is rebuilt before the next task.

        Raises:
            ComponentError: a burst handler of the component lost its task handler.
        """
        if self.components.get(component.name) is component:
            self.table_stale = True
            check_burst_handlers(component)

    def refresh_table(self) -> None:
        """Rebuild the table from the components, with every change made since it was built."""
        self.table.rebuild(self.components.values())
        self.table_stale = False


def _start(component: AbstractComponent) -> None:
    (component.start_thread if isinstance(component, AbstractLoop) else component.begin)()


def _halt(component: AbstractComponent) -> None:
    if isinstance(component, AbstractLoop):
        component.set_terminate_flag("node stopping")
    component.halt()
