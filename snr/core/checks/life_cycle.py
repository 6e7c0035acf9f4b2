"""A node's or a component's life cycle gone wrong, in words: run twice, started twice, a
task without its page, a reload refused, a thread that will not stop, a halt() that raised.

Only the first two raise; the rest is logged, and the node runs on.

Example::

    raise ran_twice_error("robot", "terminated")
    # Cannot run node 'robot': it is terminated. A node runs once; build a new
    # Node to run again.
"""

from __future__ import annotations

import logging
from typing import Iterable, Literal, Optional

from snr.core.checks.explain import reload_failure
from snr.core.checks.student_code import describe_callable
from snr.prelude.abstract import AbstractComponent, AbstractLoop
from snr.prelude.errors import NodeStateError, SNRError

__all__ = [
    "NOT_A_PAGE",
    "ReloadStage",
    "call_failed",
    "not_found",
    "ran_twice_error",
    "reload_refused",
    "started_twice_error",
    "still_running",
]

NOT_A_PAGE = (
    "A store_page task for %r carries %r instead of a Page; dropped it. "
    "Make these tasks with tasks.store_page(page) or self.store_data_task()."
)
"""What the node core logs for a ``store_page`` task without a page (its name, its values)."""


def ran_twice_error(role: str, state: str) -> NodeStateError:
    """The error for ``Node.loop()`` called on a node that is not new (``state``: where it is).

    Example::

        raise ran_twice_error("robot", "running")
    """
    return NodeStateError(
        f"Cannot run node {role!r}: it is {state}. A node runs once; build a new Node to run again."
    )


def started_twice_error(name: str, state: str) -> NodeStateError:
    """The error for a loop whose thread is started while it runs (``state``: "running").

    Example::

        raise started_twice_error("sonar", "running")
    """
    return NodeStateError(
        f"Cannot start loop {name!r} twice: it is {state}. "
        "Reloading builds a new loop from its factory instead."
    )


ReloadStage = Literal["source", "build", "none", "name", "restart", "start"]
"""Where a reload went wrong: the new ``source``, ``build`` (``none``: ``get()`` gave None;
``name``: a taken name), ``restart`` of the old one, ``start`` of the new one."""

_KEEPS = "so the old version keeps running"


def reload_refused(
    log: logging.Logger,
    stage: ReloadStage,
    old: AbstractComponent,
    error: Optional[BaseException] = None,
    new: Optional[AbstractComponent] = None,
) -> None:
    """Log why reloading ``old`` went wrong at ``stage`` (``new``: the new one), and what runs now.

    Example::

        reload_refused(node.log, "source", old, error)
        # Reloading 'depth_filter' failed while reading its new source, so the old
        # version keeps running:
        # filters.py:12: SyntaxError: invalid syntax
    """
    name, text = old.name, ""
    if stage == "source" and error is not None:
        text = f"Reloading {name!r} failed while reading its new source, {_KEEPS}:\n"
        text += reload_failure(error)
    elif stage == "build" and error is not None:
        why = error if isinstance(error, SNRError) else reload_failure(error)
        text = f"Rebuilding {name!r} after its reload failed, {_KEEPS}:\n{why}"
    elif stage == "none":
        get = describe_callable(type(old.factory).get)
        text = f"{get} returned None on reload, so the old version of {name!r} keeps running."
    elif stage == "name" and new is not None:
        text = f"Reloaded {name!r} came back named {new.name!r}, which another component has; "
        text += "the old version keeps running."
    elif stage == "restart" and error is not None:
        text = f"{name!r} could not be restarted after the failed reload: "
        text += f"{type(error).__name__}: {error}"
    elif stage == "start" and new is not None:
        text = f"Reloaded {new.name!r}, but it failed to start: {error}"
    if text:
        log.error("%s", text)


# What not_found logs (name, role) for removing or reloading the node's own core.
_CORE_REFUSED = {
    "remove component": (
        "Refused to remove %r from node %r: it is the node's own core, which "
        "stores every page, adds, removes and reloads components, and stops the "
        "node on a terminate task; without it the node would run on deaf. To stop "
        "the node, schedule a terminate task (or type `exit` in a console)."
    ),
    "reload": (
        "Refused to reload %r in node %r: it is the node's own core and runs this "
        "very reload (and every store, add, remove and terminate); SNR's own code "
        "is not reloaded while the node runs. Restart the node to load a new SNR."
    ),
}


def not_found(log: logging.Logger, action: str, name: str, role: str, names: Iterable[str]) -> None:
    """Log that node ``role`` cannot ``action`` the component ``name``: its core, or none.

    Example::

        not_found(node.log, "reload", "depht", "robot", ["depth"])
        # "Cannot reload 'depht': node 'robot' has no such component. It has: depth."
    """
    if action in _CORE_REFUSED and name == "node_core":
        log.error(_CORE_REFUSED[action], name, role)
    else:
        has = ", ".join(names)
        log.error(
            "Cannot %s %r: node %r has no such component. It has: %s.", action, name, role, has
        )


def still_running(
    log: logging.Logger, component: AbstractComponent, timeout_s: float, reload: bool
) -> None:
    """Log that ``component``'s thread did not stop within ``timeout_s`` (reloading, or stopping).

    Example::

        still_running(node.log, sonar_loop, 1.0, reload=False)
    """
    where = component.where_running() if isinstance(component, AbstractLoop) else ""
    advice = (
        "Make loop() return often: give reads a timeout and wait with self.wait_s(seconds) "
        "instead of time.sleep(), so the loop notices when it should stop."
    )
    if reload:
        log.error(
            f"Cannot reload loop {component.name!r}: it did not stop within "
            f"{timeout_s:.1f} s of being asked{f' (it is at {where})' if where else ''}, and "
            "a new copy would run beside it. Reload refused; the old version keeps "
            f"running. {advice}"
        )
        return
    log.warning(
        f"Loop {component.name!r} did not stop within {timeout_s:.1f} s of being asked"
        f"{f': it is at {where}' if where else ''}. Its terminate() runs now anyway, while "
        f"its thread is still going (the thread ends with the program). {advice}"
    )


def call_failed(log: logging.Logger, component: AbstractComponent, what: str) -> None:
    """Log, with its traceback, that ``component``'s ``what()`` raised; the node carries on.

    Call it in the ``except`` block, where the error is being handled.

    Example::

        try:
            component.halt()
        except Exception:
            call_failed(node.log, component, "halt")
    """
    name = type(component).__name__
    log.exception("%s.%s() of component %r raised; carrying on", name, what, component.name)
