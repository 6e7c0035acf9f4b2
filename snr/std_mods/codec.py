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

Two JSON backends do the work: the standard library's ``json`` and, when it
is installed (``pip install 'snr-robotics[fast]'``), ``orjson``, several times faster.
The backends differ (orjson writes NaN as ``null``, writes non-ASCII text as
raw UTF-8, formats small floats differently, rejects some inputs that ``json``
accepts), so the orjson path is taken only where its result is known to be the
same; everything else goes through ``json``. Either way the bytes written and
the inputs rejected are exactly those of ``docs/wire-format.md``. Set the
environment variable ``SNR_JSON=json`` (or call ``use_backend("json")``) to
use the standard library only.

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
    Sequence,
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
_BIG = float(2**63)  # orjson reads integers beyond 64 bits as floats; json keeps them exact
_PLAIN = frozenset((str, int, float, bool, type(None)))
_LONE_SURROGATE = re.compile("[\ud800-\udfff]")
_TOO_DEEP = f"it nests arrays and objects more than {MAX_DEPTH} deep"


# -- the two backends ---------------------------------------------------------------


def _reject_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not a JSON number")


_STD_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)
# `_STD_ENCODER`'s own C encoder, made once: `encode` makes a new one for every
# call. Without the circular check (a list that holds itself raises
# RecursionError, and `page_json` then gives the verdict); None where json has
# no C speed-ups. Returns the JSON text in pieces.
_std_c_encoder: Any = getattr(json.encoder, "c_make_encoder", None)
_STD_PIECES: Optional[Callable[[Any, int], Sequence[str]]] = (
    None
    if _std_c_encoder is None
    else _std_c_encoder(
        None,
        _STD_ENCODER.default,
        json.encoder.encode_basestring_ascii,
        None,
        ":",
        ",",
        False,
        False,
        False,
    )
)
_STD_DECODER = json.JSONDecoder(parse_constant=_reject_constant)
# Reads one value at an index: (value, where it ended). Set by JSONDecoder's
# __init__ (the C scanner where there is one), though typeshed does not list it.
_STD_SCAN: Callable[[str, int], Tuple[Any, int]] = _STD_DECODER.scan_once  # type: ignore[attr-defined]


class _Refused(Exception):
    """Data JSON cannot hold, with the reason (turned into NotSerializableError)."""


def _problem(value: Any, strings: bool, limit: float) -> Optional[str]:
    """Why a decoded value breaks the rules, or None.

    Checks the nesting depth, numbers (``abs(x) < limit``: ``inf`` rejects
    infinity only) and, when ``strings``, lone surrogates in strings and keys.
    Decoded JSON holds only dict, list, str, int, float, bool and None.
    """
    stack: List[Tuple[Any, int]] = [(value, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            return _TOO_DEEP
        if type(node) is dict:
            if strings:
                for key in node:
                    if _LONE_SURROGATE.search(key):
                        return f"the key {key[:40]!r} holds a lone surrogate, which is not text"
            items: Any = node.values()
        elif type(node) is list:
            items = node
            if len(node) > 8:  # an array of readings: all numbers are checked at C speed
                try:
                    if max(map(abs, node)) < limit:
                        continue
                except TypeError:  # not all numbers: one by one below
                    pass
        else:
            items = (node,)
        for item in items:
            kind = type(item)
            if kind is float or kind is int:
                if not -limit < item < limit:
                    return f"the number {item!r:.40} is out of range (infinity or too large)"
            elif kind is list or kind is dict:
                stack.append((item, depth + 1))
            elif strings and kind is str and _LONE_SURROGATE.search(item):
                return f"the string {item[:40]!r} holds a lone surrogate, which is not text"
    return None


# A number can only overflow a double with an exponent of 3 digits or more, or
# with 200 digits or more before its point (a 2-digit exponent adds at most 99).
# Looked for in a copy with every digit made 0, E made e and + removed; strings
# may match too (harmless: the decoded value is then checked). The same for
# integers beyond 64 bits (19 digits or more).
_ZEROED = bytes.maketrans(b"123456789E", b"000000000e")
_BIG_EXPONENT = b"e000"
_LONG_NUMBER = b"0" * 200
_MAY_EXCEED_64_BITS = b"0" * 19
# Valid JSON nested deeper than MAX_DEPTH opens (and closes) more than MAX_DEPTH
# arrays or objects: anything shorter cannot be too deep, and is not counted.
_MIN_TOO_DEEP_BYTES = 2 * (MAX_DEPTH + 1)


def _as_bytes(raw: Text) -> bytes:
    if type(raw) is bytes:
        return raw
    return raw.encode("utf-8", "surrogatepass") if isinstance(raw, str) else bytes(raw)


def _load_std(raw: Text) -> Any:
    data = raw if type(raw) is bytes else _as_bytes(raw)
    strings = b"\\ud" in data or b"\\uD" in data
    if isinstance(raw, str):
        text = raw
        strings = strings or not text.isascii()
    else:
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as error:
            raise WireFormatError(f"it is not UTF-8 text ({error})") from None
    try:
        # The usual frame is one value with nothing around it: the decoder's
        # scanner reads it without `decode`'s two calls and two regex matches
        # (0.5 us of a page's 2.7). Anything else (whitespace around it, an
        # error) goes through `decode`, which gives the verdict and the message.
        try:
            obj, end = _STD_SCAN(text, 0)
            whole = end == len(text)
        except (StopIteration, ValueError):
            whole = False
        if not whole:
            obj = _STD_DECODER.decode(text)
    except ValueError as error:  # json.JSONDecodeError, NaN/Infinity, huge integers
        raise WireFormatError(f"it is not JSON ({error}): {text[:60]!r}") from None
    except RecursionError:
        raise WireFormatError(_TOO_DEEP) from None
    zeroed = data.translate(_ZEROED, b"+")
    if (
        strings
        or _BIG_EXPONENT in zeroed
        or _LONG_NUMBER in zeroed
        or (len(data) >= _MIN_TOO_DEEP_BYTES and data.count(b"[") + data.count(b"{") > MAX_DEPTH)
    ):
        problem = _problem(obj, strings, math.inf)
        if problem is not None:
            raise WireFormatError(f"it is not valid JSON for SNR: {problem}")
    return obj


def _load_orjson(raw: Text) -> Any:
    assert _orjson is not None
    try:
        obj = _orjson.loads(raw)
    except _orjson.JSONDecodeError:
        return _load_std(raw)  # the stdlib path gives the verdict and the message
    # orjson rejects NaN, infinity and lone surrogates itself, but reads
    # integers beyond 64 bits as floats: such a number is re-read by json.
    data = raw if type(raw) is bytes else _as_bytes(raw)
    if (
        _MAY_EXCEED_64_BITS in data.translate(_ZEROED, b"+")
        or (len(data) >= _MIN_TOO_DEEP_BYTES and data.count(b"[") + data.count(b"{") > MAX_DEPTH)
    ) and _problem(obj, False, _BIG) is not None:
        return _load_std(raw)
    return obj


def _dump_std(obj: Any) -> bytes:
    try:
        text = _STD_ENCODER.encode(obj)
    except (TypeError, ValueError) as error:
        raise _Refused(str(error)) from error
    except RecursionError:
        raise _Refused(f"data nests lists and dicts more than {_DATA_DEPTH} deep") from None
    if text.count("[") + text.count("{") > MAX_DEPTH or "\\ud" in text:
        # Possibly too deep, or a surrogate: refuse what a reader would reject.
        try:
            problem = _problem(_STD_DECODER.decode(text), True, math.inf)
        except RecursionError:
            problem = _TOO_DEEP
        if problem == _TOO_DEEP:
            raise _Refused(f"data nests lists and dicts more than {_DATA_DEPTH} deep")
        if problem is not None:
            raise _Refused(problem)
    return text.encode("ascii")


def _plain(value: Any) -> bool:
    """True when ``value`` holds only exact JSON types: orjson writes it as json does.

    False, too, for data nested deeper than `MAX_DEPTH` (or containing itself,
    which is endlessly deep): json then gives the verdict.
    """
    kind = type(value)
    if kind in _PLAIN:
        return True
    stack = [(value, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            return False
        kind = type(node)
        if kind is dict:
            if node and set(map(type, node)) != {str}:
                return False
            node = node.values()
        elif kind is not list and kind is not tuple:
            return False
        types = set(map(type, node))
        if types <= _PLAIN:
            continue
        if not types <= _PLAIN | {list, tuple, dict}:
            return False
        stack.extend((item, depth + 1) for item in node if type(item) not in _PLAIN)
    return True


# Where orjson's output may differ from json's: NaN/inf written as null, small
# floats (0.00001 vs 1e-05, 1e-7 vs 1e-07), non-ASCII text and DEL unescaped.
_ORJSON_SUSPECT = (b"null", b"e-", b"0.0000", b"\x7f")


def _dump_orjson(obj: Any) -> bytes:
    assert _orjson is not None
    try:
        out: bytes = _orjson.dumps(obj)
    except TypeError:  # big integers, non-str keys, surrogates: json decides
        return _dump_std(obj)
    if (
        not out.isascii()
        or b"null" in out  # the suspects of _ORJSON_SUSPECT, one by one: no generator
        or b"e-" in out
        or b"0.0000" in out
        or b"\x7f" in out
        or (len(out) >= _MIN_TOO_DEEP_BYTES and out.count(b"[") + out.count(b"{") > MAX_DEPTH)
    ):
        return _dump_std(obj)
    return out


def _exact(values: Iterable[Any], levels: int = 2) -> bool:
    """True when orjson writes every one of ``values`` exactly as json does, known without writing.

    That holds for ASCII text without DEL, finite floats that are 0 or at
    least 1e-4 in size (orjson writes NaN as null and smaller ones as
    ``0.00001``/``1e-7`` where json writes ``1e-05``/``1e-07``), ints, bools
    and None; and for dicts and lists of up to `_EXACT_MAX_ITEMS` such
    values (keys included), nested up to ``levels`` deep. A few values are
    checked here faster than orjson's output is searched for every suspect.
    Integers beyond 64 bits and non-str keys pass, but orjson refuses them
    (TypeError). Example: ``_exact([{"seq": 1, "value": 0.5}])`` is True.
    """
    for value in values:
        kind = type(value)
        if kind is str:
            if not value.isascii() or "\x7f" in value:
                return False
        elif kind is float:
            # value - value is NaN for NaN and infinity; 0 < |value| < 1e-4 is tiny
            if value - value != 0.0 or (-1e-4 < value < 1e-4 and value != 0.0):
                return False
        elif kind is int or kind is bool or value is None:
            continue
        elif kind is dict:
            if not (
                levels
                and len(value) <= _EXACT_MAX_ITEMS
                and _exact(value, 0)
                and _exact(value.values(), levels - 1)
            ):
                return False
        elif kind is list or kind is tuple:
            if not (levels and len(value) <= _EXACT_MAX_ITEMS and _exact(value, levels - 1)):
                return False
        else:
            return False
    return True


_EXACT_MAX_ITEMS = 16  # above this, writing and searching the output is faster


def _exact_data(data: Any) -> bool:
    """``_exact((data,))`` for a page's data, one call less for a number or a small dict.

    Most pages hold a number or a small dict of numbers and names: a float is
    checked here, a small dict by `_exact` on its keys and on its values
    directly, anything else by `_exact` itself (the same verdict either way).
    Example: ``_exact_data({"seq": 1, "value": 0.5})`` is True.
    """
    kind = data.__class__
    if kind is float:
        return data - data == 0.0 and not (-1e-4 < data < 1e-4 and data != 0.0)
    if kind is int or kind is bool or data is None:
        return True
    if kind is dict and len(data) <= _EXACT_MAX_ITEMS:
        return _exact(data, 0) and _exact(data.values(), 1)
    return _exact((data,))


def _dump_exact(obj: Mapping[str, Any]) -> bytes:
    """orjson's bytes for ``obj``, whose values passed `_exact`; json's if orjson refuses."""
    assert _orjson is not None
    try:
        out: bytes = _orjson.dumps(obj)
    except TypeError:  # integers beyond 64 bits, non-str keys: json decides
        return _dump_std(obj)
    return out


_load: Callable[[Text], Any] = _load_std
_dump_plain: Callable[[Any], bytes] = _dump_std
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
    global _load, _dump_plain, _backend
    if name is None:
        name = os.environ.get(BACKEND_ENV_VAR, "").strip().lower() or (
            "orjson" if _orjson is not None else "json"
        )
    if name == "json":
        _load, _dump_plain = _load_std, _dump_std
    elif name == "orjson":
        if _orjson is None:
            raise ValueError(
                f"the orjson JSON backend is not installed ({BACKEND_ENV_VAR}=orjson?): "
                f"{install_hint('fast')}, or use 'json'"
            )
        _load, _dump_plain = _load_orjson, _dump_orjson
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
        return _dump_std(obj)
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
        return _dump_std(data)
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
    fields["data"] = data = page.data
    fields["origin"] = page.origin
    fields["created_at_s"] = page.created_at_s
    fields["process"] = page.process
    try:
        if (
            _dump_plain is _dump_orjson
            and type(page.key) is str
            and type(page.origin) is str
            and _exact(fields.values())
        ):
            # The usual robot page (a number, a short text, a small flat dict
            # or list): orjson's bytes are json's, no need to search them.
            return _dump_exact(fields)
        if (
            _dump_plain is not _dump_std
            and type(page.key) is str
            and type(page.origin) is str
            and type(page.created_at_s) in (float, int)
            and type(page.process) is bool
            and _plain(data)
        ):
            return _dump_plain(fields)
        return _dump_std(fields)
    except _Refused as error:
        raise not_serializable_error(page.key, data, to=to, reason=str(error)) from None


_MAX_KNOWN_PAGE_KINDS = 1024  # (key, origin) pairs a PageEncoder keeps the JSON around the data of


class PageEncoder:
    """`page_json` with fixed leading fields, faster for pages that come again and again.

    A node sends pages under a few keys, each from one origin, over and over:
    everything in the JSON of such a page except the data and the time is the
    same every time. The text before the data and between the data and the
    time is made once per key and origin and kept (up to 1,024 pairs; then it
    starts again), so a page costs the JSON of its data and time and a join:
    two orjson calls, or one call of json's C encoder (made once, where
    `json.dumps` makes one a call) and the time's ``repr``. The bytes are
    exactly `page_json`'s: the short path is taken only where `page_json`
    would take the same output as it is (the same checks), and everything
    else (deep data, a surrogate, anything json refuses) goes through
    `page_json` itself.

    Example::

        encode = PageEncoder({"v": 1, "kind": "page"})
        encode(Page("x", 1.5, "robot", 0.5))
        # b'{"v":1,"kind":"page","key":"x","data":1.5,"origin":"robot","created_at_s":0.5,...}'
    """

    def __init__(self, head: Mapping[str, Any], to: str = "to another node") -> None:
        self.head = dict(head)
        self.to = to
        self._parts: Dict[Tuple[str, str], Optional[Tuple[bytes, bytes]]] = {}
        self._std_parts: Dict[Tuple[str, str], Optional[Tuple[str, str]]] = {}

    def __call__(self, page: Page) -> bytes:
        """The page's JSON; raises `NotSerializableError` as `page_json` does."""
        key, origin, data, created = page.key, page.origin, page.data, page.created_at_s
        if (
            _dump_plain is _dump_orjson
            and type(key) is str
            and type(origin) is str
            and type(page.process) is bool
        ):
            try:
                parts = self._parts[(key, origin)]
            except KeyError:
                parts = self._learn(key, origin)
            # _exact((data, created)), with the time (a float, or an int) checked
            # inline: one call less for every page sent.
            if (
                parts is not None
                and (
                    created.__class__ is int
                    or (
                        created.__class__ is float
                        and created - created == 0.0
                        and (created >= 1e-4 or created <= -1e-4 or created == 0.0)
                    )
                )
                and _exact_data(data)
            ):
                assert _orjson is not None
                try:
                    data_json, created_json = _orjson.dumps(data), _orjson.dumps(created)
                except TypeError:  # integers beyond 64 bits, non-str keys: json decides
                    return page_json(page, self.head, self.to)
                tail = b',"process":true}' if page.process else b',"process":false}'
                return b"".join((parts[0], data_json, parts[1], created_json, tail))
        elif (
            _dump_plain is _dump_std
            and _STD_PIECES is not None
            and type(key) is str
            and type(origin) is str
            and type(page.process) is bool
            and (
                created.__class__ is int
                or (created.__class__ is float and created - created == 0.0)
            )
        ):
            try:
                text_parts = self._std_parts[(key, origin)]
            except KeyError:
                text_parts = self._learn_std(key, origin)
            if text_parts is not None:
                try:
                    data_text = "".join(_STD_PIECES(data, 0))
                except (TypeError, ValueError, RecursionError):  # page_json says why
                    return page_json(page, self.head, self.to)
                # What _dump_std would look into (deep data, a surrogate): page_json decides.
                if (
                    "\\ud" not in data_text
                    and data_text.count("[") + data_text.count("{") < MAX_DEPTH
                ):
                    tail_text = ',"process":true}' if page.process else ',"process":false}'
                    return "".join(
                        (text_parts[0], data_text, text_parts[1], repr(created), tail_text)
                    ).encode("ascii")
        return page_json(page, self.head, self.to)

    def _learn_std(self, key: str, origin: str) -> Optional[Tuple[str, str]]:
        """`_learn` for the standard library's json: the same two pieces, as text."""
        if len(self._std_parts) >= _MAX_KNOWN_PAGE_KINDS:
            self._std_parts.clear()
        parts: Optional[Tuple[str, str]] = None
        try:
            before = _dump_std({**self.head, "key": key}).decode("ascii")[:-1] + ',"data":'
            between = ',"origin":' + _dump_std(origin).decode("ascii") + ',"created_at_s":'
            if "\\ud" not in before + between:  # a surrogate: page_json decides
                parts = (before, between)
        except _Refused:  # a head value json refuses: page_json says why
            parts = None
        self._std_parts[(key, origin)] = parts
        return parts

    def _learn(self, key: str, origin: str) -> Optional[Tuple[bytes, bytes]]:
        """The JSON before the data and between the data and the time (None: not exact)."""
        if len(self._parts) >= _MAX_KNOWN_PAGE_KINDS:
            self._parts.clear()
        parts: Optional[Tuple[bytes, bytes]] = None
        fields = {**self.head, "key": key}
        if _exact(fields.values()) and _exact((origin,)):
            assert _orjson is not None
            try:
                before = _orjson.dumps(fields)[:-1] + b',"data":'
                between = b',"origin":' + _orjson.dumps(origin) + b',"created_at_s":'
                parts = (before, between)
            except TypeError:  # a head value orjson refuses: page_json decides
                parts = None
        self._parts[(key, origin)] = parts
        return parts


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


# Lines carry no head: `page_json`'s bytes, with the JSON around the data kept
# per key and origin. Shared by every thread that writes lines: a race between
# two of them only makes a kept piece again.
_LINE_ENCODER = PageEncoder({}, to="to a recording or serial link")


def page_to_line(page: Page) -> str:
    """One page as one line of JSON (without the newline).

    Raises:
        NotSerializableError: the page's data is not JSON (a set, an object,
            NaN...); the message names the key, the part and the fix.

    Example::

        page_to_line(Page("x", [1, 2], "robot", 0.5))
        # '{"key":"x","data":[1,2],"origin":"robot","created_at_s":0.5,"process":true}'
    """
    return _LINE_ENCODER(page).decode("ascii")


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
