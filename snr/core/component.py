"""`Component`: what `Endpoint` and `ThreadLoop` share.

A component belongs to one node (its ``parent``), has a unique ``name`` there,
remembers the ``factory`` that built it, and registers ``task_handlers``. It
talks to the rest of the node only through tasks and pages.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any, Optional, Sequence

from snr.core.checks import explain
from snr.core.dispatch import HandlerMap
from snr.prelude.abstract import AbstractComponent, AbstractFactory, AbstractNode
from snr.prelude.names import ComponentName, DataKey
from snr.prelude.page import Page
from snr.prelude.task import SomeTasks, Task, TaskHandlerMap

__all__ = ["Component"]


class Component(AbstractComponent):
    """Base of every endpoint and loop; use `Endpoint` or `ThreadLoop`.

    Example::

        class Beeper(Endpoint):
            def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "beeper")
                self.task_handlers = {(TaskType.event, "beep"): self.beep}
    """

    produces: Sequence[DataKey] = ()
    """Data keys this component stores, for ``python -m snr graph`` (optional).

    The graph finds literal keys in the code itself; name computed ones all here.

    Example::

        self.produces = [f"motor_{side}" for side in ("left", "right")]
    """

    reads: Sequence[DataKey] = ()
    """Data keys this component reads with ``get_data``/``get_page``, for the graph (optional).

    As ``produces``: set it, and it is the whole list.

    Example::

        self.reads = [f"sonar_{n}" for n in range(4)]
    """

    def __init__(self, factory: AbstractFactory, parent: AbstractNode, name: ComponentName) -> None:
        explain.check_component_args(type(self), factory, parent, name)
        self.factory = factory
        self.parent = parent
        self.name = name
        self._log: Optional[logging.Logger] = None
        self._task_handlers = HandlerMap(owner_class=type(self), on_change=self._handlers_changed)

    @property
    def log(self) -> logging.Logger:
        """This component's logger, ``snr.<role>.<name>`` (made on first use: it is never freed)."""
        if self._log is None:
            self._log = self.parent.log.getChild(self.name)
        return self._log

    @log.setter
    def log(self, value: Any) -> None:
        raise explain.log_name_taken(type(self))

    @property
    def task_handlers(self) -> TaskHandlerMap:
        """Which handler runs for which task id; assign a dict in ``__init__``.

        Example::

            self.task_handlers = {(TaskType.store_page, "depth"): self.on_depth}
        """
        return self._task_handlers

    @task_handlers.setter
    def task_handlers(self, handlers: TaskHandlerMap) -> None:
        if "_task_handlers" not in self.__dict__:
            raise explain.handlers_before_init(type(self))
        self._task_handlers = HandlerMap(
            handlers, owner_class=type(self), on_change=self._handlers_changed
        )
        self._handlers_changed()

    def _handlers_changed(self) -> None:
        self.parent.handlers_changed(self)

    # -- life cycle hooks (documented no-ops: override what you need) -------
    def begin(self) -> None:
        """Runs once when the node starts; override to start things up."""

    def halt(self) -> None:
        """The component is about to stop or be reloaded: save state on the factory."""

    def terminate(self) -> None:
        """The component will not come back: close files, sockets and devices."""

    def join(self, timeout_s: Optional[float] = None) -> None:
        """Wait for the component's threads to end (endpoints have none)."""

    # -- talking to the node ------------------------------------------------
    def schedule(self, t: SomeTasks) -> None:
        """Queue tasks on the node; safe from any thread.

        Example::

            self.schedule(tasks.event("beep"))
        """
        self.parent.schedule(t)

    def page(self, key: DataKey, data: Any, process: bool = True) -> Page:
        """A new page stamped with this node's role and the time."""
        return self.parent.page(key, data, process)

    def store_page(self, page: Page) -> None:
        """Queue storing ``page`` on the node; safe from any thread."""
        self.parent.schedule(self.parent.store_page_task(page))

    def store_data(self, key: DataKey, data: Any, process: bool = True) -> None:
        """Queue storing ``data`` under ``key``; safe from any thread.

        Example::

            self.store_data("depth_m", 3.2)
        """
        self.parent.store_data(key, data, process)

    def store_data_task(self, key: DataKey, data: Any, process: bool = True) -> Task:
        """A task that stores ``data`` under ``key``: return it from a handler.

        Example::

            return self.store_data_task("speed", 0.5)
        """
        return self.parent.store_data_task(key, data, process)

    def store_page_task(self, page: Page) -> Task:
        """A task that stores ``page``: return it from a handler.

        Example::

            return self.store_page_task(self.page("speed", 0.5))
        """
        return self.parent.store_page_task(page)

    def get_page(self, key: DataKey) -> Optional[Page]:
        """The newest page under ``key``, or None. Read-only; any thread."""
        return self.parent.get_page(key)

    def get_data(self, key: DataKey) -> Optional[Any]:
        """The newest data under ``key``, or None. Read-only; any thread."""
        return self.parent.get_data(key)

    # -- logging (``self.warn("bad value %s", value)``) ----------------------
    def dbg(self, msg: str, *args: Any) -> None:
        """Log a debug message, e.g. ``self.dbg("got %s", value)``."""
        self.log.debug(msg, *args)

    def info(self, msg: str, *args: Any) -> None:
        """Log an informational message."""
        self.log.info(msg, *args)

    def warn(self, msg: str, *args: Any) -> None:
        """Log a warning, e.g. ``self.warn("Invalid data from %s", task)``."""
        self.log.warning(msg, *args)

    def err(self, msg: str, *args: Any) -> None:
        """Log an error."""
        self.log.error(msg, *args)

    def fatal(self, msg: str, *args: Any) -> None:
        """Log a critical error (the component cannot go on)."""
        self.log.critical(msg, *args)

    if not TYPE_CHECKING:  # hidden from mypy, which would let any misspelt attribute pass

        def __getattr__(self, attribute: str) -> Any:
            # Only reached when normal lookup fails. Before Component.__init__ has
            # run, every missing attribute means "super().__init__ was forgotten":
            # say so instead of a bare AttributeError deep inside SNR.
            raise explain.used_before_init(self, attribute)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.__dict__.get('name', '?')!r}>"
