"""What Python said about an error, kept whole when SNR wraps it, plus a hint; "did you mean".

Python adds the "Did you mean" of an ``AttributeError`` or ``NameError`` only when
it prints the traceback; `exception_text` keeps it (and works it out where Python
3.11 does not, ``TaskType.evnt``). `short_repr` is the prelude's, named here too.

Example::

    exception_text(error)
    # "AttributeError: type object 'TaskType' has no attribute 'evnt'. Did you mean: 'event'?"
"""

from __future__ import annotations

import builtins
import enum
import re
import traceback
from typing import Iterable, List, Optional

from snr.core.checks.student_code import innermost_frame
from snr.prelude.page import Page
from snr.prelude.student_code import short_repr

__all__ = ["PAGE_IN_A_HANDLER", "closest_key", "closest_match", "did_you_mean"]
__all__ += ["exception_text", "short_repr", "suggestion"]

PAGE_IN_A_HANDLER = (
    ". A stored page reaches a handler as a Page in task.val_list; "
    "its value is page.data, e.g. task.val_list[0].data."
)


def exception_text(error: BaseException) -> str:
    """``"Type: message"`` as Python prints it, with its "Did you mean" and SNR's hint.

    Call it before trimming the traceback: a misspelt name is looked up where it was used.

    Example::

        exception_text(AttributeError("'Task' object has no attribute 'val_lst'"))
    """
    text = "".join(traceback.format_exception_only(type(error), error)).strip()
    kind = type(error)
    if kind.__module__.split(".", 1)[0] == "snr":  # "ComponentError", as SNR's messages say
        text = text.replace(f"{kind.__module__}.{kind.__qualname__}", kind.__qualname__, 1)
    if isinstance(error, (AttributeError, NameError)) and "Did you mean" not in text:
        text = _enum_text(error) or text
        guess = None if "Did you mean" in text else _guess_name(error)
        text += f". Did you mean: {guess!r}?" if guess else ""
    if isinstance(error, TypeError) and re.search(r"\bPage\b", text):  # 'Page', Page object
        text += PAGE_IN_A_HANDLER  # explain.page_hint: get_page, loops
    elif isinstance(error, AttributeError) and isinstance(getattr(error, "obj", None), Page):
        try:  # does the page's data have what the page lacks (page.items)?
            data = error.obj.data  # type: ignore[attr-defined]
            found = isinstance(error.name, str) and hasattr(data, error.name)
        except Exception:  # the student's property failed: say nothing
            found = False
        if found:
            # Read-only page data (checks/read_only.py) is said as the list or dict it is.
            plain = "list" if isinstance(data, list) else "dict" if isinstance(data, dict) else ""
            text += f". Its data (a {plain or type(data).__name__}) has .{error.name}"
            text += PAGE_IN_A_HANDLER
    return text


def _enum_text(error: BaseException) -> Optional[str]:
    """Python 3.11's ``AttributeError: evnt`` for ``TaskType.evnt``, said as 3.12 says it."""
    frame = innermost_frame(error)
    found = frame.f_locals if frame is not None else {}
    cls, name = found.get("cls"), found.get("name")
    if not (isinstance(cls, type) and issubclass(cls, enum.Enum) and isinstance(name, str)):
        return None
    text = f"AttributeError: type object {cls.__name__!r} has no attribute {name!r}"
    guess = closest_match(name, list(cls.__members__))
    return f"{text}. Did you mean: {guess!r}?" if guess else text


def _guess_name(error: BaseException) -> Optional[str]:
    """The close match Python 3.12 would name for a misspelt attribute or name."""
    name, obj = getattr(error, "name", None), getattr(error, "obj", None)
    frame = innermost_frame(error)
    try:  # a broken __dir__ must not hide the student's error
        if isinstance(error, AttributeError):
            choices = [c for c in dir(obj) if not c.startswith("_")] if obj is not None else []
        else:
            choices = [*frame.f_locals, *frame.f_globals, *dir(builtins)] if frame else []
    except Exception:
        return None
    return closest_match(name, choices) if isinstance(name, str) else None


def closest_match(word: str, choices: Iterable[str], cutoff: float = 0.6) -> Optional[str]:
    """The choice most like ``word``, or None: the one rule of every "did you mean" hint.

    Capitals and underscores do not count (``taskHandlers`` is ``task_handlers``).

    Example::

        closest_match("urv", ["urov", "topside"])  # 'urov'
    """
    import difflib  # here, not at the top: hints are only made when something is wrong

    plain = {c.lower().replace("_", ""): c for c in reversed(list(choices))}
    found = difflib.get_close_matches(word.lower().replace("_", ""), list(plain), 1, cutoff)
    return plain[found[0]] if found else None


def closest_key(word: str, choices: List[str]) -> Optional[str]:
    """The choice that is ``word`` in other capitals, else `closest_match`'s: for keys and events.

    Example::

        closest_key("Depth", ["depth", "dept"])   # 'depth'
    """
    same_but_case = [c for c in choices if c.lower() == word.lower()]
    return same_but_case[0] if same_but_case else closest_match(word, choices)


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """`` Did you mean 'x'?`` for the choice most like ``word``, or "" if none is close.

    Example::

        f"There is no role 'urv'.{did_you_mean('urv', ['urov', 'topside'])}"
        # "There is no role 'urv'. Did you mean 'urov'?"
    """
    return suggestion(closest_match(word, choices))


def suggestion(guess: Optional[str]) -> str:
    """`` Did you mean 'x'?`` for a guess, or "" for None.

    Example::

        f"Unknown key.{suggestion(closest_key(key, stored))}"
    """
    return f" Did you mean {guess!r}?" if guess else ""
