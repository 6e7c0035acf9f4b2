"""Which data keys a component stores and reads, found in its source code.

The thesis API has no list of the keys a component publishes, so the graph
reads the component's class (and its bases outside SNR's core) with `ast`
and looks at the calls that store or read pages:

* stores: ``store_data(KEY, ...)``, ``store_data_task(KEY, ...)``,
  ``task_store_data(KEY, ...)``, ``page(KEY, ...)``, ``Page(KEY, ...)``;
* reads: ``get_data(KEY)``, ``get_page(KEY)``.

``KEY`` is found when it is a string (``"depth"``) or an attribute of the
component (``self.output``, ``self.link.receive_key``): the attribute's value
is read from the built component. Any other ``KEY`` (a variable, an
f-string) is computed while the node runs; the call is noted as *unresolved*,
so the graph can say "stores keys computed at run time; name them in
``produces``". A ``store_page(page)`` of a page made elsewhere is unresolved
too. Each source file is parsed once (a few milliseconds), and each class's
result is cached.

Example::

    uses = key_uses(SensorReader)
    resolve(uses, reader)   # KeysInCode(stores={'depth_raw', ...}, reads={...}, unresolved=[...])
"""

from __future__ import annotations

import ast
import inspect
import linecache
import os
import weakref
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Set, Tuple, Union

from snr.core.checks.student_code import parse_source
from snr.prelude import DataKey

__all__ = ["KeyUse", "KeysInCode", "key_uses", "resolve"]

_STORE_CALLS = frozenset({"store_data", "store_data_task", "task_store_data", "page", "Page"})
_READ_CALLS = frozenset({"get_data", "get_page"})
# These store a page built somewhere else.
_OPAQUE_STORE_CALLS = frozenset({"store_page", "store_page_task", "task_store_page"})
_SNR_MACHINERY = ("snr.core", "snr.prelude")  # the base classes: not a component's own keys

# How a key is written in the call: a string, a path of attributes from
# ``self`` (("output",) for self.output), or None (computed at run time).
KeyExpr = Union[str, Tuple[str, ...], None]


@dataclass(frozen=True)
class KeyUse:
    """One call in a class that stores or reads a data key.

    Example::

        KeyUse("store", ("output",), "InputProcessor.process", "store_data_task(self.output)")
    """

    kind: str  # "store" or "read"
    key: KeyExpr
    where: str  # "Class.method"
    text: str  # the call's first argument as written, for messages


@dataclass
class KeysInCode:
    """The keys a built component stores and reads, as far as its code says.

    Example::

        found = resolve(key_uses(type(component)), component)
        found.stores, found.reads, found.unresolved
    """

    stores: Set[DataKey] = field(default_factory=set)
    reads: Set[DataKey] = field(default_factory=set)
    unresolved: List[str] = field(default_factory=list)


# Per class; weak, so the classes a hot reload replaces are not kept alive.
_cache: weakref.WeakKeyDictionary[type, Tuple[KeyUse, ...]] = weakref.WeakKeyDictionary()


def key_uses(cls: type) -> Tuple[KeyUse, ...]:
    """Every store or read call in ``cls`` and its bases (SNR's machinery excluded).

    Classes whose source cannot be read (built in, made at run time) add
    nothing. The answer is cached per class.
    """
    cached = _cache.get(cls)
    if cached is not None:
        return cached
    uses: List[KeyUse] = []
    for klass in cls.__mro__:
        module = getattr(klass, "__module__", "") or ""
        if klass is object or module.startswith(_SNR_MACHINERY) or module == "abc":
            continue
        uses.extend(_uses_in_class(klass))
    result = tuple(uses)
    _cache[cls] = result
    return result


def resolve(uses: Tuple[KeyUse, ...], component: Any) -> KeysInCode:
    """The keys ``uses`` name for this ``component`` (attributes are read from it)."""
    found = KeysInCode()
    for use in uses:
        status, key = _value_of(use.key, component)
        if status == _NOT_SET:
            continue  # e.g. self.output is None: this component stores nothing there
        if key is None:
            if use.kind == "store":
                found.unresolved.append(f"{use.where}: {use.text}")
            continue
        (found.stores if use.kind == "store" else found.reads).add(key)
    return found


_UNKNOWN = "unknown"  # the key is computed while the node runs
_NOT_SET = "not set"  # an attribute key that is None: the call is skipped while running too


def _value_of(expr: KeyExpr, component: Any) -> Tuple[str, Optional[DataKey]]:
    """``("key", KEY)``, or `_UNKNOWN`/`_NOT_SET` and None."""
    if expr is None:
        return _UNKNOWN, None
    if isinstance(expr, str):
        return "key", expr
    value: Any = component
    for name in expr:
        try:
            value = getattr(value, name)
        except Exception:  # a property may raise anything: then the key is unknown
            return _UNKNOWN, None
    if value is None:
        return _NOT_SET, None
    return ("key", value) if isinstance(value, str) and value else (_UNKNOWN, None)


def _uses_in_class(klass: type) -> List[KeyUse]:
    class_node = _class_node(klass)
    if class_node is None:
        return []
    uses: List[KeyUse] = []
    for node in class_node.body:
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        where = f"{klass.__name__}.{node.name}"
        for call in ast.walk(node):
            if isinstance(call, ast.Call):
                use = _use_of(call, where)
                if use is not None:
                    uses.append(use)
    return uses


_trees: Dict[Tuple[str, float], Optional[ast.Module]] = {}  # (file, its mtime) -> tree


def _class_node(klass: type) -> Optional[ast.ClassDef]:
    """The class's definition in its module's syntax tree (each file is parsed once).

    (``inspect.getsource`` would parse the whole module again for every class.)
    """
    filename = _source_file(klass)
    if filename is None:
        return None
    try:
        version = (filename, os.stat(filename).st_mtime)
    except OSError:
        return None
    if version not in _trees:  # new, or edited since (a hot reload): read it again
        linecache.checkcache(filename)
        try:
            _trees[version] = parse_source("".join(linecache.getlines(filename)))
        except (SyntaxError, ValueError):
            _trees[version] = None
    tree = _trees[version]
    if tree is None:
        return None
    candidates = [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.ClassDef) and node.name == klass.__name__
    ]
    if len(candidates) > 1:  # classes of one name in several functions: match a method's line
        lines = {
            code.co_firstlineno
            for value in vars(klass).values()
            for code in [getattr(value, "__code__", None)]
            if code is not None
        }
        candidates = [node for node in candidates if _method_lines(node) & lines]
    return candidates[0] if len(candidates) == 1 else None


def _source_file(klass: type) -> Optional[str]:
    """The file that defines ``klass``, from its methods' code when it has some.

    Better than ``inspect.getsourcefile``, which looks the module up by name:
    a class of a program run as ``__main__`` (as ``python -m snr graph``
    runs it) would be looked for in the wrong file.
    """
    for value in vars(klass).values():
        code = getattr(value, "__code__", None)
        if code is not None and os.path.isfile(code.co_filename):
            return str(code.co_filename)
    try:
        return inspect.getsourcefile(klass)
    except TypeError:  # a built-in class
        return None


def _method_lines(node: ast.ClassDef) -> Set[int]:
    lines: Set[int] = set()
    for item in node.body:
        if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
            lines.add(item.lineno)
            lines.update(decorator.lineno for decorator in item.decorator_list)
    return lines


def _use_of(call: ast.Call, where: str) -> Optional[KeyUse]:
    name = _called_name(call.func)
    if name in _STORE_CALLS or name in _READ_CALLS:
        argument = _key_argument(call)
        if argument is None:
            return None
        kind = "store" if name in _STORE_CALLS else "read"
        return KeyUse(kind, _key_expr(argument), where, f"{name}({ast.unparse(argument)})")
    if name in _OPAQUE_STORE_CALLS and call.args:
        page = call.args[0]
        if isinstance(page, ast.Call) and _called_name(page.func) in _STORE_CALLS:
            return None  # store_page(self.page("key", ...)): the inner call names the key
        return KeyUse("store", None, where, f"{name}({ast.unparse(page)})")
    return None


def _called_name(func: ast.expr) -> Optional[str]:
    if isinstance(func, ast.Attribute):
        return func.attr
    if isinstance(func, ast.Name):
        return func.id
    return None


def _key_argument(call: ast.Call) -> Optional[ast.expr]:
    if call.args and not isinstance(call.args[0], ast.Starred):
        return call.args[0]
    for keyword in call.keywords:
        if keyword.arg == "key":
            return keyword.value
    return None


def _key_expr(argument: ast.expr) -> KeyExpr:
    if isinstance(argument, ast.Constant):
        return argument.value if isinstance(argument.value, str) else None
    path: List[str] = []
    node: ast.expr = argument
    while isinstance(node, ast.Attribute):
        path.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name) and node.id == "self" and path:
        return tuple(reversed(path))
    return None
