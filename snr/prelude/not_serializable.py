"""Data that cannot cross between nodes, named by its key, its path and its type.

Every way out of a node words data JSON cannot hold with `not_serializable_error`
(docs/errors.md, 13).

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

from snr.prelude.errors import NotSerializableError
from snr.prelude.student_code import short_repr

__all__ = ["check_serializable", "not_serializable_error"]

_JSON_SCALARS = (str, int, float, bool, type(None))
_MAX_DEPTH = 100
_LOOP_HINT = "It contains itself (or nests too deep); send a copy without the loop."
_KEY_HINT = "Dict keys sent between nodes must be str (or numbers): use str(key)."
_NUMBER_HINT = (  # NaN or infinity: JSON has no such numbers
    "JSON has no NaN or infinity: send None (or leave the page out) when there is "
    "no valid number, e.g. None if math.isnan(x) else x."
)
_TEXT_HINT = (  # a lone surrogate: not Unicode text, UTF-8 cannot hold it
    "It holds a lone surrogate, which is not text: decode bytes with "
    "errors='replace', or send them as value.hex()."
)
_Found = Tuple[str, Any, str]  # (path, offending value, the hint to fix it)


def _scalar_hint(value: Any) -> Optional[str]:
    """The hint for a str or number JSON cannot hold, or None when it can."""
    if isinstance(value, float) and not math.isfinite(value):
        return _NUMBER_HINT
    if isinstance(value, str) and not value.isascii():
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            return _TEXT_HINT
    return None


def _find(value: Any, path: str, open_containers: Set[int], depth: int) -> Optional[_Found]:
    """The first part of ``value`` JSON cannot hold, as (path, part, hint), or None."""
    if isinstance(value, _JSON_SCALARS):
        hint = _scalar_hint(value)
        return None if hint is None else (path, value, hint)
    if not isinstance(value, (list, tuple, dict)):
        return path, value, _type_hint(value)
    if id(value) in open_containers or depth > _MAX_DEPTH:
        return path, value, _LOOP_HINT
    open_containers.add(id(value))
    try:
        pairs = value.items() if isinstance(value, dict) else enumerate(value)
        for key, item in pairs:
            if isinstance(value, dict):  # a key JSON cannot hold; a NaN key gets the key hint
                hint = _scalar_hint(key) if isinstance(key, _JSON_SCALARS) else _KEY_HINT
                if hint is not None:
                    return path, key, _KEY_HINT if hint is _NUMBER_HINT else hint
            found = _find(item, f"{path}[{key!r}]", open_containers, depth + 1)
            if found is not None:
                return found
        return None
    finally:
        open_containers.discard(id(value))


def _type_hint(value: Any) -> str:
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
    key: str, data: Any, to: str = "to another node", reason: str = ""
) -> NotSerializableError:
    """A NotSerializableError naming the key, the path inside the data and the type.

    ``to`` says where the page was going; ``reason`` what is wrong when no single
    part is to blame.

    Example::

        not_serializable_error("pose", {"pose": [1, 2, {3}]})   # "... data['pose'][2] is a set"
    """
    found = _find(data, "data", set(), 0)
    why = f"{reason or 'it cannot be written as JSON'}."
    if found is not None:
        path, bad, hint = found
        has = "has a key that is" if hint is _KEY_HINT else "is"
        what = f"{type(bad).__name__} ({short_repr(bad, 60)})"
        why = f"{path} {has} a {what}, which JSON cannot hold. {hint}"
    return NotSerializableError(
        f"Cannot send the page stored under {key!r} {to}: {why} Data sent between "
        "nodes may only hold dicts, lists, tuples, str, int, float, bool and None."
    )


def check_serializable(key: str, data: Any) -> None:
    """Raise `not_serializable_error`'s error unless ``data`` is plain JSON (no set, no NaN).

    Example::

        check_serializable("pose", {"x": 1.0})     # fine
        check_serializable("pose", {"x": {1.0}})   # NotSerializableError: data['x'] is a set
    """
    if _find(data, "data", set(), 0) is not None:
        raise not_serializable_error(key, data)
