"""The page codec: pages as strict JSON, the same for comms, recordings and serial links.

Every place where a page leaves or enters a node writes and reads it here:
comms frames (``snr.std_mods.comms.wire`` adds the length header), and the
JSON-lines format of recordings and serial links (defined below: a header
line, then one page per line). So there is one set of rules, one error
message for data JSON cannot hold, and one strict reader:

* **Written:** compact JSON, ASCII only (other characters as ``\\uXXXX``), in
  a fixed field order, UTF-8 bytes.
* **Refused when writing** (`NotSerializableError`, naming the key and the
  part of the data): anything JSON cannot hold, NaN and infinity, lone
  surrogates, nesting deeper than `MAX_DEPTH`.
* **Rejected when reading** (`WireFormatError`, saying why): text that is not
  UTF-8 or not JSON, ``NaN``/``Infinity``, numbers too large for a double
  (``1e999``), lone surrogates (``"\\ud800"``), nesting deeper than
  `MAX_DEPTH`, and pages with missing or wrongly typed fields.

Two JSON backends do the work, each through its public functions only: the
standard library's ``json`` and, when it is installed (``pip install
'snr-robotics[fast]'``), ``orjson``, several times faster. The backends differ (orjson
writes NaN as ``null``, writes non-ASCII text as raw UTF-8, formats small
floats differently, reads integers beyond 64 bits as floats), so orjson's
result is used only where it is known to be json's; everything else goes
through ``json``, which gives every verdict and message. Either way the bytes
written and the inputs rejected are exactly those of ``docs/wire-format.md``.
Set the environment variable ``SNR_JSON=json`` (or call ``use_backend("json")``)
to use the standard library only.

Example::

    line = page_to_line(Page("depth_m", 3.2, "urov", 1700000000.25))
    # '{"key":"depth_m","data":3.2,"origin":"urov","created_at_s":1700000000.25,"process":true}'
    page_from_line(line)   # Page('depth_m', 3.2, 'urov', 1700000000.25, True)
    page_from_line('{"key":"x","data":1e999}')   # WireFormatError: ... infinity ...
"""

from __future__ import annotations

import json
import math
import os
import re
import time
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Mapping,
    NoReturn,
    Optional,
    Tuple,
    Union,
)

from snr.prelude import NotSerializableError, Page, WireFormatError
from snr.prelude.install import install_hint, upgrade_hint
from snr.prelude.not_serializable import not_serializable_error

_orjson: Any
try:
    import orjson as _orjson
except ImportError:  # the optional fast backend is not installed
    _orjson = None

__all__ = [
    "BACKEND_ENV_VAR",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "MAX_DEPTH",
    "PageEncoder",
    "PathLike",
    "available_backends",
    "backend",
    "check_header",
    "data_json",
    "decode_line",
    "dump_json",
    "header_line",
    "is_header",
    "load_json",
    "load_object",
    "page_from_fields",
    "page_from_line",
    "page_json",
    "page_to_line",
    "use_backend",
]

MAX_DEPTH = 100
"""Deepest nesting of arrays and objects in one body or line, the outer object included.

So a page's ``data`` may nest 99 deep (``[[1]]`` is 2 deep). Deeper input is
rejected, deeper data is refused.
"""

BACKEND_ENV_VAR = "SNR_JSON"
"""Environment variable choosing the JSON backend: ``json`` (stdlib) or ``orjson``."""

FORMAT_NAME = "snr-pages"
"""The ``format`` field of the header line of recordings and serial links."""

FORMAT_VERSION = 1
"""The line format version this SNR writes; it reads this version and older."""

PathLike = Union[str, "os.PathLike[str]"]
"""A file name: a string or a ``pathlib.Path``."""

Text = Union[bytes, bytearray, memoryview, str]
"""What the readers take: UTF-8 bytes, or text already decoded."""

_DATA_DEPTH = MAX_DEPTH - 1  # the page object itself is one level
_JSON_SCALARS = frozenset((str, int, float, bool, type(None)))
_STR = frozenset((str,))
_LONE_SURROGATE = re.compile("[\ud800-\udfff]")
_TOO_DEEP = f"it nests arrays and objects more than {MAX_DEPTH} deep"


class _Refused(Exception):
    """Data JSON cannot hold, with the reason (turned into NotSerializableError)."""


class _OutOfRange(Exception):
    """A number a double cannot hold, such as ``1e999`` (json alone reads it as infinity).

    Not a ValueError, which is what json's own verdicts are.
    """


def _opens_too_many(text: bytes, depth: int = MAX_DEPTH) -> bool:
    """True when JSON text opens more than ``depth`` arrays and objects, so may nest too deep.

    Brackets inside strings count too: then the decoded value shows it is fine.
    Shorter text cannot open (and close) that many, and is not counted.
    """
    return len(text) > 2 * depth and text.count(b"[") + text.count(b"{") > depth


def _problem(value: Any) -> Optional[str]:
    """Why a decoded JSON value breaks SNR's rules (nested too deep, a lone surrogate), or None.

    Decoded JSON holds only dict, list, str, int, float, bool and None.
    Example: ``_problem(["\\ud800"])`` names the lone surrogate.
    """
    stack: List[Tuple[Any, int]] = [(value, 1)]  # (a value, how deep it is)
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            return _TOO_DEEP
        items: Iterable[Any] = (node,)
        if type(node) is list:
            items = node
        elif type(node) is dict:
            for key in node:
                if _LONE_SURROGATE.search(key):
                    return f"the key {key[:40]!r} holds a lone surrogate, which is not text"
            items = node.values()
        for item in items:
            if type(item) is list or type(item) is dict:
                stack.append((item, depth + 1))
            elif type(item) is str and _LONE_SURROGATE.search(item):
                return f"the string {item[:40]!r} holds a lone surrogate, which is not text"
    return None


# -- the standard library's json: every verdict and message comes from here ----------


def _reject_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not a JSON number")


def _finite_float(text: str) -> float:
    """A JSON number with a fraction or an exponent, read as json reads it, but never infinity."""
    value = float(text)
    if math.isinf(value):
        raise _OutOfRange(f"the number {value!r:.40} is out of range (infinity or too large)")
    return value


_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)
_DECODER = json.JSONDecoder(parse_constant=_reject_constant, parse_float=_finite_float)
_SYNTAX_DECODER = json.JSONDecoder(parse_constant=_reject_constant)  # reads 1e999 as inf


def _decode(decoder: json.JSONDecoder, text: str) -> Any:
    """``decoder``'s value for ``text``; json's verdict as a `WireFormatError`."""
    try:
        return decoder.decode(text)
    except ValueError as error:  # json.JSONDecodeError, NaN/Infinity, huge integers
        raise WireFormatError(f"it is not JSON ({error}): {text[:60]!r}") from None
    except RecursionError:
        raise WireFormatError(_TOO_DEEP) from None


def _load_std(raw: Text) -> Any:
    """The JSON value in ``raw``, read strictly with json (`load_json` says what is rejected)."""
    if isinstance(raw, str):
        text, data = raw, raw.encode("utf-8", "surrogatepass")
    else:
        data = bytes(raw)
        try:
            text = data.decode("utf-8")  # strict: surrogates as UTF-8 bytes are not UTF-8
        except UnicodeDecodeError as error:
            raise WireFormatError(f"it is not UTF-8 text ({error})") from None
    try:
        value = _decode(_DECODER, text)
    except _OutOfRange as error:
        _decode(_SYNTAX_DECODER, text)  # text broken further on: json's verdict comes first
        raise WireFormatError(f"it is not valid JSON for SNR: {error}") from None
    # json reads lone surrogates (escaped as \ud800, or raw in text) and nests as
    # deep as its recursion lets it: where the text may hold either, look.
    if (
        b"\\ud" in data
        or b"\\uD" in data
        or (isinstance(raw, str) and not raw.isascii())
        or _opens_too_many(data)
    ):
        problem = _problem(value)
        if problem is not None:
            raise WireFormatError(f"it is not valid JSON for SNR: {problem}")
    return value


def _dump_std(obj: Any) -> bytes:
    """``obj`` as compact ASCII JSON, written with json; raises `_Refused` saying why not."""
    try:
        out = _ENCODER.encode(obj).encode("ascii")
    except (TypeError, ValueError) as error:  # not JSON, NaN/infinity, contains itself
        raise _Refused(str(error)) from error
    except RecursionError:
        raise _Refused(f"data nests lists and dicts more than {_DATA_DEPTH} deep") from None
    # json writes lone surrogates (as \ud800) and nests as deep as its recursion
    # lets it: where the text may hold either, refuse what a reader would reject.
    if b"\\ud" in out or _opens_too_many(out):
        try:
            problem = _problem(json.loads(out))
        except RecursionError:
            problem = _TOO_DEEP
        if problem == _TOO_DEEP:
            raise _Refused(f"data nests lists and dicts more than {_DATA_DEPTH} deep")
        if problem is not None:
            raise _Refused(problem)
    return out


# -- orjson, where its result is known to be json's; json does everything else ------

# Every digit made 0, so that one search finds a run of 19 digits or more.
_DIGITS_TO_ZERO = bytes.maketrans(b"123456789", b"000000000")


def _load_orjson(raw: Text) -> Any:
    """`_load_std`'s value and verdict, found with orjson where it reads the same."""
    assert _orjson is not None
    try:
        value = _orjson.loads(raw)
    except _orjson.JSONDecodeError:
        return _load_std(raw)  # json gives the verdict and the message
    # orjson rejects NaN, infinity and lone surrogates itself, but reads an
    # integer beyond 64 bits (19 digits or more) as a float, and nests up to
    # 1,024 deep: json reads such text again.
    data = raw.encode("utf-8") if isinstance(raw, str) else bytes(raw)
    if b"0" * 19 in data.translate(_DIGITS_TO_ZERO) or _opens_too_many(data):
        return _load_std(raw)
    return value


def _plain(value: Any, depth: int = 1) -> bool:
    """True when ``value`` holds only exact JSON types, nested at most `MAX_DEPTH` deep.

    That is str, int, float, bool, None, lists, tuples and dicts with str keys;
    not their subclasses, enums, dataclasses, dates or UUIDs, which orjson
    writes and json refuses or writes otherwise. Data that contains itself is
    endlessly deep, so not plain either. ``depth`` is how deep ``value`` itself
    is (2 for a page's data). Example: ``_plain({"a": [1, 2.5]})``.
    """
    kind = type(value)
    if kind is dict:
        if not _STR.issuperset(map(type, value)):  # all keys at once
            return False
        value = value.values()
    elif kind is not list and kind is not tuple:
        return kind in _JSON_SCALARS
    if depth > MAX_DEPTH:
        return False
    for item in value:
        if type(item) not in _JSON_SCALARS and not _plain(item, depth + 1):
            return False
    return True


def _dump_orjson(obj: Any) -> bytes:
    """`_dump_std`'s bytes and refusals, written with orjson where it writes the same."""
    assert _orjson is not None
    if _plain(obj):
        try:
            out: bytes = _orjson.dumps(obj)
        except TypeError:  # integers beyond 64 bits, lone surrogates: json decides
            return _dump_std(obj)
        if _as_json_writes(out):
            return out
    return _dump_std(obj)


def _as_json_writes(out: bytes) -> bool:
    """True unless orjson's ``out`` may hold what json writes otherwise.

    That is non-ASCII text and DEL (json escapes them), null (orjson's NaN and
    infinity, which json refuses; or None) and small floats (0.00001 and 1e-7,
    where json writes 1e-05 and 1e-07). Example: ``_as_json_writes(b'[0.5]')``.
    """
    return (
        out.isascii()
        and b"\x7f" not in out
        and b"null" not in out
        and b"0.0000" not in out
        and b"e-" not in out
    )


# -- a page's data and time alone, for PageEncoder ---------------------------------
#
# Most pages hold a number, a short name or a small list or dict of those.
# A number's type says what its JSON is, so it is written directly; anything
# else is written, and its JSON searched as `_dump_std` and `_dump_orjson` do.
# None means "let page_json decide", which also gives the refusal's message.


def _value_std(value: Any) -> Optional[bytes]:
    """json's bytes for ``value``, or None where `page_json` must decide.

    json writes a float with ``float.__repr__`` and an int with ``int.__repr__``;
    writing them here saves ``JSONEncoder.encode`` making its C encoder for the
    call (about 1 µs). Text is encoded without one. Example: ``_value_std(0.5)``
    is ``b"0.5"``.
    """
    kind = type(value)
    if kind is float:
        # value - value is NaN for NaN and infinity, which json refuses
        return float.__repr__(value).encode("ascii") if value - value == 0.0 else None
    if kind is bool:
        return b"true" if value else b"false"
    if value is None:
        return b"null"
    try:
        out = (int.__repr__(value) if kind is int else _ENCODER.encode(value)).encode("ascii")
    except (TypeError, ValueError, RecursionError):  # not JSON, NaN, 4,300 digits...
        return None
    # a surrogate, maybe lone; data nesting more than a page's data may
    if b"\\ud" in out or _opens_too_many(out, _DATA_DEPTH):
        return None
    return out


_SMALL = 16  # items in a list or dict `_alike` looks at; longer ones, searching is faster


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
            # value - value is NaN for NaN and infinity
            if value - value != 0.0 or (-1e-4 < value < 1e-4 and value != 0.0):
                return False
        elif kind is str:
            if not value.isascii() or "\x7f" in value:
                return False
        elif kind is int or kind is bool or value is None:
            continue
        elif kind is list or kind is tuple:
            if not (levels and len(value) <= _SMALL and _alike(value, levels - 1)):
                return False
        elif kind is dict:
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


def _value_orjson(value: Any) -> Optional[bytes]:
    """`_value_std`'s bytes, written with orjson where it writes the same; None as there.

    A number, a name or a small list or dict of them (`_alike`) is written
    as it is; other data of exact JSON types is written and its bytes are
    searched as `_dump_orjson` does; the rest goes to `_value_std`.
    Example: ``_value_orjson({"seq": 1})`` is ``b'{"seq":1}'``.
    """
    assert _orjson is not None
    if type(value) is float and value - value == 0.0 and not -1e-4 < value < 1e-4:
        return _orjson.dumps(value)  # type: ignore[no-any-return]  # every page's time
    try:
        if _alike((value,), 2):
            return _orjson.dumps(value)  # type: ignore[no-any-return]
        if _plain(value, depth=2):  # 2: inside the page, so at most _DATA_DEPTH deep
            out: bytes = _orjson.dumps(value)
            if _as_json_writes(out):
                return out
    except TypeError:  # an integer beyond 64 bits, a key that is not text
        pass
    return _value_std(value)  # json's bytes, or None


_load: Callable[[Text], Any] = _load_std
_dump: Callable[[Any], bytes] = _dump_std
_value: Callable[[Any], Optional[bytes]] = _value_std
_backend = "json"


def available_backends() -> Tuple[str, ...]:
    """The JSON backends that can be used here: ``("json", "orjson")`` or ``("json",)``.

    Example::

        "orjson" in available_backends()   # True after pip install 'snr-robotics[fast]'
    """
    return ("json", "orjson") if _orjson is not None else ("json",)


def backend() -> str:
    """The JSON backend in use: ``"orjson"`` or ``"json"``.

    Example::

        backend()   # 'orjson'
    """
    return _backend


def use_backend(name: Optional[str] = None) -> str:
    """Choose the JSON backend; returns the one now in use.

    Args:
        name: ``"json"`` (the standard library), ``"orjson"``, or None for the
            default: the ``SNR_JSON`` environment variable if set, else orjson
            when it is installed. The bytes written and the inputs rejected
            are the same with both; only the speed differs.

    Raises:
        ValueError: an unknown name, or orjson asked for but not installed.

    Example::

        use_backend("json")     # compare with the stdlib, e.g. in a test
        use_backend()           # back to the default
    """
    global _load, _dump, _value, _backend
    if name is None:
        name = os.environ.get(BACKEND_ENV_VAR, "").strip().lower() or (
            "orjson" if _orjson is not None else "json"
        )
    if name == "json":
        _load, _dump, _value = _load_std, _dump_std, _value_std
    elif name == "orjson":
        if _orjson is None:
            raise ValueError(
                f"the orjson JSON backend is not installed ({BACKEND_ENV_VAR}=orjson?): "
                f"{install_hint('fast')}, or use 'json'"
            )
        _load, _dump, _value = _load_orjson, _dump_orjson, _value_orjson
    else:
        raise ValueError(f"unknown JSON backend {name!r}; choose 'json' or 'orjson'")
    _backend = name
    return name


# -- JSON text ------------------------------------------------------------------------


def load_json(raw: Text) -> Any:
    """The JSON value in ``raw`` (UTF-8 bytes or text), read strictly.

    Raises:
        WireFormatError: not UTF-8, not JSON, NaN/Infinity, a number beyond a
            double (``1e999``), a lone surrogate, nesting over `MAX_DEPTH`.

    Example::

        load_json(b'{"a":[1,2.5]}')   # {'a': [1, 2.5]}
        load_json(b'[1e999]')         # WireFormatError
    """
    return _load(raw)


def load_object(raw: Text) -> Dict[str, Any]:
    """Like `load_json`, for a body or line that must be a JSON object.

    Example::

        load_object(b'{"key":"x","data":1}')   # {'key': 'x', 'data': 1}
    """
    obj = _load(raw)
    if type(obj) is not dict:
        raise WireFormatError(f"it is a JSON {type(obj).__name__}, not an object {{...}}")
    return obj


def dump_json(obj: Mapping[str, Any], what: str = "it") -> bytes:
    """``obj`` as compact, ASCII-only JSON bytes (for small fixed objects, not pages).

    Raises:
        NotSerializableError: something in it JSON cannot hold.

    Example::

        dump_json({"v": 1, "kind": "hello", "role": "urov"})
        # b'{"v":1,"kind":"hello","role":"urov"}'
    """
    try:
        return _dump(obj)
    except _Refused as error:
        raise NotSerializableError(f"Cannot write {what} as JSON: {error}") from None


# -- pages ----------------------------------------------------------------------------


def data_json(key: str, data: Any, to: str) -> bytes:
    """A page's ``data`` alone as compact, ASCII-only JSON bytes, refused as pages are.

    For formats that send the data without the rest of the page (a serial
    link's plain lines, a board's compact lines).

    Raises:
        NotSerializableError: the same message as `page_json` (naming ``key``,
            the part of the data and the fix).

    Example::

        data_json("motor", [50, -50], to="to a serial link")   # b'[50,-50]'
    """
    try:
        return _dump(data)
    except _Refused as error:
        raise not_serializable_error(key, data, to=to, reason=str(error)) from None


def page_json(
    page: Page, head: Optional[Mapping[str, Any]] = None, to: str = "to another node"
) -> bytes:
    """``page`` as one JSON object: ``head``'s fields, then the page's fields.

    Args:
        page: the page.
        head: fields written first, e.g. ``{"v": 1, "kind": "page"}`` for a frame.
        to: where it is going, for the error message.

    Raises:
        NotSerializableError: the data is not JSON (a set, an object, NaN,
            a lone surrogate, too deep): the message names the key, the part
            of the data and the fix.

    Example::

        page_json(Page("x", [1, 2], "robot", 0.5))
        # b'{"key":"x","data":[1,2],"origin":"robot","created_at_s":0.5,"process":true}'
    """
    fields: Dict[str, Any] = dict(head) if head else {}
    fields["key"] = page.key
    fields["data"] = page.data
    fields["origin"] = page.origin
    fields["created_at_s"] = page.created_at_s
    fields["process"] = page.process
    try:
        return _dump(fields)
    except _Refused as error:
        raise not_serializable_error(page.key, page.data, to=to, reason=str(error)) from None


_MAX_ENVELOPES = 1024
"""The (key, origin) pairs a `PageEncoder` keeps the fixed JSON of; when full it starts again."""

_PAGE_FIELDS = frozenset(("key", "data", "origin", "created_at_s", "process"))
_TAILS = (b',"process":false}', b',"process":true}')


class PageEncoder:
    """`page_json` with the leading fields and the destination given once: a link's encoder.

    A node sends pages under a few keys, each from one origin, again and
    again, and their JSON differs only in the data and the time. So the text
    around them (the head, the key and the origin, with the field names) is
    written once per key and origin with `dump_json` and kept in a dict (up
    to `_MAX_ENVELOPES` pairs; then it is emptied and filled again). A page
    whose data and time are numbers, names or small lists and dicts of them
    then costs the JSON of those two and a join; any other page goes through
    `page_json`. The bytes and the refusals are `page_json`'s either way.

    Args:
        head: fields written before the page's, e.g. ``{"v": 1, "kind": "page"}``.
        to: where the pages go, for the error message.

    Example::

        encode = PageEncoder({"v": 1, "kind": "page"})
        encode(Page("x", 1.5, "robot", 0.5))
        # b'{"v":1,"kind":"page","key":"x","data":1.5,"origin":"robot","created_at_s":0.5,...}'
    """

    def __init__(self, head: Mapping[str, Any], to: str = "to another node") -> None:
        self.head = dict(head)
        self.to = to
        # (key, origin) -> the JSON before the data, and between the data and the
        # time; None where page_json must decide (a head that names a page field,
        # a key or origin json refuses).
        self._envelopes: Dict[Tuple[str, str], Optional[Tuple[bytes, bytes]]] = {}

    def __call__(self, page: Page) -> bytes:
        """The page's JSON; raises `NotSerializableError` as `page_json` does."""
        key, origin, process = page.key, page.origin, page.process
        if type(key) is str and type(origin) is str and type(process) is bool:
            try:
                envelope = self._envelopes[(key, origin)]
            except KeyError:
                envelope = self._learn(key, origin)
            if envelope is not None:
                data, created = _value(page.data), _value(page.created_at_s)
                if data is not None and created is not None:
                    return b"".join((envelope[0], data, envelope[1], created, _TAILS[process]))
        return page_json(page, self.head, self.to)

    def _learn(self, key: str, origin: str) -> Optional[Tuple[bytes, bytes]]:
        """The JSON around a page's data under ``key`` from ``origin``, kept for the next page."""
        if len(self._envelopes) >= _MAX_ENVELOPES:
            self._envelopes.clear()
        envelope: Optional[Tuple[bytes, bytes]] = None
        if _PAGE_FIELDS.isdisjoint(self.head):  # else the fields' order is page_json's to say
            try:
                before = _dump({**self.head, "key": key})[:-1] + b',"data":'  # without its "}"
                envelope = (before, b',"origin":' + _dump(origin) + b',"created_at_s":')
            except _Refused:  # e.g. a lone surrogate in the key: page_json says why
                envelope = None
        self._envelopes[(key, origin)] = envelope
        return envelope


def _bad_type(name: str, value: Any, expected: str) -> WireFormatError:
    return WireFormatError(
        f"field {name!r} of the page must be {expected}, not {type(value).__name__} {value!r:.40}"
    )


def page_from_fields(
    fields: Mapping[str, Any], default_origin: Optional[str] = "", now_s: Optional[float] = None
) -> Page:
    """The page a decoded JSON object describes.

    ``key`` (a non-empty string) and ``data`` are always required; unknown
    fields are ignored. In recordings and serial lines a missing ``origin``
    becomes ``default_origin`` and a missing ``created_at_s`` becomes
    ``now_s`` (or the current time). With ``default_origin=None`` (comms
    frames) both are required, and ``origin`` must not be empty. A missing
    ``process`` is true.

    Raises:
        WireFormatError: a field is missing, empty or of the wrong type; the
            message names it.

    Example::

        page_from_fields({"key": "temp_c", "data": 21.5}, default_origin="arduino")
        page_from_fields(frame_fields, default_origin=None)   # everything required
    """
    key, origin = fields.get("key"), fields.get("origin")
    created, process = fields.get("created_at_s"), fields.get("process", True)
    # The common case, checked in one go; the slow path below names the problem.
    if (
        type(key) is str
        and key
        and type(origin) is str
        and (origin or default_origin is not None)
        and type(created) is float
        and type(process) is bool
        and "data" in fields
    ):
        return Page(key, fields["data"], origin, created, process)
    if "key" not in fields:
        raise WireFormatError("the page has no 'key' field (a page needs at least key and data)")
    if type(key) is not str:
        raise _bad_type("key", key, "a JSON string")
    if not key:
        raise WireFormatError("field 'key' of the page must not be empty")
    if "data" not in fields:
        raise WireFormatError(f"the page under {key!r} has no 'data' field")
    if default_origin is None:
        for name in ("origin", "created_at_s"):
            if name not in fields:
                raise WireFormatError(f"the page under {key!r} has no {name!r} field")
        origin_value = origin
    else:
        origin_value = fields.get("origin", default_origin)
    if type(origin_value) is not str:
        raise _bad_type("origin", origin_value, "a JSON string")
    if default_origin is None and not origin_value:
        raise WireFormatError("field 'origin' of the page must not be empty")
    if "created_at_s" in fields:
        if type(created) not in (int, float):
            raise _bad_type("created_at_s", created, "a number")
        try:
            created_s = float(created)  # type: ignore[arg-type]
        except OverflowError:
            raise WireFormatError("field 'created_at_s' of the page is too large") from None
    else:
        created_s = time.time() if now_s is None else now_s
    if type(process) is not bool:
        raise _bad_type("process", process, "a JSON bool (true or false)")
    return Page(key, fields["data"], origin_value, created_s, process)


# -- the JSON-lines format of recordings and serial links ------------------------------


def header_line() -> str:
    """The header line (without its newline) that starts a recording or serial link.

    Example::

        header_line()   # '{"format":"snr-pages","version":1}'
    """
    return dump_json({"format": FORMAT_NAME, "version": FORMAT_VERSION}).decode("ascii")


def page_to_line(page: Page) -> str:
    """One page as one line of JSON (without the newline).

    Raises:
        NotSerializableError: the page's data is not JSON (a set, an object,
            NaN...); the message names the key, the part and the fix.

    Example::

        page_to_line(Page("x", [1, 2], "robot", 0.5))
        # '{"key":"x","data":[1,2],"origin":"robot","created_at_s":0.5,"process":true}'
    """
    return _line_encoder(page).decode("ascii")


_line_encoder = PageEncoder({}, to="to a recording or serial link")


def decode_line(line: Text) -> Dict[str, Any]:
    """The JSON object on one line (a page or a header), read strictly.

    Raises:
        WireFormatError: the line is not UTF-8, not strict JSON, or not a
            JSON object.

    Example::

        decode_line('{"key":"x","data":1}')   # {'key': 'x', 'data': 1}
    """
    return load_object(line)


def is_header(fields: Mapping[str, Any]) -> bool:
    """True when a decoded line is a header line, not a page.

    Example::

        is_header(decode_line(header_line()))   # True
    """
    return "format" in fields and "key" not in fields


def check_header(fields: Mapping[str, Any]) -> None:
    """Check a header's format name and version.

    Raises:
        WireFormatError: not an SNR page stream, a version that is not a
            whole number, or a newer version than this SNR can read.

    Example::

        check_header({"format": "snr-pages", "version": 1})   # fine
    """
    if fields.get("format") != FORMAT_NAME:
        raise WireFormatError(
            f"the header names format {fields.get('format')!r}, not {FORMAT_NAME!r}: this is "
            "not an SNR page stream"
        )
    version = fields.get("version")
    if type(version) is not int or version < 1:
        raise WireFormatError(f"the header has version {version!r}; expected a whole number >= 1")
    if version > FORMAT_VERSION:
        raise WireFormatError(
            f"it was written in format version {version}, but this SNR reads up to version "
            f"{FORMAT_VERSION}: upgrade SNR ({upgrade_hint()}) to read it"
        )


def page_from_line(
    line: Text, default_origin: str = "", now_s: Optional[float] = None
) -> Optional[Page]:
    """The page a line holds, or None for a (valid) header line.

    Raises:
        WireFormatError: the line is malformed, or is a header of another
            format or a newer version; the message says which.

    Example::

        page_from_line('{"key":"temp_c","data":21.5}', default_origin="arduino")
        # Page('temp_c', 21.5, 'arduino', <now>, True)
    """
    fields = load_object(line)
    if is_header(fields):
        check_header(fields)
        return None
    return page_from_fields(fields, default_origin, now_s)


use_backend()
