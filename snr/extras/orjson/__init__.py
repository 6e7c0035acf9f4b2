"""orjson as SNR's JSON backend: the page codec's work done faster, the same bytes.

``pip install 'snr-robotics[fast]'`` installs [orjson](https://pypi.org/project/orjson/),
and the page codec (``snr.std_mods.codec``) then uses this backend by default:
it is registered in the entry point group ``snr.json_backends`` as ``orjson``.
``SNR_JSON=json`` (or ``codec.use_backend("json")``) runs without it.

What it gains, and why it is an extra: docs/performance.md, "The JSON backend
as an extra" (bench_comms: more pages a second and a shorter round trip; the
kernel stays with the standard library a student can read).

orjson differs from ``json`` in places: it writes NaN as ``null``, non-ASCII
text unescaped, ``1e-05`` as ``0.00001``, refuses integers beyond 64 bits and
reads them as floats, and nests up to 1,024 deep. So `OrjsonBackend` answers
only where its result is known to be json's, and steps aside (``None``, or a
ValueError) everywhere else: the codec then uses json, which also gives every
verdict and message.

Example::

    from snr.std_mods import codec

    codec.use_backend("orjson")   # what the default picks when orjson is installed
    codec.page_to_line(Page("x", [1, 2.5], "robot", 0.5))   # the same line as with json
"""

from __future__ import annotations

from typing import Any, Dict, Iterable, Optional, Union

from snr.prelude.install import install_hint
from snr.std_mods.codec import MAX_DEPTH

_orjson: Any
try:
    import orjson as _orjson
except ImportError:  # OrjsonBackend() says how to install it
    _orjson = None

__all__ = ["OrjsonBackend"]

_JSON_SCALARS = frozenset((str, int, float, bool, type(None)))
_STR = frozenset((str,))
_SMALL = 16  # items in a list or dict `_alike` looks at; longer ones, searching is faster
_DIGITS_TO_ZERO = bytes.maketrans(b"123456789", b"000000000")  # a run of 19 digits: one search
_NINETEEN_DIGITS = b"0" * 19  # what that run is once `_DIGITS_TO_ZERO` has made each digit 0
_LARGEST = 1.7976931348623157e308  # the largest finite float: a larger one is infinity


def _float_alike(value: float) -> bool:
    """True when orjson writes the float ``value`` as json does: finite, 0 or at least 1e-4.

    orjson writes NaN and infinity as ``null`` (json refuses them) and 1e-5 as
    ``0.00001`` (json: ``1e-05``). NaN fails every comparison, so it is False.
    The loops of `_names_and_scalars` and `_alike` write this test out in
    place, to save a call per item. Example: ``_float_alike(0.5)`` is True.
    """
    return 1e-4 <= value <= _LARGEST or -_LARGEST <= value <= -1e-4 or value == 0.0


def _names_and_scalars(value: Dict[Any, Any]) -> bool:
    """True when orjson writes the dict ``value`` (or a dict subclass) as json does; one pass.

    The shape of most pages' data (``{"seq": 1, "value": 0.5}``): ASCII text
    without DEL for keys, and for values what `_alike` accepts of scalars.
    Anything else (a nested list, a key that is not text) is False: `_alike`
    then looks. Example: ``_names_and_scalars({"seq": 1, "value": 0.5})`` is True.
    """
    for key, item in value.items():
        if type(key) is not str or not key.isascii() or "\x7f" in key:
            return False
        kind = type(item)
        if kind is float:
            # `_float_alike`, written out: a call per item would cost what it saves
            if not (1e-4 <= item <= _LARGEST or -_LARGEST <= item <= -1e-4 or item == 0.0):
                return False
        elif kind is str:
            if not item.isascii() or "\x7f" in item:
                return False
        elif kind is not int and kind is not bool and item is not None:
            return False
    return True


def _alike(values: Iterable[Any], levels: int) -> bool:
    """True when orjson writes each of ``values`` as json does, known from their types alone.

    That holds for ints, bools, None, ASCII text without DEL, floats that are
    finite and 0 or at least 1e-4 in size (orjson writes NaN as null, 1e-5 as
    0.00001), and lists and dicts of up to `_SMALL` of them, ``levels`` deep.
    Integers beyond 64 bits and keys that are not text pass: orjson refuses
    them. Example: ``_alike([{"seq": 1, "value": 0.5}], 1)`` is True.
    """
    for value in values:
        kind = type(value)
        if kind is float:
            # `_float_alike`, written out: a call per item would cost what it saves
            if not (1e-4 <= value <= _LARGEST or -_LARGEST <= value <= -1e-4 or value == 0.0):
                return False
        elif kind is str:
            if not value.isascii() or "\x7f" in value:
                return False
        elif kind is int or kind is bool or value is None:
            continue
        elif kind is list or kind is tuple or isinstance(value, list):
            if not (levels and len(value) <= _SMALL and _alike(value, levels - 1)):
                return False
        elif isinstance(value, dict):  # (a list or dict subclass is written as one)
            if not (
                levels
                and len(value) <= _SMALL
                and _alike(value, 0)  # the keys
                and _alike(value.values(), levels - 1)
            ):
                return False
        else:
            return False
    return True


def _plain(value: Any, depth: int = 1) -> bool:
    """True when ``value`` holds only exact JSON types, nested at most `MAX_DEPTH` deep.

    That is str, int, float, bool, None, lists, tuples and dicts with str keys,
    and lists and dicts of subclasses too (both write them as the plain ones:
    read-only page data is such, in DEBUG and TEST); not other subclasses,
    enums, dataclasses, dates or UUIDs, which orjson writes and json refuses
    or writes otherwise. Data that contains itself is endlessly deep, so not
    plain either. ``depth`` is how deep ``value`` itself is (2 for a page's
    data). Example: ``_plain({"a": [1, 2.5]})``.
    """
    kind = type(value)
    if kind is dict or (kind is not list and isinstance(value, dict)):
        if not _STR.issuperset(map(type, value)):  # all keys at once
            return False
        value = value.values()
    elif kind is not list and kind is not tuple and not isinstance(value, list):
        return kind in _JSON_SCALARS
    if depth > MAX_DEPTH:
        return False
    for item in value:
        if type(item) not in _JSON_SCALARS and not _plain(item, depth + 1):
            return False
    return True


def _as_json_writes(out: bytes) -> bool:
    """True unless orjson's ``out`` may hold what json writes otherwise.

    That is non-ASCII text and DEL (json escapes them), null (orjson's NaN and
    infinity, which json refuses; or None) and small floats (0.00001 and 1e-7,
    where json writes 1e-05 and 1e-07). Example: ``_as_json_writes(b'[0.5]')``.
    """
    # find, not `in`: `in` first tries a bytes needle as a number, which costs more
    return (
        out.isascii()
        and out.find(b"\x7f") < 0
        and out.find(b"null") < 0
        and out.find(b"0.0000") < 0
        and out.find(b"e-") < 0
    )


class OrjsonBackend:
    """orjson as the page codec's `snr.std_mods.codec.JsonBackend`: json's results, or a step aside.

    Raises:
        ImportError: orjson is not installed (the message is the pip line).

    Example::

        OrjsonBackend().dumps({"seq": 1, "value": 0.5})   # b'{"seq":1,"value":0.5}'
        OrjsonBackend().dumps(1e-5)                       # None: json writes 1e-05
    """

    def __init__(self) -> None:
        if _orjson is None:
            raise ImportError(install_hint("fast"))

    def dumps(self, value: Any) -> Optional[bytes]:
        """orjson's bytes for ``value`` where they are json's, else None.

        A number, a name or a small list or dict of them (`_alike`, two deep;
        a dict of names and scalars in one pass, `_names_and_scalars`) is
        written as it is; other data of exact JSON types, nested at most
        ``MAX_DEPTH - 1`` deep (`_plain`), is written and its bytes are
        searched (`_as_json_writes`). orjson refuses lone surrogates itself.
        """
        kind = type(value)
        if kind is float:  # every page's time
            if _float_alike(value):
                return _orjson.dumps(value)  # type: ignore[no-any-return]
            return None  # NaN, infinity (json refuses them), 1e-05 (orjson writes 0.00001)
        try:
            if (
                (kind is dict or isinstance(value, dict))
                and len(value) <= _SMALL
                and _names_and_scalars(value)
            ):
                return _orjson.dumps(value)  # type: ignore[no-any-return]  # most pages' data
            if _alike((value,), 2):
                return _orjson.dumps(value)  # type: ignore[no-any-return]
            if _plain(value, 2):  # None for data nesting over MAX_DEPTH - 1: json decides
                out: bytes = _orjson.dumps(value)
                if _as_json_writes(out):
                    return out
        except TypeError:  # an integer beyond 64 bits, a key that is not text, a surrogate
            pass
        return None

    def loads(self, raw: Union[bytes, bytearray, memoryview, str]) -> Any:
        """orjson's value for ``raw`` where it is json's; ValueError where json must read it.

        orjson rejects NaN, infinity and lone surrogates itself (its
        JSONDecodeError is a ValueError), but reads an integer beyond 64 bits
        (19 digits or more) as a float, and nests deeper than `MAX_DEPTH`.
        """
        value = _orjson.loads(raw)
        if type(raw) is not bytes:  # a link's body is bytes; a line may be text
            raw = raw.encode("utf-8") if isinstance(raw, str) else bytes(raw)
        # find, not `in`: `in` first tries a bytes needle as a number, which costs more
        if raw.translate(_DIGITS_TO_ZERO).find(_NINETEEN_DIGITS) >= 0 or (
            len(raw) > 2 * MAX_DEPTH and raw.count(b"[") + raw.count(b"{") > MAX_DEPTH
        ):
            raise ValueError("json reads it: an integer beyond 64 bits, or deep nesting")
        return value
