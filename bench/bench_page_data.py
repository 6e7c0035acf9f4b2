"""What keeping a page's data from being changed in place would cost, per candidate.

A handler that appends to a page's list changes the page every other handler
and the datastore see. The candidates, each timed on typical page data (a
float, a dict of 3 floats, a list of 100 floats), in ns a call net of a bare
call:

* **deepcopy**: every handler gets ``copy.deepcopy(page.data)`` (sound, per handler);
* **shallow**: every handler gets ``list(data)`` / ``dict(data)`` (per handler;
  nested lists stay shared);
* **freeze**: once, as the page is stored, the data becomes read-only
  containers (list and dict subclasses whose changing methods raise, saying to
  copy), nested ones too: element by element in Python, or with the nested
  values' types checked in C (``set(map(type, data))``) and only mutable ones
  frozen one by one;
* **top level only**: the freeze without looking inside (nested lists stay open).

Run: ``python bench/bench_page_data.py``. The numbers and the decision are in
docs/performance.md ("Page data that cannot be changed in place").
"""

from __future__ import annotations

import copy
import timeit
from typing import Any, Callable, Dict, List, NoReturn

__all__ = ["FrozenDict", "FrozenList", "freeze", "freeze_c", "main", "shallow"]

IMMUTABLE = frozenset({int, float, str, bool, bytes, type(None)})


class FrozenList(list):  # type: ignore[type-arg]
    """A list whose changing methods raise (the candidate's read-only page data).

    Example::

        FrozenList([1.0]).append(2.0)   # TypeError: ... copy it: list(page.data)
    """

    __slots__ = ()

    def _refuse(self, *args: Any, **kwargs: Any) -> NoReturn:
        raise TypeError("page data is read-only: copy it, list(page.data)")

    append = extend = insert = pop = remove = clear = sort = reverse = _refuse
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse


class FrozenDict(dict):  # type: ignore[type-arg]
    """A dict whose changing methods raise (the candidate's read-only page data).

    Example::

        FrozenDict(x=1.0)["y"] = 2.0   # TypeError: ... copy it: dict(page.data)
    """

    __slots__ = ()

    def _refuse(self, *args: Any, **kwargs: Any) -> NoReturn:
        raise TypeError("page data is read-only: copy it, dict(page.data)")

    update = pop = popitem = clear = setdefault = _refuse
    __setitem__ = __delitem__ = __ior__ = _refuse


def freeze(data: Any) -> Any:
    """``data`` as read-only containers, element by element in Python.

    Example::

        freeze([1.0, [2.0]])   # FrozenList([1.0, FrozenList([2.0])])
    """
    kind = type(data)
    if kind in IMMUTABLE:
        return data
    if kind is list:
        return FrozenList([v if type(v) in IMMUTABLE else freeze(v) for v in data])
    if kind is dict:
        return FrozenDict({k: v if type(v) in IMMUTABLE else freeze(v) for k, v in data.items()})
    return data


def freeze_c(data: Any) -> Any:
    """``data`` as read-only containers: a C copy, nested values' types checked in C.

    Example::

        freeze_c({"x": 1.0})   # FrozenDict({'x': 1.0})
    """
    kind = type(data)
    if kind in IMMUTABLE:
        return data
    if kind is list:
        if set(map(type, data)) <= IMMUTABLE:
            return FrozenList(data)
        return FrozenList(map(freeze_c, data))
    if kind is dict:
        if set(map(type, data.values())) <= IMMUTABLE:
            return FrozenDict(data)
        return FrozenDict({k: freeze_c(v) for k, v in data.items()})
    return data


def shallow(data: Any) -> Any:
    """A handler's own copy of the top level of ``data``.

    Example::

        shallow([1.0]) is not shallow([1.0])   # True
    """
    kind = type(data)
    if kind in IMMUTABLE:
        return data
    if kind is list:
        return list(data)
    if kind is dict:
        return dict(data)
    return copy.copy(data)


def top_level(data: Any) -> Any:
    """Only the outer container read-only, by a C copy."""
    kind = type(data)
    if kind is list:
        return FrozenList(data)
    if kind is dict:
        return FrozenDict(data)
    return data


def _ns(function: Callable[[Any], Any], data: Any, number: int = 100_000) -> float:
    """Best of 7 runs, ns a call."""
    return min(timeit.repeat(lambda: function(data), number=number, repeat=7)) / number * 1e9


def main() -> None:
    """Print the table of docs/performance.md."""
    samples: Dict[str, Any] = {
        "a float": 1.5,
        "a dict of 3 floats": {"x": 1.0, "y": 2.0, "z": 3.0},
        "a list of 100 floats": [float(i) for i in range(100)],
    }
    bare = _ns(lambda data: data, 0)
    candidates: List[Callable[[Any], Any]] = [copy.deepcopy, shallow, freeze, freeze_c, top_level]
    print(f"ns a call, net of a bare call ({bare:.0f} ns)")
    print(f"{'data':22}" + "".join(f"{c.__name__:>11}" for c in candidates))
    for name, data in samples.items():
        print(f"{name:22}" + "".join(f"{_ns(c, data) - bare:11.0f}" for c in candidates))


if __name__ == "__main__":
    main()
