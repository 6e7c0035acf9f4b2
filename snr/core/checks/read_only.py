"""Read-only page data (DEBUG and TEST): a page's list or dict cannot be changed in place.

A page's data is one object, shared by every handler of its key and the
datastore: changing it in place would change it for all of them, in silence.
So outside DEPLOYED the node stores a read-only copy: lists become
`ReadOnlyList`, dicts `ReadOnlyDict`, nested ones too. They still equal,
print and serialise as the plain list or dict; their changing methods refuse,
saying to copy first (docs/performance.md, "Page data that cannot be changed
in place").

Example::

    data = freeze([1.0, 2.0], "scan")
    data == [1.0, 2.0]      # True
    data.append(3.0)        # TypeError: The data of page 'scan' is read-only ...
    mine = list(data)       # a copy of your own: change it, store it
"""

from __future__ import annotations

import copy
from typing import Any, Callable, Dict, List, NoReturn, Tuple

from snr.prelude import DataKey

__all__ = ["ReadOnlyDict", "ReadOnlyList", "freeze"]

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

    Anything else, and whatever is nested deeper than `MAX_DEPTH`, comes back as it is.

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
