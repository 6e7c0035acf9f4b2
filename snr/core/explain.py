"""How the node puts a student's mistakes into words.

Small helpers used by `Node` when a handler returns something odd, a factory
forgets to return, or a loop thread calls a method it must not. Kept apart so
`node.py` reads as the runtime it is.

Example::

    task_label(tasks.event("go"))   # "(event, 'go')"
"""

from __future__ import annotations

import dis
from typing import Any, Optional

from snr.prelude import Page, Task
from snr.prelude.errors import short_repr

__all__ = [
    "THREAD_SAFE_INSTEAD",
    "bad_result_hint",
    "describe_bad_result",
    "only_returns_none",
    "task_label",
    "task_values",
]


def task_label(task: Task) -> str:
    """``(event, 'go')``: a task's id as students see it printed."""
    return f"({task.type.name}, {task.name!r})"


def task_values(task: Task) -> str:
    """What a task carries, shortened: its page's key and data, or its values."""
    values = task.val_list
    if len(values) == 1 and isinstance(values[0], Page):
        page = values[0]
        return f"carrying the page {page.key!r} with data {short_repr(page.data, 200)}"
    return f"with values {short_repr(values, 200)}"


def describe_bad_result(result: Any) -> str:
    """What a handler returned that is not a Task, a list of Tasks or None."""
    if isinstance(result, list):
        index, bad = next((i, t) for i, t in enumerate(result) if not isinstance(t, Task))
        return (
            f"returned a list whose item {index} is {short_repr(bad)} ({type(bad).__name__}),"
            " not a Task,"
        )
    return f"returned {short_repr(result)} ({type(result).__name__})"


def bad_result_hint(result: Any) -> str:
    """A hint for the likely slip behind a bad return value (or "")."""
    items = result if isinstance(result, (list, tuple)) else []
    if isinstance(result, tuple) and all(isinstance(t, Task) for t in items):
        return " Return a list, [task1, task2], not a tuple."
    if isinstance(result, Page):
        return " To store a page, return tasks.store_page(page)."
    if isinstance(result, bool):
        return " Return None when there is nothing to do."
    if any(t is None for t in items):
        return " Leave None out of the list."
    if any(isinstance(t, (list, tuple)) for t in items):
        return " Return one flat list of Tasks (join lists with + or extend)."
    return ""


def only_returns_none(func: Any) -> bool:
    """True if ``func``'s code has no ``return <value>``: it can only give None.

    Read from the bytecode, not the source (which may not be on the robot).
    """
    code = getattr(getattr(func, "__func__", func), "__code__", None)
    if code is None:
        return False
    previous: Optional[dis.Instruction] = None
    saw_return = False
    for instruction in dis.get_instructions(code):
        if instruction.opname == "RETURN_CONST":
            saw_return = True
            if instruction.argval is not None:
                return False
        if instruction.opname == "RETURN_VALUE":
            saw_return = True
            if not (
                previous is not None and previous.opname == "LOAD_CONST" and previous.argval is None
            ):
                return False
        previous = instruction
    # No return instruction we know: a newer Python's bytecode. Never accuse
    # a student's factory on a guess.
    return saw_return


# What a loop thread should call instead of a method that changes node state.
THREAD_SAFE_INSTEAD = {
    "execute_task": "self.schedule(task)",
    "handle_task": "self.schedule(task)",
    "add_component": "self.schedule(tasks.add_component(factory))",
    "remove_component": "self.schedule(tasks.remove_component(name))",
    "reload_component": "self.schedule(tasks.reload_component(name))",
    "write_page": "self.store_page(page) or self.store_data(key, value)",
    "terminate": "self.schedule(tasks.terminate(reason))",
}
