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
from typing import Callable, Dict, Iterator, List, NamedTuple, Optional, Set, Tuple

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
_TASK_BUILDERS = {
    "event",
    "store_data",
    "store_page",
    "terminate",
    "process_data",
    "reload_component",
    "add_component",
    "remove_component",
}
# task_store_data and task_store_page: the thesis's names (listing 6.3).
_SELF_BUILDERS = {
    "page",
    "store_data_task",
    "store_page_task",
    "task_store_data",
    "task_store_page",
}

_NEAR_MISS = 0.8  # closest_match's cutoff for a name SNR uses
# Names SNR reads: when SNR's stays unset, a value meant for it, what happens.
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
_MAX_CACHED = 1000


def _framework_names(kind: type) -> Dict[str, str]:
    """Each name SNR uses on ``kind``, said: "ThreadLoop's method wait_s()"."""
    names: Dict[str, str] = {}
    for base in reversed(kind.__mro__):
        if not is_snr(base):
            continue
        for name, value in vars(base).items():
            if name.startswith("_") or name in _MAY_SET:
                continue
            if isinstance(value, property):
                names[name] = f"{kind.__name__}'s property {name}"
            elif callable(value) or isinstance(value, (staticmethod, classmethod)):
                names[name] = f"{kind.__name__}'s method {name}()"
    for name, what in _SET_BY_SNR.items():
        if name != "state" or issubclass(kind, ThreadLoop):
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
    first_time = cls not in _checked
    if first_time:
        if len(_checked) >= _MAX_CACHED:
            _checked.clear()
        _checked[cls] = list(_read_class(cls, kind))
    for message, is_error in _checked[cls]:
        if is_error:
            raise ComponentError(message)
    _check_instance(component, kind)
    if warn is not None and first_time:
        for message, is_error in _checked[cls]:
            if not is_error:
                warn(message)


def _check_instance(component: AbstractComponent, kind: type) -> None:
    """Collisions seen in the built object (a class's source may be unreadable)."""
    names = _framework_names(kind)
    _check_near_misses(component, names)
    for hook in _HOOKS[kind]:
        method = getattr(component, hook, None)
        if inspect.iscoroutinefunction(method):
            raise ComponentError(async_text(describe_callable(method), method))
    for name in vars(component):
        if name in names and name not in _SET_BY_SNR:
            raise ComponentError(_collision(type(component), name, names[name], ""))
    if kind is ThreadLoop and not isinstance(
        vars(component).get("state", LoopState.NEW), LoopState
    ):
        raise ComponentError(_collision(type(component), "state", names["state"], ""))


def _check_near_misses(component: AbstractComponent, names: Dict[str, str]) -> None:
    """``self.task_handler = {...}`` while ``task_handlers`` stays empty: raise, at the line."""
    unset = [name for name, (is_unset, _, _) in _READ_BY_SNR.items() if is_unset(component)]
    if not unset:
        return
    for attr, value in vars(component).items():
        if attr.startswith("_") or attr in names or attr in _MAY_SET:
            continue
        guess = closest_match(attr, unset, cutoff=_NEAR_MISS)
        if guess is None or not isinstance(value, _READ_BY_SNR[guess][1]):
            continue
        cls = type(component)
        raise ComponentError(
            f"{describe_class(cls)} sets self.{attr}, but SNR reads self.{guess}, which "
            f"{_READ_BY_SNR[guess][2]}. Did you mean self.{guess}? Rename it: "
            f"`self.{guess} = ...`.{_assignment(cls, attr)}"
        )


def _assignment(cls: type, attr: str) -> str:
    """The line of the student's class that assigns ``self.attr``, as a block, or ""."""
    for source in map(_read_source, cls.__mro__):
        if source is None:
            continue
        for method in source.methods():
            for node in walk_own(method):
                for target in _attributes_set(node):
                    if target.attr == attr:
                        return source.at(method.name, target.lineno)
    return ""


def _collision(cls: type, name: str, what: str, where: str) -> str:
    return (
        f"{describe_class(cls)} uses the name {name!r} for its own value, but {name!r} is "
        f"already {what}. Two things cannot share a name: SNR or your code would get the "
        f"wrong one. Use another name, e.g. self.{cls.__name__.lower()}_{name}.{where}"
    )


class _Source(NamedTuple):
    """One of the student's classes, with its file and its syntax tree."""

    cls: type
    filename: str
    tree: ast.ClassDef

    def methods(self) -> List[ast.FunctionDef]:
        return [item for item in self.tree.body if isinstance(item, ast.FunctionDef)]

    def at(self, method: str, line: int) -> str:
        """A line of ``method`` as a `source_block`, on a line of its own."""
        return "\n" + source_block(self.filename, line, f"{self.cls.__name__}.{method}")


def _read_source(cls: type) -> Optional[_Source]:
    """``cls`` as a `_Source`, or None: SNR's own, or its source cannot be read."""
    if is_snr(cls) or cls is object:
        return None
    try:
        filename = inspect.getsourcefile(cls)
    except (OSError, TypeError):
        return None
    node = source_node(cls)
    if filename is None or not isinstance(node, ast.ClassDef):
        return None
    return _Source(cls, filename, node)


def _read_class(cls: type, kind: type) -> Iterator[Tuple[str, bool]]:
    """(message, is_error) for every mistake in the student's classes of ``cls``."""
    names = _framework_names(kind)
    for source in map(_read_source, cls.__mro__):
        if source is not None:
            yield from _collisions(source, names, _HOOKS[kind])
            yield from _dropped_work(source, kind)
            yield from _ignored_returns(source, _HOOKS[kind])
            yield from _uncalled_hooks(source, kind)


def _is_self(node: ast.AST) -> bool:
    return isinstance(node, ast.Name) and node.id == "self"


def _attributes_set(node: ast.AST) -> List[ast.Attribute]:
    """The ``x.name`` an assignment sets (``x.name = ...``, ``+=``, annotated)."""
    targets: List[ast.expr] = list(node.targets) if isinstance(node, ast.Assign) else []
    if isinstance(node, (ast.AugAssign, ast.AnnAssign)):
        targets = [node.target]
    return [target for target in targets if isinstance(target, ast.Attribute)]


def _collisions(
    source: _Source, names: Dict[str, str], hooks: Tuple[str, ...]
) -> Iterator[Tuple[str, bool]]:
    for method in source.methods():
        if method.name in names and method.name not in hooks:
            where = source.at(method.name, method.lineno)
            yield _collision(source.cls, method.name, names[method.name], where), True
        for node in walk_own(method):
            for target in _attributes_set(node):
                if target.attr in names and _is_self(target.value):
                    where = source.at(method.name, target.lineno)
                    yield _collision(source.cls, target.attr, names[target.attr], where), True


def _dropped_work(source: _Source, kind: type) -> Iterator[Tuple[str, bool]]:
    for method in source.methods():
        for node in walk_own(method):
            if not (isinstance(node, ast.Expr) and isinstance(node.value, ast.Call)):
                continue
            built = _built(node.value.func)
            code = ast.unparse(node.value)
            if built == "page":
                what, until, use = "a page", "stored", f"`self.store_page({code})`"
            elif built is None:
                continue
            else:
                what, until = "a task", "returned from a handler or scheduled"
                use = f"`self.schedule({code})`"
                if kind is not ThreadLoop:
                    use = f"`return {code}` (from a handler) or {use}"
            yield (
                f"{source.cls.__name__}.{method.name} builds {what}, `{code}`, and drops it: "
                f"nothing happens until it is {until}. Write {use}."
                f"{source.at(method.name, node.lineno)}",
                False,
            )


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


def _ignored_returns(source: _Source, hooks: Tuple[str, ...]) -> Iterator[Tuple[str, bool]]:
    for method in source.methods():
        if method.name not in hooks:
            continue
        for node in walk_own(method):
            if not isinstance(node, ast.Return) or node.value is None:
                continue
            if isinstance(node.value, ast.Constant) and node.value.value is None:
                continue
            code = ast.unparse(node.value)
            yield (
                f"{source.cls.__name__}.{method.name}() returns `{code}`, but SNR does not use "
                f"what {method.name}() returns: it is dropped. To run a task, schedule it: "
                f"`self.schedule({code})`.{source.at(method.name, node.lineno)}",
                False,
            )


def _uncalled_hooks(source: _Source, kind: type) -> Iterator[Tuple[str, bool]]:
    hooks = _HOOKS[kind]
    used = _names_used(source.tree)
    cls = source.cls.__name__
    for method in source.methods():
        name = method.name
        if name.startswith("_") or name in hooks or name in used:
            continue
        where = source.at(name, method.lineno)
        if kind is Endpoint and name in ("setup", "loop"):
            fix = (
                "SNR calls begin() when the node starts: rename it to begin."
                if name == "setup"
                else "Only a ThreadLoop has a loop(): make the class a ThreadLoop (with a "
                "LoopFactory) to run it again and again."
            )
            yield (
                f"{cls}.{name}() is never called: an Endpoint has no {name}(). {fix}{where}",
                False,
            )
            continue
        # "begining", "halting": still that hook.
        guess = closest_match(name, hooks, _NEAR_MISS) or closest_match(
            name.removesuffix("ing"), hooks, _NEAR_MISS
        )
        if guess is not None:
            yield (
                f"{cls}.{name}() is never called: SNR calls {guess}(), and "
                f"nothing in the class calls {name}(). Did you mean {guess}?{where}",
                False,
            )


def _names_used(tree: ast.ClassDef) -> Set[str]:
    """Every ``x.name`` and bare name read in the class: methods it calls or registers."""
    used: Set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            used.add(node.attr)
        elif isinstance(node, ast.Name):
            used.add(node.id)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            used.add(node.value)  # getattr(self, "name")
    return used
