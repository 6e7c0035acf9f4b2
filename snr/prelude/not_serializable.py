"""Data that cannot cross between nodes, named by its key, its path and its type.

Pages cross between nodes as JSON. Every way out of a node (comms, recordings,
serial links, the live view, `Page.serialize`) words data JSON cannot hold
with `not_serializable_error`, so the same mistake reads the same wherever it
is found (docs/errors.md section 13).

Example::

    raise not_serializable_error("pose", {"pose": [1, 2, {3}]})
    # NotSerializableError: Cannot send the page stored under 'pose' to another node:
    # data['pose'][2] is a set ({3}), which JSON cannot hold. Send a list instead: ...
"""

from __future__ import annotations

import dataclasses
import enum
import math
from typing import Any, Optional, Set, Tuple

from snr.prelude.error_text import short_repr
from snr.prelude.errors import NotSerializableError

__all__ = ["check_serializable", "not_serializable_error"]

_JSON_SCALARS = (str, int, float, bool, type(None))
_MAX_DEPTH = 100
_KEY_PROBLEM = "key"
_LOOP_PROBLEM = "loop"
_TYPE_PROBLEM = "type"
_NUMBER_PROBLEM = "number"  # NaN or infinity: JSON has no such numbers
_TEXT_PROBLEM = "text"  # a lone surrogate: not Unicode text, UTF-8 cannot hold it
_Found = Tuple[str, Any, str]  # (path, offending value, which problem)


def _scalar_problem(value: Any) -> Optional[str]:
    if isinstance(value, float) and not math.isfinite(value):
        return _NUMBER_PROBLEM
    if isinstance(value, str) and not value.isascii():
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            return _TEXT_PROBLEM
    return None


def _find(value: Any, path: str, open_containers: Set[int], depth: int) -> Optional[_Found]:
    if isinstance(value, _JSON_SCALARS):
        problem = _scalar_problem(value)
        return None if problem is None else (path, value, problem)
    if not isinstance(value, (list, tuple, dict)):
        return path, value, _TYPE_PROBLEM
    if id(value) in open_containers or depth > _MAX_DEPTH:
        return path, value, _LOOP_PROBLEM
    open_containers.add(id(value))
    try:
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, _JSON_SCALARS):
                    return path, key, _KEY_PROBLEM
                key_problem = _scalar_problem(key)
                if key_problem is not None:
                    return (
                        path,
                        key,
                        _KEY_PROBLEM if key_problem == _NUMBER_PROBLEM else key_problem,
                    )
                found = _find(item, f"{path}[{key!r}]", open_containers, depth + 1)
                if found is not None:
                    return found
        else:
            for index, item in enumerate(value):
                found = _find(item, f"{path}[{index}]", open_containers, depth + 1)
                if found is not None:
                    return found
        return None
    finally:
        open_containers.discard(id(value))


def _serializable_hint(value: Any, problem: str) -> str:
    if problem == _LOOP_PROBLEM:
        return "It contains itself (or nests too deep); send a copy without the loop."
    if problem == _KEY_PROBLEM:
        return "Dict keys sent between nodes must be str (or numbers): use str(key)."
    if problem == _NUMBER_PROBLEM:
        return (
            "JSON has no NaN or infinity: send None (or leave the page out) when there is "
            "no valid number, e.g. None if math.isnan(x) else x."
        )
    if problem == _TEXT_PROBLEM:
        return (
            "It holds a lone surrogate, which is not text: decode bytes with "
            "errors='replace', or send them as value.hex()."
        )
    if isinstance(value, (set, frozenset)):
        return "Send a list instead: list(value), or sorted(value) for a stable order."
    if isinstance(value, (bytes, bytearray)):
        return "Send text or numbers instead: value.hex(), or list(value)."
    if isinstance(value, enum.Enum):
        return "Send value.name or value.value instead."
    if isinstance(value, complex):
        return "Send [value.real, value.imag] instead."
    if hasattr(value, "tolist"):
        return "Convert it with value.tolist() (numpy arrays and numbers)."
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return "Convert it with dataclasses.asdict(value)."
    return "Send a dict or list of plain values instead, e.g. built from the object's fields."


def not_serializable_error(
    key: str, data: Any, where: str = "", to: str = "to another node", reason: str = ""
) -> NotSerializableError:
    """A NotSerializableError naming the key, the path inside the data and the type.

    Args:
        key: the data key of the page.
        data: the page's data.
        where: extra context, e.g. ``" by component 'sockets_client'"``.
        to: where the page was going, e.g. ``"to a recording"``.
        reason: what went wrong when no single part of the data is to blame
            (e.g. it nests too deep or is too big).

    Example::

        not_serializable_error("pose", {"pose": [1, 2, {3}]})
        # "Cannot send the page stored under 'pose' to another node: data['pose'][2]
        #  is a set ({3}), which JSON cannot hold. Send a list instead: ..."
    """
    found = _find(data, "data", set(), 0)
    head = f"Cannot send the page stored under {key!r}{where} {to}"
    allowed = (
        "Data sent between nodes may only hold dicts, lists, tuples, str, int, "
        "float, bool and None."
    )
    if found is None:
        why = reason or "it cannot be written as JSON"
        return NotSerializableError(f"{head}: {why}. {allowed}")
    path, bad, problem = found
    if problem == _KEY_PROBLEM:
        what = f"{path} has a key that is a {type(bad).__name__} ({short_repr(bad, 60)})"
    else:
        what = f"{path} is a {type(bad).__name__} ({short_repr(bad, 60)})"
    return NotSerializableError(
        f"{head}: {what}, which JSON cannot hold. {_serializable_hint(bad, problem)} {allowed}"
    )


def check_serializable(key: str, data: Any, to: str = "to another node") -> None:
    """Raise `not_serializable_error`'s error unless ``data`` is plain JSON.

    For writers that would otherwise quietly change the data (a set written
    as a list, NaN written as ``NaN``), such as `Page.serialize`.

    Example::

        check_serializable("pose", {"x": 1.0})     # fine
        check_serializable("pose", {"x": {1.0}})   # NotSerializableError: data['x'] is a set
    """
    if _find(data, "data", set(), 0) is not None:
        raise not_serializable_error(key, data, to=to)
