"""What a node logs when a reload, a removal or a component's life-cycle call goes wrong.

`snr.core.components.ComponentSet` never lets such a mistake stop the node; each
message names the component, what failed and what happens now.

Example::

    reload_refused(node.log, "source", old, error)
    # Reloading 'depth_filter' failed while reading its new source, so the old
    # version keeps running:
    # filters.py:12: SyntaxError: invalid syntax
"""

from __future__ import annotations

import logging
from typing import Iterable, Literal, Optional

from snr.core.checks.explain import CORE_REFUSED, not_stopped_text, reload_failure
from snr.core.checks.student_code import describe_callable
from snr.prelude.abstract import AbstractComponent
from snr.prelude.errors import SNRError

__all__ = ["ReloadStage", "call_failed", "not_found", "reload_refused", "still_running"]

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

        reload_refused(node.log, "none", old)
        # "DepthFactory.get (robot.py:20) returned None on reload, so the old
        #  version of 'depth' keeps running."
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


def not_found(log: logging.Logger, action: str, name: str, role: str, names: Iterable[str]) -> None:
    """Log that node ``role`` cannot ``action`` the component ``name``: its core, or none.

    Example::

        not_found(node.log, "reload", "depht", "robot", ["depth"])
        # "Cannot reload 'depht': node 'robot' has no such component. It has: depth."
    """
    if action in CORE_REFUSED and name == "node_core":
        log.error(CORE_REFUSED[action], name, role)
    else:
        has = ", ".join(names)
        log.error(
            "Cannot %s %r: node %r has no such component. It has: %s.", action, name, role, has
        )


def still_running(
    log: logging.Logger, component: AbstractComponent, timeout_s: float, reload: bool
) -> None:
    """Log that ``component``'s thread did not stop within ``timeout_s`` (see `not_stopped_text`).

    Example::

        still_running(node.log, sonar_loop, 1.0, reload=False)
    """
    level = logging.ERROR if reload else logging.WARNING
    log.log(level, "%s", not_stopped_text(component, timeout_s, reload=reload))


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
