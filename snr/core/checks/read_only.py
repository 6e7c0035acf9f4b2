"""What components may read but not change: their node's datastore, and page data.

``node.datastore`` (`NodeDatastore`) is a live view of the node's ``node.pages``
that refuses every change, naming ``store_data`` (docs/design.md, "Only the
node writes its datastore").

Read-only page data (DEBUG and TEST): a page's list or dict cannot be changed
in place. A page's data is one object, shared by every handler of its key, the
datastore and whoever stored it. A handler that appends to
``task.val_list[0].data`` would change the page for all of them, in silence.
So in DEBUG and TEST modes the node stores a read-only copy of the data:
lists become `ReadOnlyList`, dicts `ReadOnlyDict`, nested ones too (tuples
holding them are rebuilt). Both are subclasses, so they still equal, print,
``isinstance``-check and serialise as the plain list or dict; only their
changing methods refuse, at the student's line, with the fix: copy it first.

Why once, at store, and not a copy per handler: ``docs/performance.md``,
"Page data that cannot be changed in place". DEPLOYED passes data as it is: a
program that ran in DEBUG without tripping this does not change page data.

Other objects (a set, a NumPy array, a class of the student's) are passed as
they are: JSON pages hold only lists and dicts.

Example::

    data = freeze([1.0, 2.0], "scan")
    data == [1.0, 2.0]      # True
    data.append(3.0)        # TypeError: The data of page 'scan' is read-only ...
    mine = list(data)       # a copy of your own: change it, store it
"""

from __future__ import annotations

import copy
import threading
from typing import Any, Callable, Dict, Iterator, List, Mapping, NoReturn, Optional, Tuple

from snr.core.task_queue import TaskQueue
from snr.prelude import DataKey, Datastore, DatastoreWriteError, Page
from snr.prelude.student_code import caller_location

__all__ = ["NodeDatastore", "ReadOnlyDict", "ReadOnlyList", "freeze"]

MAX_DEPTH = 100
"""Lists and dicts nested deeper than this are left as they are (JSON pages are shallower)."""

# Types whose values cannot be changed in place: passed as they are.
_IMMUTABLE = frozenset({int, float, str, bool, bytes, type(None), complex})


def _refusing(kind: str, what: str, instead: str = "") -> Callable[..., NoReturn]:
    """A method that refuses ``what`` on a read-only ``kind``, saying to copy."""

    def refuse(self: Any, *args: Any, **kwargs: Any) -> NoReturn:
        key = getattr(self, "key", "?")  # '?' for one made by hand, not by freeze
        raise TypeError(
            f"The data of page {key!r} is read-only: {what} would change it for every "
            f"handler of {key!r} and for the datastore, which all share this one {kind}. "
            f"{instead}{'Otherwise c' if instead else 'C'}opy it and change the copy: "
            f"mine = {kind}(task.val_list[0].data) in a handler, or "
            f"mine = {kind}(self.get_data({key!r})) elsewhere; "
            f"store_data({key!r}, mine) then shares it. DEBUG and TEST modes keep page "
            "data read-only; DEPLOYED does not check."
        )

    refuse.__doc__ = f"Refused: {what} would change shared page data."
    return refuse


class ReadOnlyList(List[Any]):
    """A page's list, read-only: it equals and reads as a list; changing it raises.

    Example::

        data = freeze([1.0, 2.0], "scan")       # a ReadOnlyList
        data[0], len(data), data == [1.0, 2.0]   # 1.0, 2, True
        data.append(3.0)   # TypeError naming 'scan' and how to copy it
    """

    __slots__ = ("key",)  # the page's key, for the message (set by `freeze`)

    append = _refusing("list", ".append()")
    extend = _refusing("list", ".extend()")
    insert = _refusing("list", ".insert()")
    pop = _refusing("list", ".pop()")
    remove = _refusing("list", ".remove()")
    clear = _refusing("list", ".clear()")
    sort = _refusing("list", ".sort()", "sorted(data) gives a sorted copy. ")
    reverse = _refusing("list", ".reverse()", "data[::-1] gives a reversed copy. ")
    __setitem__ = _refusing("list", "setting an item")
    __delitem__ = _refusing("list", "del")
    __iadd__ = _refusing("list", "+=")
    __imul__ = _refusing("list", "*=")

    # Pickled and copied as a plain list: a copy is the student's own to change.
    def __reduce__(self) -> Tuple[Any, ...]:
        return (list, (list(self),))

    def __deepcopy__(self, memo: Dict[int, Any]) -> List[Any]:
        return [copy.deepcopy(item, memo) for item in self]


class ReadOnlyDict(Dict[Any, Any]):
    """A page's dict, read-only: it equals and reads as a dict; changing it raises.

    Example::

        data = freeze({"x": 1.0}, "pose")       # a ReadOnlyDict
        data["x"], data == {"x": 1.0}    # 1.0, True
        data["y"] = 2.0   # TypeError naming 'pose' and how to copy it
    """

    __slots__ = ("key",)  # the page's key, for the message (set by `freeze`)

    update = _refusing("dict", ".update()")
    pop = _refusing("dict", ".pop()")
    popitem = _refusing("dict", ".popitem()")
    clear = _refusing("dict", ".clear()")
    setdefault = _refusing("dict", ".setdefault()")
    __setitem__ = _refusing("dict", "setting an item")
    __delitem__ = _refusing("dict", "del")
    __ior__ = _refusing("dict", "|=")

    def __reduce__(self) -> Tuple[Any, ...]:
        return (dict, (dict(self),))

    def __deepcopy__(self, memo: Dict[int, Any]) -> Dict[Any, Any]:
        return {key: copy.deepcopy(value, memo) for key, value in self.items()}


def freeze(data: Any, key: DataKey, depth: int = 0) -> Any:
    """``data`` with every list and dict in it read-only (a copy), for page ``key``.

    Values that cannot change (numbers, strings, None) and objects that are not
    lists, dicts or tuples come back as they are, and so does whatever is nested
    deeper than `MAX_DEPTH` (data that contains itself is endlessly deep). Nested
    values' types are checked in C first (``issuperset(map(type, ...))``), so a flat
    list of numbers costs one copy.

    Example::

        freeze({"pose": [1.0, 2.0]}, "robot")   # ReadOnlyDict({'pose': ReadOnlyList([1.0, 2.0])})
        freeze(3.2, "depth")                    # 3.2
    """
    kind = type(data)
    if kind in _IMMUTABLE or depth > MAX_DEPTH:
        return data
    frozen: Any
    if kind is list or kind is ReadOnlyList:  # a flat one is checked and copied in C
        flat = _IMMUTABLE.issuperset(map(type, data))
        frozen = ReadOnlyList(data if flat else [freeze(item, key, depth + 1) for item in data])
    elif kind is dict or kind is ReadOnlyDict:
        if _IMMUTABLE.issuperset(map(type, data.values())):
            frozen = ReadOnlyDict(data)
        else:
            frozen = ReadOnlyDict({k: freeze(v, key, depth + 1) for k, v in data.items()})
    elif kind is tuple and not _IMMUTABLE.issuperset(map(type, data)):
        return tuple(freeze(item, key, depth + 1) for item in data)
    else:
        return data
    frozen.key = key
    return frozen


def _refused(what: str, names_key: bool = False) -> Callable[..., NoReturn]:
    """A method that refuses ``what``, naming the key it was given when ``names_key``."""

    def refuse(self: NodeDatastore, *args: Any, **kwargs: Any) -> NoReturn:
        key = args[0] if names_key and args else None
        name = "key" if key is None else repr(key)
        if self.queue is not None and threading.get_ident() == self.queue.owner_thread:
            how = (
                f"call self.store_data({name}, value), or return "
                f"self.store_data_task({name}, value) from a handler"
            )
        else:  # a loop's thread, or before the node runs
            how = (
                f"call self.store_data({name}, value); from a loop's thread it is also the "
                "thread-safe way, as it hands the page to the node's thread"
            )
        raise DatastoreWriteError(
            f"Only node {self.role!r} writes its datastore, so {what.format(key=repr(key))} at "
            f"{caller_location()} was refused: the node keeps a Page (data, time, origin) "
            f"under each key and tells the key's handlers. To store a value, {how}. "
            f"Read it back with self.get_data({name})."
        )

    refuse.__doc__ = "Refused: the node alone writes its datastore."
    return refuse


class NodeDatastore(Mapping[DataKey, Page]):
    """A live, read-only view of a node's pages that refuses every change, naming store_data.

    Example::

        store = NodeDatastore({}, "robot")
        store.get("depth")        # None: reads as a dict
        store.pop("depth")        # DatastoreWriteError naming store_data
    """

    __slots__ = ("_pages", "queue", "role")

    def __init__(self, pages: Datastore, role: str, queue: Optional[TaskQueue] = None) -> None:
        self._pages = pages
        self.role = role
        self.queue = queue  # its owner_thread: the node's thread, once the node runs

    def __getitem__(self, key: DataKey) -> Page:
        page = self._pages.get(key)
        if page is None:
            raise KeyError(key)
        return page

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self._pages.get(key) is not None

    def __iter__(self) -> Iterator[DataKey]:
        return iter(self._pages)

    def __len__(self) -> int:
        return len(self._pages)

    def __repr__(self) -> str:
        return repr(self.copy())

    def copy(self) -> Dict[DataKey, Page]:
        """A plain dict of the pages now, the caller's own to change."""
        pages = self._pages  # list(): the keys now, as the node may store more
        return {key: page for key in list(pages) if (page := pages.get(key)) is not None}

    # Every way to change a dict; "{key}": the key given, in the message.
    __setitem__ = _refused("datastore[{key}] = value", names_key=True)
    __delitem__ = _refused("del datastore[{key}]", names_key=True)
    __ior__ = _refused("datastore |= other")
    update = _refused("datastore.update()")
    pop = _refused("datastore.pop()", names_key=True)
    popitem = _refused("datastore.popitem()")
    clear = _refused("datastore.clear()")
    setdefault = _refused("datastore.setdefault()", names_key=True)

    def __reduce__(self) -> Tuple[Any, ...]:
        # copy.copy, deepcopy and pickle: a copy is a plain dict, the copier's own.
        return (dict, (self.copy(),))
