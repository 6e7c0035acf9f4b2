"""Checks of what a component registers as task handlers, with the fix in words.

`snr.core.dispatch.HandlerMap` calls `check_entry` on every ``task_handlers`` entry as it is set,
and the node calls `check_burst_handlers`: a wrong id, wrong parameters or an
``async def`` is refused at start-up, in every mode.

Example::

    check_task_id((TaskType.event, "go"))   # fine
    check_task_id("go")                     # ComponentError: "... Did you mean ..."
"""

from __future__ import annotations

import inspect
from types import CodeType
from typing import Any, Set

from snr.core.checks.call_checks import param_text
from snr.core.checks.error_text import closest_match
from snr.core.checks.student_code import (
    caller_block,
    code_of,
    def_block,
    describe_callable,
    describe_class,
)
from snr.prelude import AbstractComponent, ComponentError, TaskId, TaskType

__all__ = ["async_text", "check_burst_handlers", "check_entry", "check_handler", "check_task_id"]


def check_task_id(key: Any, owner_class: type = object) -> None:
    """Raise a ComponentError unless ``key`` is a TaskType or (TaskType, str).

    Example::

        check_task_id((TaskType.event, "go"))   # fine
        check_task_id("go")                     # ComponentError explaining why
    """
    pair = isinstance(key, tuple) and len(key) == 2
    if isinstance(key, TaskType) or (
        pair and isinstance(key[0], TaskType) and isinstance(key[1], str)
    ):
        return
    hint = ""
    if pair and isinstance(key[1], TaskType):
        hint = f" Put the TaskType first: ({key[1]!r}, {key[0]!r})."
    elif isinstance(key, str):
        guess = closest_match(key, TaskType.__members__)
        if guess is not None:
            hint = f" Did you mean TaskType.{guess}?"
        else:
            hint = (
                f" To run on pages stored under {key!r}, use "
                f"(TaskType.store_page, {key!r}); for an event called {key!r}, "
                f"use (TaskType.event, {key!r})."
            )
    raise ComponentError(
        f"{describe_class(owner_class)} registers a task handler under {key!r} "
        f"({type(key).__name__}), "
        "but task_handlers keys must be a TaskType, such as TaskType.terminate, or "
        f"a (TaskType, str) pair, such as (TaskType.store_page, 'depth').{hint}"
    )


_checked_code: Set[CodeType] = set()


def check_entry(key: Any, handler: Any, owner_class: type = object) -> None:
    """Raise a ComponentError, at the line that registered it, unless ``key: handler`` is valid.

    Example::

        check_entry((TaskType.event, "go"), self.on_go, MyEndpoint)   # fine
        check_entry("go", self.on_go, MyEndpoint)   # ComponentError, with the line
    """
    try:
        check_task_id(key, owner_class)
        if not callable(handler):
            check_handler(handler, key, owner_class)
    except ComponentError as error:
        where = caller_block()
        if not where:
            raise
        raise ComponentError(f"{error}\n{where}") from None
    check_handler(handler, key, owner_class)  # names the def to fix itself


def check_handler(handler: Any, key: TaskId, owner_class: type = object) -> None:
    """Raise a ComponentError unless ``handler`` can be called as ``f(task, key)`` (once per def).

    Example::

        def on_go(self, task: Task, key: TaskId) -> SomeTasks: ...   # fine
        def on_go(self, task: Task) -> SomeTasks: ...                # error
    """
    if not callable(handler):
        raise ComponentError(
            f"{describe_class(owner_class)} registers {handler!r} "
            f"({type(handler).__name__}) for {key!r}, "
            "but a task handler must be a method, such as self.on_data. Did you "
            "call it (self.on_data()) instead of naming it (self.on_data)?"
        )
    code = code_of(handler)
    if code is not None and code in _checked_code:
        return
    if inspect.iscoroutinefunction(handler):
        raise ComponentError(async_text(f"Task handler {describe_callable(handler)}", handler))
    try:
        signature = inspect.signature(handler)
    except (TypeError, ValueError):  # builtins without signatures: trust them
        return
    try:
        signature.bind(object(), object())
    except TypeError:
        where = describe_callable(handler)
        name = getattr(handler, "__name__", "handler")
        self_ = "self, " if hasattr(handler, "__self__") else ""
        params = [param_text(p) for p in signature.parameters.values()]
        if self_:
            params.insert(0, "self")
        code_line = "\n" + def_block(handler) if code is not None else ""
        raise ComponentError(
            f"Task handler {where} for {key!r} is written as "
            f"`def {name}({', '.join(params)})`, but SNR calls a handler with two "
            "arguments: the task and the task id it matched. Write it as "
            f"`def {name}({self_}task: Task, key: TaskId) -> SomeTasks:`.{code_line}"
        ) from None
    if code is not None:
        _checked_code.add(code)


def async_text(what: str, function: Any) -> str:
    """Why an ``async def`` handler, hook or ``loop()`` cannot work, and what to write.

    Example::

        async_text("Task handler Pump.on_go (robot.py:9)", pump.on_go)
        # "... is an `async def`, but SNR's handlers, hooks and loop() are plain functions ..."
    """
    name = getattr(function, "__name__", "handler")
    wait = (
        "loop() runs on a thread of its own, so it may wait the plain way: "
        "time.sleep(0.1), not await asyncio.sleep(0.1); max_tick_rate_hz sets its pace"
        if name == "loop"
        else "to wait for something, do it in a ThreadLoop's loop(), which runs on a "
        "thread of its own"
    )
    return (
        f"{what} is an `async def`, but SNR's handlers, hooks and loop() are plain "
        f"functions: the node calls {name}() and goes on when it returns, and never awaits "
        f"it, so none of its body would run. Write it as `def {name}(...)`, without "
        f"`async` and without `await` inside; {wait}.\n{def_block(function)}"
    ).rstrip()


def check_burst_handlers(component: AbstractComponent) -> None:
    """Raise a ComponentError for a burst handler the handler table could not use.

    Example::

        check_burst_handlers(comms)   # fine: returns None
    """
    owner = type(component)
    for key in component.burst_handlers:
        if not isinstance(key, tuple) or key[0] is not TaskType.store_page:
            raise ComponentError(
                f"{describe_class(owner)} has a burst handler for {key!r}; "
                "burst handlers are for pages under one key only: "
                "(TaskType.store_page, 'the_key')."
            )
        if key not in component.task_handlers:
            raise ComponentError(
                f"{describe_class(owner)} has a burst handler for {key!r} "
                "but no handler for it in task_handlers. Add one there too: it runs "
                "when a page under that key comes alone."
            )
