"""What Python said about an error, kept whole when SNR wraps it, plus a hint.

SNR puts a student's exception inside its own message (a `HandlerError`
names the handler and the task). ``f"{type(error).__name__}: {error}"``
would lose part of what Python says: the "Did you mean" of an
``AttributeError`` or ``NameError`` is not in ``str(error)``, it is added
when Python prints the traceback. `exception_text` keeps it, works it out
where Python 3.11 does not (a misspelt enum member, ``TaskType.evnt``), and
adds a hint for the commonest mix-up with SNR's own types (a `Page` used as
its value).

Example::

    try:
        TaskType.evnt
    except AttributeError as error:
        exception_text(error)
        # "AttributeError: type object 'TaskType' has no attribute 'evnt'. Did you mean: 'event'?"
"""

from __future__ import annotations

import builtins
import enum
import re
import traceback
from typing import Any, Iterable, List, Optional

from snr.prelude.student_code import call_site

__all__ = [
    "PAGE_IN_A_HANDLER",
    "bad_data_key",
    "closest_match",
    "did_you_mean",
    "exception_text",
    "page_as_data",
    "plain_signature",
    "short_repr",
    "values_not_a_list",
    "wrong_call",
]

_SUGGESTION = "Did you mean"


def exception_text(error: BaseException) -> str:
    """``"Type: message"`` as Python prints it, with its "Did you mean" and SNR's hint.

    Call it before trimming the traceback: a misspelt name is looked up in
    the frame where it was used.

    Example::

        exception_text(AttributeError("'Task' object has no attribute 'val_lst'"))
    """
    lines = traceback.format_exception_only(type(error), error)
    text = "".join(lines).strip()
    kind = type(error)
    if kind.__module__.split(".", 1)[0] == "snr":  # "ComponentError", as SNR's messages say
        text = text.replace(f"{kind.__module__}.{kind.__qualname__}", kind.__qualname__, 1)
    if isinstance(error, (AttributeError, NameError)) and _SUGGESTION not in text:
        text = _enum_text(error) or text
        if _SUGGESTION not in text:
            guess = _guess_name(error)
            if guess is not None:
                text = f"{text}. {_SUGGESTION}: {guess!r}?"
    if isinstance(error, TypeError) and re.search(r"\bPage\b", text):  # 'Page', Page object
        text += PAGE_IN_A_HANDLER  # checks/explain.py says it for get_page and loops
    return text


PAGE_IN_A_HANDLER = (
    ". A stored page reaches a handler as a Page in task.val_list; "
    "its value is page.data, e.g. task.val_list[0].data."
)


def _innermost_locals(error: BaseException) -> Optional[dict[str, Any]]:
    tb = error.__traceback__
    if tb is None:
        return None
    while tb.tb_next is not None:
        tb = tb.tb_next
    return tb.tb_frame.f_locals


def _enum_text(error: BaseException) -> Optional[str]:
    """Python 3.11's ``AttributeError: evnt`` for ``TaskType.evnt``, said as 3.12 says it."""
    found = _innermost_locals(error)
    cls = found.get("cls") if found else None
    name = found.get("name") if found else None
    if not (isinstance(cls, type) and issubclass(cls, enum.Enum) and isinstance(name, str)):
        return None
    text = f"AttributeError: type object {cls.__name__!r} has no attribute {name!r}"
    guess = closest_match(name, list(cls.__members__))
    return f"{text}. {_SUGGESTION}: {guess!r}?" if guess else text


def _guess_name(error: BaseException) -> Optional[str]:
    """The close match Python 3.12 would name for a misspelt attribute or name."""
    name = getattr(error, "name", None)
    if not isinstance(name, str):
        return None
    choices: Iterable[str]
    if isinstance(error, AttributeError):
        obj = getattr(error, "obj", None)
        if obj is None:
            return None
        try:
            choices = [c for c in dir(obj) if not c.startswith("_")]
        except Exception:  # a broken __dir__ must not hide the student's error
            return None
    else:
        tb = error.__traceback__
        while tb is not None and tb.tb_next is not None:
            tb = tb.tb_next
        if tb is None:
            return None
        frame = tb.tb_frame
        names: List[str] = [*frame.f_locals, *frame.f_globals, *dir(builtins)]
        choices = names
    return closest_match(name, choices)


def closest_match(word: str, choices: Iterable[str], cutoff: float = 0.6) -> Optional[str]:
    """The choice most like ``word``, or None: the one rule of every "did you mean" hint.

    Capitals and underscores do not count (``taskHandlers`` is ``task_handlers``);
    a near miss of SNR's own names (`class_checks`) asks for ``cutoff=0.8``.

    Example::

        closest_match("urv", ["urov", "topside"])  # 'urov'
    """
    import difflib  # here, not at the top: hints are only made when something is wrong

    plain = {c.lower().replace("_", ""): c for c in reversed(list(choices))}
    found = difflib.get_close_matches(word.lower().replace("_", ""), list(plain), 1, cutoff)
    return plain[found[0]] if found else None


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """`` Did you mean 'x'?`` for the choice most like ``word``, or "" if none is close.

    Example::

        f"There is no role 'urv'.{did_you_mean('urv', ['urov', 'topside'])}"
        # "There is no role 'urv'. Did you mean 'urov'?"
    """
    guess = closest_match(word, choices)
    return f" {_SUGGESTION} {guess!r}?" if guess else ""


def short_repr(value: Any, limit: int = 120) -> str:
    """``repr(value)``, cut to ``limit`` characters so messages stay readable.

    Example::

        short_repr(list(range(1000)), 20)   # '[0, 1, 2, 3, 4, 5, …'
    """
    try:
        text = repr(value)
    except Exception as error:  # a broken __repr__ must not hide the real error
        return f"<{type(value).__name__} whose repr() raised {type(error).__name__}>"
    return text if len(text) <= limit else text[: limit - 1] + "…"


def plain_signature(name: str, function: Any) -> str:
    """``"CliRunner(components_or_config, argv=None)"``: a call as a student writes it.

    ``function`` is the class or function; ``self`` and annotations are left out.

    Example::

        plain_signature("Node", Node)   # 'Node(role, config)'
    """
    import inspect  # only while an error is being explained

    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return f"{name}(...)"
    parts: List[str] = []
    for parameter in signature.parameters.values():
        if parameter.name == "self":
            continue
        text = parameter.name
        if parameter.kind is parameter.VAR_POSITIONAL:
            text = "*" + text
        elif parameter.kind is parameter.VAR_KEYWORD:
            text = "**" + text
        elif isinstance(parameter.default, enum.Enum):
            text += f"={type(parameter.default).__name__}.{parameter.default.name}"
        elif parameter.default is not parameter.empty:
            text += f"={parameter.default!r}"
        parts.append(text)
    return f"{name}({', '.join(parts)})"


def wrong_call(name: str, function: Any, args: Iterable[Any], problem: str) -> str:
    """The message for a public constructor or runner called with the wrong arguments.

    It names the call as the student wrote it (shortened), where, what is
    wrong, and the signature to follow.

    Example::

        raise ConfigError(wrong_call("Node", Node, (config, "robot"),
                                     "the role and the config are swapped."))
        # Node(Config(roles=['robot'], ...), 'robot') at robot.py:4: the role and the
        # config are swapped. Write it as Node(role, config).
    """
    shown = ", ".join(short_repr(a, 40) for a in args)
    return (
        f"{name}({shown}) at {call_site()}: {problem} "
        f"Write it as {plain_signature(name, function)}."
    )


def values_not_a_list(name: str, values: Any) -> str:
    """The message for ``tasks.event(name, values)`` whose values are not a list.

    Example::

        values_not_a_list("say", "hello")
        # tasks.event('say', 'hello') at robot.py:9 in Speaker.begin: ...
    """
    got = f"{short_repr(values, 40)} is a {type(values).__name__}"
    if isinstance(values, str) and values:
        got += f", so task.val_list[0] would be {values[0]!r}"
    wrapped = (
        f"list({short_repr(values, 40)})"
        if isinstance(values, (tuple, set))
        else (f"[{short_repr(values, 40)}]")
    )
    return (
        f"tasks.event({name!r}, {short_repr(values, 40)}) at {call_site()}: an event's "
        f"values go in a list (its val_list), and {got}. Write "
        f"tasks.event({name!r}, {wrapped})."
    )


def bad_data_key(key: Any, data: Any) -> str:
    """The message for storing under a key that is not a str (often key and data swapped).

    Example::

        bad_data_key(21.5, "temperature")
        # Data stored under the key 21.5 at robot.py:9 in Thermometer.loop: a data key ...
    """
    if isinstance(data, str):
        fix = (
            f"The key and the data look swapped: write store_data({data!r}, {short_repr(key, 40)})."
        )
    else:
        fix = "Write store_data(key, data) with a key such as 'depth_m'."
    return (
        f"Data stored under the key {short_repr(key, 40)} at {call_site()}: a data key "
        f"must be a str, and {short_repr(key, 40)} is a {type(key).__name__} (the data "
        f"is {short_repr(data, 40)}). {fix}"
    )


def page_as_data(key: Any) -> str:
    """The message for storing a whole `Page` as the data of another page.

    Example::

        page_as_data("depth")
        # Data stored under 'depth' at robot.py:9 in Smoother.smooth is a whole Page ...
    """
    return (
        f"Data stored under {key!r} at {call_site()} is a whole Page (as a handler "
        "gets it in task.val_list), so readers of "
        f"{key!r} would get a Page inside a Page. Store its value, page.data "
        "(e.g. task.val_list[0].data), or pass the page on as it is with "
        "tasks.store_page(page)."
    )
