"""The wire format: pages as strict JSON, in frames between nodes and in lines on disk.

Every page that leaves or enters a node is written and read here
(docs/wire-format.md): comms *frames* (a 4-byte big-endian length, then a
JSON object with ``"v"`` and a ``"kind"``: ``hello``, ``proof``, ``page``,
``beat`` or ``bye``), and the lines of recordings and serial links (a header
line, then one page per line). One set of rules:

* **Written:** compact JSON, ASCII only (``\\uXXXX``), fields in a fixed order.
* **Refused when writing** (`NotSerializableError`, naming the key and the
  part of the data): what JSON cannot hold, NaN and infinity, lone
  surrogates, nesting deeper than `MAX_DEPTH`.
* **Rejected when reading** (`WireFormatError`, saying why): text that is not
  UTF-8 or not JSON, ``NaN``, ``1e999``, lone surrogates, nesting deeper than
  `MAX_DEPTH`, pages with missing or wrongly typed fields. Nothing is
  unpickled or evaluated: a bad frame can only be *wrong*, never harmful.

The standard library's ``json`` does the work. A faster `JsonBackend` from an
extra may do part of it (``snr.extras.orjson``: ``pip install
'snr-robotics[fast]'``, used when installed; ``SNR_JSON=json`` turns it off).

Example::

    frame = encode_page(Page("depth_m", 3.2, origin="urov", created_at_s=1700000000.0))
    decoder = FrameDecoder()
    decoder.feed(frame)
    decode_body(decoder.next_frame())   # Page('depth_m', 3.2, 'urov', 1700000000.0, True)
    page_to_line(Page("depth_m", 3.2, "urov", 1700000000.25))
    # '{"key":"depth_m","data":3.2,"origin":"urov","created_at_s":1700000000.25,"process":true}'
    page_from_line('{"key":"x","data":1e999}')   # WireFormatError: ... infinity ...
"""

from __future__ import annotations

import json
import math
import os
import re
import struct
import time
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Mapping, NoReturn, Optional, Protocol, Tuple, Union

from snr.core import plugins
from snr.prelude import ConfigError, NotSerializableError, Page, WireFormatError
from snr.prelude.install import upgrade_hint
from snr.prelude.not_serializable import not_serializable_error

__all__ = [
    "BACKEND_ENV_VAR",
    "BACKEND_GROUP",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "HEADER_BYTES",
    "HELLO_VERSION",
    "MAX_DEPTH",
    "MAX_FRAME_BYTES",
    "WIRE_VERSION",
    "Beat",
    "Bye",
    "FrameDecoder",
    "Hello",
    "JsonBackend",
    "Message",
    "PageEncoder",
    "PathLike",
    "Proof",
    "available_backends",
    "backend",
    "check_header",
    "data_json",
    "decode_body",
    "decode_line",
    "dump_json",
    "encode_beat",
    "encode_bye",
    "encode_hello",
    "encode_page",
    "encode_proof",
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
"""Deepest nesting in a body or line, the outer object included: ``data`` may nest 99 deep."""

BACKEND_ENV_VAR = "SNR_JSON"
"""Environment variable choosing the JSON backend: ``json`` (stdlib) or ``orjson``."""

BACKEND_GROUP = "snr.json_backends"
"""The entry point group of the faster JSON backends (`JsonBackend`): ``orjson``."""

FORMAT_NAME = "snr-pages"
"""The ``format`` field of the header line of recordings and serial links."""

FORMAT_VERSION = 1
"""The line format version this SNR writes; it reads this version and older."""

WIRE_VERSION = 1
"""The ``"v"`` field of page, beat and bye frames, and of the first hello (no system)."""

HELLO_VERSION = 2
"""The ``"v"`` of a hello naming a system or carrying a challenge, and of proofs."""

HEADER_BYTES = 4
"""Length of the frame header: an unsigned 32-bit big-endian body length."""

MAX_FRAME_BYTES = 16 * 1024 * 1024
"""Largest body accepted or sent (16 MiB); a longer length header resets the link."""

PathLike = Union[str, "os.PathLike[str]"]
"""A file name: a string or a ``pathlib.Path``."""

Text = Union[bytes, bytearray, memoryview, str]
"""What the readers take: UTF-8 bytes, or text already decoded."""

_DATA_DEPTH = MAX_DEPTH - 1  # the page object itself is one level
_LONE_SURROGATE = re.compile("[\ud800-\udfff]")
_TOO_DEEP = f"it nests arrays and objects more than {MAX_DEPTH} deep"
_DATA_TOO_DEEP = f"data nests lists and dicts more than {_DATA_DEPTH} deep"
_HEADER = struct.Struct(">I")


class _Refused(Exception):
    """Data JSON cannot hold, with the reason (turned into NotSerializableError)."""


class _OutOfRange(Exception):
    """A number a double cannot hold, such as ``1e999`` (not a ValueError, json's verdicts)."""


def _suspect(text: bytes, depth: int = MAX_DEPTH) -> bool:
    """True when JSON text may hold a lone surrogate (``\\ud800``) or nest over ``depth``.

    Text shorter than ``2 * depth`` cannot nest that deep; brackets in strings
    count too (then the decoded value shows that all is well).
    """
    return b"\\ud" in text or (
        len(text) > 2 * depth and text.count(b"[") + text.count(b"{") > depth
    )


def _problem(value: Any, limit: int = MAX_DEPTH) -> Optional[str]:
    """Why a decoded JSON value breaks SNR's rules (nested over ``limit``, a lone surrogate).

    Example: ``_problem(["\\ud800"])`` names the lone surrogate; None if all is well.
    """
    stack = [(value, 1)]  # (a value, how deep it is)
    while stack:
        node, depth = stack.pop()
        if depth > limit:
            return _TOO_DEEP
        items: Any = node if type(node) is list else (node,)
        if type(node) is dict:
            items = [*node, *node.values()]  # the keys are strings to check too
        for item in items:
            if type(item) is list or type(item) is dict:
                stack.append((item, depth + 1))
            elif type(item) is str and _LONE_SURROGATE.search(item):
                what = "key" if type(node) is dict and item in node else "string"
                return f"the {what} {item[:40]!r} holds a lone surrogate, which is not text"
    return None


# -- the extension point: a faster JSON backend, found by entry point ----------------


class JsonBackend(Protocol):
    """What an entry point of `BACKEND_GROUP` makes: json's results, faster, or a step aside.

    The entry point names a class that raises ImportError, its message the
    pip line, when a package it needs is missing. Wherever a backend steps
    aside the codec uses json, which also gives every verdict and message, so
    the bytes written and the input rejected are the same with any backend.

    Example::

        class Slow:  # pyproject.toml: [project.entry-points."snr.json_backends"] slow = "m:Slow"
            def dumps(self, value: Any) -> Optional[bytes]:
                return None  # json writes it
            def loads(self, raw: Union[bytes, str]) -> Any:
                raise ValueError("json reads it")
    """

    def dumps(self, value: Any) -> Optional[bytes]:
        """json's bytes for ``value`` (compact, ASCII), or None to let json write it.

        None at least where json's bytes nest more than ``MAX_DEPTH - 1`` deep
        or hold a lone surrogate (``\\ud800``): the codec does not look again.
        """

    def loads(self, raw: Text) -> Any:
        """The value `load_json` reads from ``raw``, or ValueError to let json read it."""


class _DefaultOnFirstUse:
    """The backend until the first value is read or written: then the default is chosen.

    Finding the installed backends reads the packages' entry points
    (``importlib.metadata``, about 13 ms), so importing the codec does not:
    ``from snr import *`` and a program that sends no page never pay it.
    """

    def dumps(self, value: Any) -> Optional[bytes]:
        use_backend()
        return None  # json writes the first value: the same bytes

    def loads(self, raw: Text) -> Any:
        use_backend()
        raise ValueError("json reads the first value")


_fast: Optional[JsonBackend] = _DefaultOnFirstUse()  # the backend in use; None: json alone
_backend: Optional[str] = None  # None: not chosen yet
_loaded: Dict[str, JsonBackend] = {}


def _load_backend(name: str) -> JsonBackend:
    """The backend ``name`` of `BACKEND_GROUP`; ValueError if unknown or not installed."""
    names = plugins.names(BACKEND_GROUP)
    if name not in names:
        choices = " or ".join(repr(n) for n in ("json", *names))
        raise ValueError(f"unknown JSON backend {name!r}; choose {choices}")
    if name not in _loaded:
        try:
            _loaded[name] = plugins.load(BACKEND_GROUP, name, f"the JSON backend {name!r}")()
        except (ImportError, ConfigError) as error:  # ImportError's message: the pip line
            hint = error.__cause__ if isinstance(error, ConfigError) else error
            raise ValueError(
                f"the {name} JSON backend is not installed ({BACKEND_ENV_VAR}={name}?): "
                f"{hint}, or use 'json'"
            ) from None
    return _loaded[name]


def available_backends() -> Tuple[str, ...]:
    """The JSON backends that can be used here: ``("json", "orjson")`` or ``("json",)``.

    Example::

        "orjson" in available_backends()   # True after pip install 'snr-robotics[fast]'
    """
    usable = ["json"]
    for name in plugins.names(BACKEND_GROUP):
        try:
            _load_backend(name)
            usable.append(name)
        except ValueError:  # not installed
            pass
    return tuple(usable)


def backend() -> str:
    """The JSON backend in use: ``"orjson"`` or ``"json"``.

    Example::

        backend()   # 'orjson'
    """
    return _backend or use_backend()


def use_backend(name: Optional[str] = None) -> str:
    """Choose the JSON backend; returns the one now in use.

    Args:
        name: ``"json"`` (the standard library), a backend of `BACKEND_GROUP`
            (``"orjson"``), or None for the default: ``SNR_JSON`` if set, else
            the first backend installed, else json. Only the speed differs.

    Raises:
        ValueError: an unknown name, or a backend asked for but not installed.

    Example::

        use_backend("json")     # compare with the stdlib, e.g. in a test
        use_backend()           # back to the default
    """
    global _fast, _backend
    if name is None:
        name = os.environ.get(BACKEND_ENV_VAR, "").strip().lower()
        name = name or (*available_backends(), "json")[1]  # the first faster one, else json
    _fast = None if name == "json" else _load_backend(name)
    _backend = name
    return name


# -- reading and writing: the backend where it answers, else the standard library's json


def _reject_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not a JSON number")


def _finite_float(text: str) -> float:
    value = float(text)
    if math.isinf(value):
        raise _OutOfRange(f"the number {value!r:.40} is out of range (infinity or too large)")
    return value


_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)
_DECODER = json.JSONDecoder(parse_constant=_reject_constant, parse_float=_finite_float)
_SYNTAX_DECODER = json.JSONDecoder(parse_constant=_reject_constant)  # reads 1e999 as inf


def _decode(decoder: json.JSONDecoder, text: str) -> Any:
    try:
        return decoder.decode(text)
    except ValueError as error:  # json.JSONDecodeError, NaN/Infinity, huge integers
        raise WireFormatError(f"it is not JSON ({error}): {text[:60]!r}") from None
    except RecursionError:
        raise WireFormatError(_TOO_DEEP) from None


def load_json(raw: Text) -> Any:
    """The JSON value in ``raw`` (UTF-8 bytes or text), read strictly.

    Raises:
        WireFormatError: not UTF-8, not JSON, NaN/Infinity, a number beyond a
            double (``1e999``), a lone surrogate, nesting over `MAX_DEPTH`.

    Example::

        load_json(b'{"a":[1,2.5]}')   # {'a': [1, 2.5]}
        load_json(b'[1e999]')         # WireFormatError
    """
    if _fast is not None:
        try:
            return _fast.loads(raw)
        except ValueError:  # json reads it, and says what is wrong
            pass
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
    # json reads lone surrogates and nests as deep as its recursion lets it
    if _suspect(data) or b"\\uD" in data or (isinstance(raw, str) and not raw.isascii()):
        problem = _problem(value)
        if problem is not None:
            raise WireFormatError(f"it is not valid JSON for SNR: {problem}")
    return value


def _dump(value: Any, depth: int = MAX_DEPTH) -> bytes:
    """``value`` as compact ASCII JSON nesting at most ``depth`` deep; `_Refused` says why not.

    Numbers are written with their ``repr``, as json writes them, without json's encoder.
    """
    out = None if _fast is None else _fast.dumps(value)
    if out is not None:
        return out
    kind = type(value)
    # value - value is NaN for NaN and infinity, which json refuses
    if kind is float and value - value == 0.0:
        return float.__repr__(value).encode("ascii")
    try:
        out = (int.__repr__(value) if kind is int else _ENCODER.encode(value)).encode("ascii")
    except (TypeError, ValueError) as error:  # not JSON, NaN, 4,300 digits, contains itself
        raise _Refused(str(error)) from None
    except RecursionError:
        raise _Refused(_DATA_TOO_DEEP) from None
    if _suspect(out, depth):  # json writes lone surrogates (\ud800), and nests as deep as it can
        try:
            problem = _problem(json.loads(out), depth)
        except RecursionError:
            problem = _TOO_DEEP
        if problem is not None:
            raise _Refused(_DATA_TOO_DEEP if problem == _TOO_DEEP else problem)
    return out


# -- JSON text and pages --------------------------------------------------------------


def load_object(raw: Text) -> Dict[str, Any]:
    """Like `load_json`, for a body or line that must be a JSON object.

    Example::

        load_object(b'{"key":"x","data":1}')   # {'key': 'x', 'data': 1}
    """
    obj = load_json(raw)
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


def _refusing(value: Any, key: str, data: Any, to: str) -> bytes:
    """`_dump`, refusing with the error that names the page's key and the part of its data."""
    try:
        return _dump(value)
    except _Refused as error:
        raise not_serializable_error(key, data, to=to, reason=str(error)) from None


def data_json(key: str, data: Any, to: str) -> bytes:
    """A page's ``data`` alone as JSON bytes, refused as `page_json` refuses it.

    For formats that send the data without the page (a serial link's plain
    lines, a board's compact lines).

    Example::

        data_json("motor", [50, -50], to="to a serial link")   # b'[50,-50]'
    """
    return _refusing(data, key, data, to)


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
            a lone surrogate, too deep), naming the key, the part and the fix.

    Example::

        page_json(Page("x", [1, 2], "robot", 0.5))
        # b'{"key":"x","data":[1,2],"origin":"robot","created_at_s":0.5,"process":true}'
    """
    key, data = page.key, page.data
    fields = {**(head or {}), "key": key, "data": data, "origin": page.origin}
    fields.update(created_at_s=page.created_at_s, process=page.process)
    return _refusing(fields, key, data, to)


_MAX_ENVELOPES = 1024  # the (key, origin) pairs a PageEncoder keeps; when full it starts again
_PAGE_FIELDS = frozenset(("key", "data", "origin", "created_at_s", "process"))
_TAILS = (b',"process":false}', b',"process":true}')


class PageEncoder:
    """`page_json` with the leading fields and the destination given once: a link's encoder.

    A node sends pages under a few keys, each from one origin, again and
    again: the JSON around the data and the time (the head, the key, the
    origin) is written once per key and origin and kept (up to 1,024
    pairs). A page then costs the JSON of its data and time and a
    join. The bytes and the refusals are `page_json`'s.

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
        # (key, origin) -> the JSON before the data, and between it and the time;
        # None where page_json must decide (a head naming a page field, a bad key)
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
                try:
                    data = _dump(page.data, _DATA_DEPTH)
                    created = _dump(page.created_at_s, _DATA_DEPTH)
                    return b"".join((envelope[0], data, envelope[1], created, _TAILS[process]))
                except _Refused:  # page_json says why
                    pass
        return page_json(page, self.head, self.to)

    def _learn(self, key: str, origin: str) -> Optional[Tuple[bytes, bytes]]:
        if len(self._envelopes) >= _MAX_ENVELOPES:
            self._envelopes.clear()
        envelope: Optional[Tuple[bytes, bytes]] = None
        if _PAGE_FIELDS.isdisjoint(self.head):  # else the fields' order is page_json's to say
            try:
                before = _dump({**self.head, "key": key})[:-1] + b',"data":'  # without its "}"
                envelope = (before, b',"origin":' + _dump(origin) + b',"created_at_s":')
            except _Refused:  # e.g. a lone surrogate in the key: page_json says why
                pass
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

    ``key`` (not empty) and ``data`` are required; other fields are ignored.
    A missing ``origin`` becomes ``default_origin``, a missing
    ``created_at_s`` ``now_s`` (or the current time), a missing ``process``
    true. With ``default_origin=None`` (frames) origin and time are required
    and origin must not be empty.

    Raises:
        WireFormatError: a field is missing, empty or of the wrong type; the
            message names it.

    Example::

        page_from_fields({"key": "temp_c", "data": 21.5}, default_origin="arduino")
        page_from_fields(frame_fields, default_origin=None)   # everything required
    """
    key, origin = fields.get("key"), fields.get("origin")
    created, process = fields.get("created_at_s"), fields.get("process", True)
    if (  # the common case in one go; below, the first problem is named
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
    for name in ("origin", "created_at_s") if default_origin is None else ():
        if name not in fields:
            raise WireFormatError(f"the page under {key!r} has no {name!r} field")
    if "origin" not in fields:
        origin = default_origin
    if type(origin) is not str:
        raise _bad_type("origin", origin, "a JSON string")
    if default_origin is None and not origin:
        raise WireFormatError("field 'origin' of the page must not be empty")
    if "created_at_s" not in fields:
        created = time.time() if now_s is None else now_s
    elif type(created) not in (int, float):
        raise _bad_type("created_at_s", created, "a number")
    try:
        created_s = float(created)  # type: ignore[arg-type]
    except OverflowError:  # a whole number past a double's range
        raise WireFormatError("field 'created_at_s' of the page is too large") from None
    if type(process) is not bool:
        raise _bad_type("process", process, "a JSON bool (true or false)")
    return Page(key, fields["data"], origin, created_s, process)


# -- frames: a page (or a hello, beat, bye, proof) between two nodes ------------------


@dataclass(frozen=True)
class Hello:
    """The first frame on a link: who is on the other end.

    ``beat_s``: how often the sender promises a sign of life (a `Beat`) while
    it has nothing else to send, None for no promise (older nodes). ``bye``:
    it understands a `Bye` frame. ``system``: the system it belongs to (None
    in a version 1 hello), ``nonce``: its challenge, 64 hex digits from a node
    with a secret, else None.

    Example::

        decode_body(encode_hello("receiver", 1.0)[HEADER_BYTES:])
        # Hello(role='receiver', beat_s=1.0, bye=False, system=None, nonce=None)
    """

    role: str
    beat_s: Optional[float] = None
    bye: bool = False
    system: Optional[str] = None
    nonce: Optional[str] = None


@dataclass(frozen=True)
class Proof:
    """The answer to the peer's challenge: ``mac``, an HMAC-SHA256 in 64 lowercase hex digits.

    Example::

        decode_body(encode_proof("ab" * 32)[HEADER_BYTES:])   # Proof(mac='abab...')
    """

    mac: str


@dataclass(frozen=True)
class Beat:
    """A sign of life: "I am still here", sent on an otherwise quiet link.

    Example::

        decode_body(encode_beat()[HEADER_BYTES:])   # Beat()
    """


@dataclass(frozen=True)
class Bye:
    """The last frame before an orderly close: "my node is stopping, not lost".

    Example::

        decode_body(encode_bye()[HEADER_BYTES:])   # Bye()
    """


Message = Union[Page, Hello, Beat, Bye, Proof]
"""What a frame carries: a `Page`, a `Hello`, a `Beat`, a `Bye` or a `Proof`."""

_page_body = PageEncoder({"v": WIRE_VERSION, "kind": "page"})


def _frame(body: bytes, what: str) -> bytes:
    if len(body) > MAX_FRAME_BYTES:
        raise NotSerializableError(
            f"Cannot send {what}: it is {len(body):,} bytes of JSON, over the "
            f"{MAX_FRAME_BYTES:,}-byte frame limit. Send smaller pieces (for example "
            "one page per sensor reading, or a file path instead of file contents)."
        )
    return _HEADER.pack(len(body)) + body


def encode_page(page: Page) -> bytes:
    """One frame carrying ``page``.

    Raises:
        NotSerializableError: the data is not JSON (a set, a custom object,
            NaN, ...), naming the key and the type, or the frame is too big.

    Example::

        encode_page(Page("x", [1, 2], "robot", 1.5))
        # b'\\x00\\x00\\x00a{"v":1,"kind":"page","key":"x","data":[1,2],...}'
    """
    body = _page_body(page)
    if len(body) > MAX_FRAME_BYTES:  # the message is only built when it is needed
        _frame(body, f"the page under key {page.key!r}")  # raises
    return _HEADER.pack(len(body)) + body


def _encode(fields: Dict[str, Any], what: str) -> bytes:
    return _frame(dump_json(fields, what), what)


def encode_hello(
    role: str,
    beat_s: Optional[float] = None,
    bye: bool = False,
    system: Optional[str] = None,
    nonce: Optional[str] = None,
) -> bytes:
    """The hello frame a node sends first on every link (the fields: `Hello`).

    With a ``system`` or a ``nonce`` it is a version 2 hello; without
    either, the version 1 hello older nodes know.

    Example::

        encode_hello("receiver")   # b'\\x00\\x00\\x00,{"v":1,"kind":"hello","role":"receiver"}'
        encode_hello("receiver", 1.0, bye=True)   # ...,"beat_s":1.0,"bye":true}
        encode_hello("receiver", system="team7")  # {"v":2,...,"system":"team7"}
    """
    v2 = system is not None or nonce is not None
    fields: Dict[str, Any] = {
        "v": HELLO_VERSION if v2 else WIRE_VERSION,
        "kind": "hello",
        "role": role,
    }
    if beat_s is not None:
        fields["beat_s"] = beat_s
    if bye:
        fields["bye"] = True
    if v2:
        fields["system"] = system
        if nonce is not None:
            fields["nonce"] = nonce
    return _encode(fields, "the hello frame")


def encode_proof(mac: str) -> bytes:
    """The proof frame: the answer to the peer's challenge (``{"v":2,"kind":"proof",...}``).

    Example::

        encode_proof("ab" * 32)   # b'...{"v":2,"kind":"proof","mac":"abab..."}'
    """
    return _encode({"v": HELLO_VERSION, "kind": "proof", "mac": mac}, "the proof frame")


def encode_beat() -> bytes:
    """The beat frame: a sign of life on a quiet link (``{"v":1,"kind":"beat"}``).

    Example::

        encode_beat()   # b'\\x00\\x00\\x00\\x15{"v":1,"kind":"beat"}'
    """
    return b'\x00\x00\x00\x15{"v":1,"kind":"beat"}'


def encode_bye() -> bytes:
    """The bye frame, last before an orderly close, for a peer whose hello said ``"bye": true``.

    Example::

        encode_bye()   # b'\\x00\\x00\\x00\\x14{"v":1,"kind":"bye"}'
    """
    return b'\x00\x00\x00\x14{"v":1,"kind":"bye"}'


_HEX_DIGITS = 64  # a nonce (32 random bytes) and an HMAC-SHA256 are both this long in hex
_HEX = frozenset("0123456789abcdef")


def _is_hex(value: Any) -> bool:
    return type(value) is str and len(value) == _HEX_DIGITS and _HEX.issuperset(value)


# a field of a hello or proof: (is its value right, what it must be); each is optional but mac
_FIELD_RULES: Dict[str, Tuple[Callable[[Any], Any], str]] = {
    "beat_s": (
        lambda v: v is None or (type(v) in (int, float) and v > 0),
        "a number of seconds above 0",
    ),
    "bye": (lambda v: type(v) is bool, "true or false"),
    "system": (lambda v: v is None or (type(v) is str and v), "a non-empty string or null"),
    "nonce": (lambda v: v is None or _is_hex(v), f"{_HEX_DIGITS} lowercase hex digits"),
    "mac": (_is_hex, f"{_HEX_DIGITS} lowercase hex digits"),
}


def _field(obj: Dict[str, Any], kind: str, name: str, default: Any = None) -> Any:
    value = obj.get(name, default)
    right, must = _FIELD_RULES[name]
    if not right(value):
        raise WireFormatError(f"the {kind}'s {name!r} is {value!r:.40}; it must be {must}")
    return value


def decode_body(body: bytes) -> Message:
    """The `Page`, `Hello`, `Beat`, `Bye` or `Proof` in a frame's body (after the header).

    Raises:
        WireFormatError: the body is not strict JSON, not an object, has
            another version, an unknown kind, or a missing or mistyped field.
            The message says which; a link logs it and drops the frame (a bad
            frame before the peer's hello ends the link instead).

    Example::

        decode_body(b'{"v":1,"kind":"hello","role":"urov"}')   # Hello(role='urov', ...)
    """
    try:
        obj = load_object(body)
    except WireFormatError as error:
        raise WireFormatError(f"the body: {error}") from None
    version, kind = obj.get("v"), obj.get("kind")
    if type(version) is not int or not (
        version == WIRE_VERSION or (version == HELLO_VERSION and kind in ("hello", "proof"))
    ):
        raise WireFormatError(
            f"the frame has version {version!r:.40}; this SNR speaks version {WIRE_VERSION} "
            f"(and {HELLO_VERSION} for hellos and proofs; the 'v' field, a whole number); "
            "update the older side"
        )
    if kind == "page":
        return page_from_fields(obj, default_origin=None)
    if kind == "beat":
        return Beat()
    if kind == "bye":
        return Bye()
    if kind == "hello":
        return _decode_hello(obj, version)
    if kind == "proof":
        if version != HELLO_VERSION:
            raise WireFormatError(f"a proof frame must have version {HELLO_VERSION}")
        return Proof(_field(obj, "proof", "mac"))
    raise WireFormatError(
        f"unknown frame kind {kind!r:.40}; known kinds are 'page', 'hello', 'beat', 'bye' "
        "and 'proof'"
    )


def _decode_hello(obj: Dict[str, Any], version: int) -> Hello:
    if "role" not in obj:
        raise WireFormatError("a hello frame has no 'role' field")
    role = obj["role"]
    if type(role) is not str:
        raise WireFormatError(
            f"field 'role' of a hello frame must be a JSON string, not "
            f"{type(role).__name__} {role!r:.40}"
        )
    if not role:
        raise WireFormatError("field 'role' of a hello frame must not be empty")
    beat_s, bye = _field(obj, "hello", "beat_s"), _field(obj, "hello", "bye", False)
    try:
        beat_s = None if beat_s is None else float(beat_s)
    except OverflowError:  # a whole number past a double's range
        raise WireFormatError(
            "the hello's 'beat_s' is a whole number too large for a double; it must "
            "be a number of seconds above 0"
        ) from None
    if version == WIRE_VERSION:
        return Hello(role, beat_s, bye)  # the first hello: no system, no challenge
    return Hello(role, beat_s, bye, _field(obj, "hello", "system"), _field(obj, "hello", "nonce"))


def _too_long(length: int, limit: int) -> WireFormatError:
    return WireFormatError(
        f"a length header says {length:,} bytes, over the {limit:,}-byte maximum frame size"
    )


class FrameDecoder:
    """Cuts a byte stream into frame bodies, however the bytes arrive.

    A ``recv`` may return half a frame or several: give every chunk to
    `cut_frames` (the links do), or `feed` it and take the bodies with
    `next_frame` until it returns None.

    Example::

        decoder = FrameDecoder()
        decoder.feed(frame[:3])
        decoder.next_frame()        # None: not all there yet
        decoder.feed(frame[3:])
        decoder.next_frame()        # the body
    """

    def __init__(self, max_frame_bytes: int = MAX_FRAME_BYTES) -> None:
        self.max_frame_bytes = max_frame_bytes
        self._buffer = bytearray()  # the beginning of a frame still arriving
        self._bodies: List[bytes] = []  # fed, not yet taken by next_frame
        self._error: Optional[WireFormatError] = None  # a bad header fed, raised after them

    def feed(self, data: bytes) -> None:
        """Add bytes received from the peer (then take the bodies with `next_frame`)."""
        try:
            self.cut_frames(data, self._bodies)
        except WireFormatError as error:
            self._error = error

    def next_frame(self) -> Optional[bytes]:
        """The next whole body fed, or None until more bytes arrive.

        Raises:
            WireFormatError: the length header is over the maximum frame size.
                The stream cannot be trusted after that: reset the connection.
        """
        if self._bodies:
            return self._bodies.pop(0)
        if self._error is not None:
            raise self._error
        return None

    def cut_frames(self, data: bytes, bodies: List[bytes]) -> None:
        """Add ``data`` and append every whole body now available to ``bodies``, in order.

        Raises:
            WireFormatError: a length header is over the maximum frame size;
                ``bodies`` holds the whole frames before it. Reset the connection.

        Example::

            bodies: List[bytes] = []
            decoder.cut_frames(frame + frame[:3], bodies)   # [body]; 3 bytes wait
        """
        limit = self.max_frame_bytes
        if self._buffer:  # a frame began in an earlier chunk: wait for all of it
            buffer = self._buffer
            buffer += data
            if len(buffer) < HEADER_BYTES:
                return
            (length,) = _HEADER.unpack_from(buffer, 0)
            if length > limit:
                raise _too_long(length, limit)
            if len(buffer) < HEADER_BYTES + length:
                return
            data, self._buffer = bytes(buffer), bytearray()
        start, size = 0, len(data)
        while size - start >= HEADER_BYTES:
            (length,) = _HEADER.unpack_from(data, start)
            if length > limit:
                raise _too_long(length, limit)
            end = start + HEADER_BYTES + length
            if end > size:
                break
            bodies.append(data[start + HEADER_BYTES : end])
            start = end
        if start < size:  # the beginning of the next frame
            self._buffer = bytearray(data[start:])

    def pending_bytes(self) -> int:
        """Bytes of an unfinished frame (non-zero at EOF means it was cut short)."""
        return len(self._buffer)


# -- the JSON-lines format of recordings and serial links ------------------------------


def header_line() -> str:
    """The header line (without its newline) that starts a recording or serial link.

    Example::

        header_line()   # '{"format":"snr-pages","version":1}'
    """
    return _ENCODER.encode({"format": FORMAT_NAME, "version": FORMAT_VERSION})  # no backend needed


_line_encoder = PageEncoder({}, to="to a recording or serial link")


def page_to_line(page: Page) -> str:
    """One page as one line of JSON (without the newline); refused as `page_json` refuses it.

    Example::

        page_to_line(Page("x", [1, 2], "robot", 0.5))
        # '{"key":"x","data":[1,2],"origin":"robot","created_at_s":0.5,"process":true}'
    """
    return _line_encoder(page).decode("ascii")


decode_line = load_object
"""The JSON object on one line (a page or a header): `load_object`.

Example: ``decode_line('{"key":"x","data":1}')`` is ``{'key': 'x', 'data': 1}``.
"""


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
