"""`check_component`: read a student's component class once for silent mistakes.

Some mistakes in an endpoint or loop raise nothing; the program runs and
does the wrong thing, or waits for its timeout. They can be seen in the
class itself, so the node reads each student class once, when its first
component is added (SNR's own classes are skipped):

* **a name SNR uses** (errors, DEBUG and TEST modes): ``self.state = "diving"``
  in a `ThreadLoop` is overwritten when the loop starts; ``self.wait_s = 0.5``
  or ``self.schedule = [...]`` hides the method SNR calls; ``def log(self)``
  replaces the component's logger. Named at the assignment, with the fix.
* **work built and dropped** (warnings, DEBUG): a statement that only builds
  a task or page, ``tasks.event("surface")`` with no ``return`` or
  ``self.schedule(...)``;
* **a return nobody reads** (warnings, DEBUG): ``begin()``, ``setup()``,
  ``loop()``, ``halt()`` or ``terminate()`` returning a task;
* **a hook SNR never calls** (warnings, DEBUG): ``def setup`` in an
  `Endpoint` (endpoints have ``begin``), ``def terminte`` (misspelt);
* **a near miss of a name SNR reads** (errors, DEBUG and TEST):
  ``self.task_handler = {...}`` or ``self.taskHandlers`` while
  ``task_handlers`` stays empty, ``self.max_tick_rate = 10`` while
  ``max_tick_rate_hz`` stays 0. "Near" is `closest_match` with ``cutoff=0.8``,
  the rule of every "did you mean" hint, made stricter;
* **an ``async def`` hook or loop()** (errors, DEBUG and TEST): SNR calls them
  and never awaits them (an ``async def`` handler is refused in every mode,
  by `check_handler`).

The source is read with `inspect`; a class whose source cannot be read
(typed in a console, shipped as ``.pyc``) is checked only for attributes
set in ``__init__``. Nothing here runs per task.

Example::

    problems = check_component(diver, warn=node.log.warning)   # may raise ComponentError
"""

from __future__ import annotations

import ast
import inspect
import textwrap
from typing import Callable, Dict, Iterator, List, Optional, Set, Tuple

from snr.core.checks.error_text import closest_match
from snr.core.checks.handler_checks import async_text
from snr.core.checks.student_code import (
    describe_callable,
    describe_class,
    parse_source,
    source_block,
)
from snr.core.endpoint import Endpoint
from snr.core.loop import LoopState, ThreadLoop
from snr.prelude import (
    AbstractComponent,
    AbstractEndpoint,
    AbstractLoop,
    ComponentError,
)

__all__ = ["NEAR_MISS", "check_component", "framework_names"]

# Names a student is meant to set or define.
_MAY_SET = {"name", "task_handlers", "max_tick_rate_hz", "terminate_reason"}
_ENDPOINT_HOOKS = ("begin", "halt", "terminate")
_LOOP_HOOKS = ("begin", "setup", "loop", "halt", "terminate")
# Instance attributes SNR sets itself (not visible on the class).
_INSTANCE_NAMES = {"parent": "the node it belongs to", "factory": "the factory that built it"}
_LOOP_INSTANCE_NAMES = {
    "state": "the loop's state (LoopState.NEW, RUNNING or STOPPED), which SNR sets as the "
    "loop starts and stops, so your value is overwritten"
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
_SELF_BUILDERS = {
    "page",
    "store_data_task",
    "store_page_task",
    "task_store_data",  # the thesis's names (listing 6.3) for the two above
    "task_store_page",
}

NEAR_MISS = 0.8  # closest_match's cutoff for a slip of the keys in a name SNR uses
# Names SNR reads: when SNR's stays unset, and what a value meant for it looks like.
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


def framework_names(kind: type) -> Dict[str, str]:
    """What each name SNR uses on an `Endpoint` or `ThreadLoop` is, for messages.

    Example::

        framework_names(ThreadLoop)["wait_s"]   # "ThreadLoop's method wait_s()"
    """
    names: Dict[str, str] = {}
    for base in reversed(kind.__mro__):
        if base.__module__.split(".", 1)[0] != "snr":
            continue
        for name, value in vars(base).items():
            if name.startswith("_") or name in _MAY_SET:
                continue
            if isinstance(value, property):
                names[name] = f"{kind.__name__}'s property {name}"
            elif callable(value) or isinstance(value, (staticmethod, classmethod)):
                names[name] = f"{kind.__name__}'s method {name}()"
    for name, what in _INSTANCE_NAMES.items():
        names[name] = f"{kind.__name__}'s {name}, {what}"
    if issubclass(kind, ThreadLoop):
        for name, what in _LOOP_INSTANCE_NAMES.items():
            names[name] = f"{kind.__name__}'s {name}, {what}"
    return names


def check_component(
    component: AbstractComponent,
    warn: Optional[Callable[[str], None]] = None,
) -> None:
    """Raise a ComponentError for a name collision; pass silent mistakes to ``warn``.

    ``warn`` is None outside DEBUG mode: then only collisions are checked.
    Each class is read once; its warnings are given once.

    Example::

        check_component(component, node.log.warning)
    """
    cls = type(component)
    if cls.__module__.split(".", 1)[0] == "snr":
        return
    kind: type = ThreadLoop if isinstance(component, AbstractLoop) else Endpoint
    if not isinstance(component, (AbstractLoop, AbstractEndpoint)):
        return
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
    """Collisions seen in the built object (for classes whose source is unreadable)."""
    names = framework_names(kind)
    owned = vars(component)
    _check_near_misses(component, names)
    for hook in _LOOP_HOOKS if kind is ThreadLoop else _ENDPOINT_HOOKS:
        method = getattr(component, hook, None)
        if inspect.iscoroutinefunction(method):
            raise ComponentError(async_text(f"{describe_callable(method)}", method))
    for name in owned:
        if name in names and name not in _INSTANCE_NAMES and name not in _LOOP_INSTANCE_NAMES:
            raise ComponentError(_collision(type(component), name, names[name], ""))
    state = owned.get("state", LoopState.NEW)
    if kind is ThreadLoop and not isinstance(state, LoopState):
        raise ComponentError(_collision(type(component), "state", names["state"], ""))


def _check_near_misses(component: AbstractComponent, names: Dict[str, str]) -> None:
    """``self.task_handler = {...}`` while ``task_handlers`` stays empty: raise, at the line."""
    unset = [name for name, (is_unset, _, _) in _READ_BY_SNR.items() if is_unset(component)]
    if not unset:
        return
    for attr, value in vars(component).items():
        if attr.startswith("_") or attr in names or attr in _MAY_SET:
            continue
        guess = closest_match(attr, unset, cutoff=NEAR_MISS)
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
    for own in cls.__mro__:
        found = _class_tree(own) if own.__module__.split(".", 1)[0] != "snr" else None
        if found is None:
            continue
        filename, tree = found
        for method in _methods(tree):
            for node in _walk_own(method):
                for target in _targets(node):
                    if isinstance(target, ast.Attribute) and target.attr == attr:
                        return _block(filename, own, method.name, target.lineno)
    return ""


def _collision(cls: type, name: str, what: str, where: str) -> str:
    # The "Did you mean" comes with a name of the student's own, e.g. self.diver_state.
    mine = f"self.{cls.__name__.lower()}_{name}"
    return (
        f"{describe_class(cls)} uses the name {name!r} for its own value, but {name!r} is "
        f"already {what}. Two things cannot share a name: SNR or your code would get the "
        f"wrong one. Use another name, e.g. {mine}.{where}"
    )


# -- reading the class ------------------------------------------------------------
def _read_class(cls: type, kind: type) -> Iterator[Tuple[str, bool]]:
    """(message, is_error) for every mistake in the student's classes of ``cls``."""
    names = framework_names(kind)
    hooks = _LOOP_HOOKS if kind is ThreadLoop else _ENDPOINT_HOOKS
    for own in cls.__mro__:
        if own.__module__.split(".", 1)[0] == "snr" or own is object:
            continue
        found = _class_tree(own)
        if found is None:
            continue
        filename, tree = found
        yield from _collisions(own, filename, tree, names, hooks)
        yield from _dropped_work(own, filename, tree, kind)
        yield from _ignored_returns(own, filename, tree, hooks)
        yield from _uncalled_hooks(own, filename, tree, kind, hooks)


def _class_tree(cls: type) -> Optional[Tuple[str, ast.ClassDef]]:
    """The file and syntax tree of ``cls``, with the file's line numbers, or None."""
    try:
        filename = inspect.getsourcefile(cls)
        lines, first = inspect.getsourcelines(cls)
    except (OSError, TypeError):
        return None
    if filename is None:
        return None
    try:
        tree = parse_source(textwrap.dedent("".join(lines)))
    except SyntaxError:
        return None
    ast.increment_lineno(tree, first - 1)
    node = tree.body[0] if tree.body else None
    return (filename, node) if isinstance(node, ast.ClassDef) else None


def _methods(tree: ast.ClassDef) -> Iterator[ast.FunctionDef]:
    for item in tree.body:
        if isinstance(item, ast.FunctionDef):
            yield item


def _walk_own(function: ast.AST) -> Iterator[ast.AST]:
    """The nodes of ``function``, not of functions or classes inside it."""
    stack = list(ast.iter_child_nodes(function))
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            stack.extend(ast.iter_child_nodes(node))


def _block(filename: str, cls: type, method: str, line: int) -> str:
    return "\n" + source_block(filename, line, f"{cls.__name__}.{method}")


def _collisions(
    cls: type, filename: str, tree: ast.ClassDef, names: Dict[str, str], hooks: Tuple[str, ...]
) -> Iterator[Tuple[str, bool]]:
    for method in _methods(tree):
        if method.name in names and method.name not in hooks:
            where = _block(filename, cls, method.name, method.lineno)
            yield _collision(cls, method.name, names[method.name], where), True
        for node in _walk_own(method):
            for target in _targets(node):
                if (
                    isinstance(target, ast.Attribute)
                    and isinstance(target.value, ast.Name)
                    and target.value.id == "self"
                    and target.attr in names
                ):
                    where = _block(filename, cls, method.name, target.lineno)
                    yield _collision(cls, target.attr, names[target.attr], where), True


def _targets(node: ast.AST) -> List[ast.expr]:
    if isinstance(node, ast.Assign):
        return list(node.targets)
    if isinstance(node, (ast.AugAssign, ast.AnnAssign)):
        return [node.target]
    return []


def _dropped_work(
    cls: type, filename: str, tree: ast.ClassDef, kind: type
) -> Iterator[Tuple[str, bool]]:
    for method in _methods(tree):
        for node in _walk_own(method):
            if not (isinstance(node, ast.Expr) and isinstance(node.value, ast.Call)):
                continue
            built = _built(node.value.func)
            if built is None:
                continue
            code = ast.unparse(node.value)
            is_page = built == "page"
            if is_page:
                use = f"`self.store_page({code})`"
            elif kind is ThreadLoop:
                use = f"`self.schedule({code})`"
            else:
                use = f"`return {code}` (from a handler) or `self.schedule({code})`"
            what = "a page" if is_page else "a task"
            yield (
                f"{cls.__name__}.{method.name} builds {what}, `{code}`, and drops it: "
                f"nothing happens until it is "
                f"{'stored' if is_page else 'returned from a handler or scheduled'}. "
                f"Write {use}.{_block(filename, cls, method.name, node.lineno)}",
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
    is_self = isinstance(owner, ast.Name) and owner.id == "self"
    is_parent = (
        isinstance(owner, ast.Attribute)
        and owner.attr == "parent"
        and isinstance(owner.value, ast.Name)
        and owner.value.id == "self"
    )
    if (is_self or is_parent) and func.attr in _SELF_BUILDERS:
        return "page" if func.attr == "page" else "task"
    return None


def _ignored_returns(
    cls: type, filename: str, tree: ast.ClassDef, hooks: Tuple[str, ...]
) -> Iterator[Tuple[str, bool]]:
    for method in _methods(tree):
        if method.name not in hooks:
            continue
        for node in _walk_own(method):
            if not isinstance(node, ast.Return) or node.value is None:
                continue
            if isinstance(node.value, ast.Constant) and node.value.value is None:
                continue
            code = ast.unparse(node.value)
            yield (
                f"{cls.__name__}.{method.name}() returns `{code}`, but SNR does not use "
                f"what {method.name}() returns: it is dropped. To run a task, schedule it: "
                f"`self.schedule({code})`."
                f"{_block(filename, cls, method.name, node.lineno)}",
                False,
            )


def _uncalled_hooks(
    cls: type, filename: str, tree: ast.ClassDef, kind: type, hooks: Tuple[str, ...]
) -> Iterator[Tuple[str, bool]]:
    used = _names_used(tree)
    other_kind = {"setup": "begin", "loop": None} if kind is Endpoint else {}
    for method in _methods(tree):
        name = method.name
        if name.startswith("_") or name in hooks or name in used:
            continue
        where = _block(filename, cls, name, method.lineno)
        if name in other_kind:
            instead = other_kind[name]
            fix = (
                "SNR calls begin() when the node starts: rename it to begin."
                if instead
                else "Only a ThreadLoop has a loop(): make the class a ThreadLoop (with a "
                "LoopFactory) to run it again and again."
            )
            yield (
                f"{cls.__name__}.{name}() is never called: an Endpoint has no {name}(). "
                f"{fix}{where}",
                False,
            )
            continue
        # "begining", "halting": a hook's name with "ing" is still that hook.
        guess = closest_match(name, hooks, NEAR_MISS) or closest_match(
            name.removesuffix("ing"), hooks, NEAR_MISS
        )
        if guess is not None:
            yield (
                f"{cls.__name__}.{name}() is never called: SNR calls {guess}(), and "
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
