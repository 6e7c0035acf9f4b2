"""`check_component`: read a student's component class once for silent mistakes.

The node reads each student class once, when its first component is added
(docs/errors.md, 15): a name SNR uses (``self.state`` in a loop, ``self.wait_s =
0.5``), a near miss of a name SNR reads (``self.task_handler``) and an ``async
def`` hook are errors in DEBUG and TEST; work built and dropped, a hook's
return nobody reads and a hook SNR never calls (``def terminte``) are DEBUG
warnings. A class whose source cannot be read is checked only for what its
``__init__`` set.

Example::

    check_component(diver, warn=node.log.warning)   # may raise ComponentError
"""

from __future__ import annotations

import ast
import inspect
from typing import Any, Callable, Dict, Iterator, List, Optional, Set, Tuple

from snr.core.checks.error_text import closest_match
from snr.core.checks.handler_checks import async_text
from snr.core.checks.student_code import (
    describe_callable,
    describe_class,
    is_snr,
    source_block,
    source_node,
    walk_own,
)
from snr.core.endpoint import Endpoint
from snr.core.loop import LoopState, ThreadLoop
from snr.prelude import AbstractComponent, AbstractEndpoint, AbstractLoop, ComponentError

__all__ = ["check_component"]

_MAY_SET = {"name", "task_handlers", "max_tick_rate_hz", "terminate_reason"}
_HOOKS: Dict[type, Tuple[str, ...]] = {
    Endpoint: ("begin", "halt", "terminate"),
    ThreadLoop: ("begin", "setup", "loop", "halt", "terminate"),
}
# Instance attributes SNR sets itself (not visible on the class); "state" on a loop only.
_SET_BY_SNR = {
    "parent": "the node it belongs to",
    "factory": "the factory that built it",
    "state": "the loop's state (LoopState.NEW, RUNNING or STOPPED), which SNR sets as the "
    "loop starts and stops, so your value is overwritten",
}
_TASK_BUILDERS = {"event", "store_data", "store_page", "terminate", "process_data"}
_TASK_BUILDERS |= {"reload_component", "add_component", "remove_component"}
# task_store_data and task_store_page: the thesis's names (listing 6.3).
_SELF_BUILDERS = {
    "page",
    "store_data_task",
    "store_page_task",
    "task_store_data",
    "task_store_page",
}

_NEAR_MISS = 0.8  # closest_match's cutoff for a name SNR uses
# Names SNR reads: when SNR's stays unset, the type of a value meant for it, what happens.
_READ_BY_SNR: Dict[str, Tuple[Callable[[AbstractComponent], bool], Tuple[type, ...], str]] = {
    "task_handlers": (
        lambda component: not component.task_handlers,
        (dict,),
        "stays empty, so none of its handlers ever runs",
    ),
    "max_tick_rate_hz": (
        lambda component: getattr(component, "max_tick_rate_hz", 1) == 0,
        (int, float),
        "stays 0, so loop() runs again the moment it returns",
    ),
}

_checked: Dict[type, List[Tuple[str, bool]]] = {}  # class -> [(message, is_error)]


def _framework_names(kind: type) -> Dict[str, str]:
    """Each name SNR uses on ``kind``, said: "ThreadLoop's method wait_s()"."""
    names: Dict[str, str] = {}
    for base in filter(is_snr, reversed(kind.__mro__)):
        for name, value in vars(base).items():
            if name.startswith("_") or name in _MAY_SET:
                continue
            if isinstance(value, property):
                names[name] = f"{kind.__name__}'s property {name}"
            elif callable(value) or isinstance(value, (staticmethod, classmethod)):
                names[name] = f"{kind.__name__}'s method {name}()"
    for name, what in _SET_BY_SNR.items():
        if name != "state" or kind is ThreadLoop:
            names[name] = f"{kind.__name__}'s {name}, {what}"
    return names


def check_component(
    component: AbstractComponent,
    warn: Optional[Callable[[str], None]] = None,
) -> None:
    """Raise a ComponentError for a name collision; pass silent mistakes to ``warn`` (DEBUG).

    Example::

        check_component(component, node.log.warning)
    """
    cls = type(component)
    if is_snr(cls) or not isinstance(component, (AbstractLoop, AbstractEndpoint)):
        return
    kind: type = ThreadLoop if isinstance(component, AbstractLoop) else Endpoint
    names = _framework_names(kind)
    first_time = cls not in _checked
    if first_time:
        if len(_checked) >= 1000:
            _checked.clear()
        _checked[cls] = [m for c, tree in _sources(cls) for m in _read_class(c, tree, kind, names)]
    for message, is_error in _checked[cls]:
        if is_error:
            raise ComponentError(message)
    _check_instance(component, kind, names)
    if warn is not None and first_time:
        for message, _ in _checked[cls]:
            warn(message)  # warnings only: the errors were raised above


def _check_instance(component: AbstractComponent, kind: type, names: Dict[str, str]) -> None:
    """Mistakes seen in the built object (a class's source may be unreadable)."""
    cls = type(component)
    # ``self.task_handler = {...}`` while task_handlers stays empty: raise, at the line.
    unset = [name for name, (is_unset, _, _) in _READ_BY_SNR.items() if is_unset(component)]
    for attr, value in vars(component).items() if unset else ():
        if attr.startswith("_") or attr in names or attr in _MAY_SET:
            continue
        guess = closest_match(attr, unset, cutoff=_NEAR_MISS)
        if guess is not None and isinstance(value, _READ_BY_SNR[guess][1]):
            raise ComponentError(
                f"{describe_class(cls)} sets self.{attr}, but SNR reads self.{guess}, which "
                f"{_READ_BY_SNR[guess][2]}. Did you mean self.{guess}? Rename it: "
                f"`self.{guess} = ...`.{_assignment(cls, attr)}"
            )
    for hook in _HOOKS[kind]:
        method = getattr(component, hook, None)
        if inspect.iscoroutinefunction(method):
            raise ComponentError(async_text(describe_callable(method), method))
    taken = [n for n in vars(component) if n in names and n not in _SET_BY_SNR]
    if kind is ThreadLoop and not isinstance(
        vars(component).get("state", LoopState.NEW), LoopState
    ):
        taken.append("state")
    if taken:
        raise ComponentError(_collision(cls, taken[0], names[taken[0]], ""))


def _collision(cls: type, name: str, what: str, where: str) -> str:
    return (
        f"{describe_class(cls)} uses the name {name!r} for its own value, but {name!r} is "
        f"already {what}. Two things cannot share a name: SNR or your code would get the "
        f"wrong one. Use another name, e.g. self.{cls.__name__.lower()}_{name}.{where}"
    )


def _sources(cls: type) -> Iterator[Tuple[type, ast.ClassDef]]:
    """The student's classes among ``cls`` and its bases whose source can be read, with it."""
    for base in cls.__mro__:
        tree = None if is_snr(base) or base is object else source_node(base)
        if isinstance(tree, ast.ClassDef) and inspect.getsourcefile(base) is not None:
            yield base, tree


def _at(cls: type, method: str, line: int) -> str:
    """A line of ``cls``'s ``method`` as a `source_block`, on a line of its own."""
    return "\n" + source_block(inspect.getsourcefile(cls) or "", line, f"{cls.__name__}.{method}")


def _methods(tree: ast.ClassDef) -> List[ast.FunctionDef]:
    return [item for item in tree.body if isinstance(item, ast.FunctionDef)]


def _is_self(node: ast.AST) -> bool:
    return isinstance(node, ast.Name) and node.id == "self"


def _attributes_set(node: ast.AST) -> List[ast.Attribute]:
    """The ``x.name`` an assignment sets (``x.name = ...``, ``+=``, annotated)."""
    targets: List[ast.expr] = list(node.targets) if isinstance(node, ast.Assign) else []
    if isinstance(node, (ast.AugAssign, ast.AnnAssign)):
        targets = [node.target]
    return [target for target in targets if isinstance(target, ast.Attribute)]


def _assignment(cls: type, attr: str) -> str:
    """The line of the student's class that assigns ``self.attr``, as a block, or ""."""
    for owner, tree in _sources(cls):
        for method in _methods(tree):
            for node in walk_own(method):
                for target in _attributes_set(node):
                    if target.attr == attr:
                        return _at(owner, method.name, target.lineno)
    return ""


def _read_class(
    cls: type, tree: ast.ClassDef, kind: type, names: Dict[str, str]
) -> List[Tuple[str, bool]]:
    """(message, is_error) for every mistake in one of the student's classes: errors first."""
    hooks = _HOOKS[kind]
    errors: List[str] = []
    dropped: List[str] = []
    ignored: List[str] = []
    for method in _methods(tree):
        name = method.name
        if name in names and name not in hooks:
            errors.append(_collision(cls, name, names[name], _at(cls, name, method.lineno)))
        for node in walk_own(method):
            for target in _attributes_set(node):
                if target.attr in names and _is_self(target.value):
                    where = _at(cls, name, target.lineno)
                    errors.append(_collision(cls, target.attr, names[target.attr], where))
            if isinstance(node, ast.Expr) and isinstance(node.value, ast.Call):
                built, code = _built(node.value.func), ast.unparse(node.value)
                if built == "page":
                    what, until, use = "a page", "stored", f"`self.store_page({code})`"
                elif built is None:
                    continue
                else:
                    what, until = "a task", "returned from a handler or scheduled"
                    use = f"`self.schedule({code})`"
                    if kind is not ThreadLoop:
                        use = f"`return {code}` (from a handler) or {use}"
                dropped.append(
                    f"{cls.__name__}.{name} builds {what}, `{code}`, and drops it: nothing "
                    f"happens until it is {until}. Write {use}.{_at(cls, name, node.lineno)}"
                )
            if isinstance(node, ast.Return) and name in hooks and node.value is not None:
                if isinstance(node.value, ast.Constant) and node.value.value is None:
                    continue
                code = ast.unparse(node.value)
                ignored.append(
                    f"{cls.__name__}.{name}() returns `{code}`, but SNR does not use what "
                    f"{name}() returns: it is dropped. To run a task, schedule it: "
                    f"`self.schedule({code})`.{_at(cls, name, node.lineno)}"
                )
    warnings = dropped + ignored + list(_uncalled_hooks(cls, tree, kind))
    return [(e, True) for e in errors] + [(w, False) for w in warnings]


def _built(func: ast.expr) -> Optional[str]:
    """What a call builds without doing anything with it: ``"task"``, ``"page"``, or None."""
    if isinstance(func, ast.Name) and func.id == "Task":
        return "task"
    if not isinstance(func, ast.Attribute):
        return None
    owner = func.value
    if isinstance(owner, ast.Name) and owner.id == "tasks" and func.attr in _TASK_BUILDERS:
        return "task"
    on_self = _is_self(owner) or (
        isinstance(owner, ast.Attribute) and owner.attr == "parent" and _is_self(owner.value)
    )
    if on_self and func.attr in _SELF_BUILDERS:
        return "page" if func.attr == "page" else "task"
    return None


def _uncalled_hooks(cls: type, tree: ast.ClassDef, kind: type) -> Iterator[str]:
    hooks = _HOOKS[kind]
    # Every x.name, bare name and string in the class: the methods it calls or registers.
    used: Set[Any] = set()
    for node in ast.walk(tree):
        used.add(
            getattr(node, "attr", None) or getattr(node, "id", None) or getattr(node, "value", None)
        )
    for method in _methods(tree):
        name = method.name
        if name.startswith("_") or name in hooks or name in used:
            continue
        said = f"{cls.__name__}.{name}() is never called:"
        where = _at(cls, name, method.lineno)
        if kind is Endpoint and name == "setup":
            fix = "SNR calls begin() when the node starts: rename it to begin."
            yield f"{said} an Endpoint has no setup(). {fix}{where}"
        elif kind is Endpoint and name == "loop":
            fix = "make the class a ThreadLoop (with a LoopFactory) to run it again and again."
            yield f"{said} an Endpoint has no loop(). Only a ThreadLoop has a loop(): {fix}{where}"
        else:  # "begining", "halting": still that hook
            guess = closest_match(name, hooks, _NEAR_MISS)
            guess = guess or closest_match(name.removesuffix("ing"), hooks, _NEAR_MISS)
            if guess is not None:
                yield (
                    f"{said} SNR calls {guess}(), and nothing in the class calls {name}(). "
                    f"Did you mean {guess}?{where}"
                )
