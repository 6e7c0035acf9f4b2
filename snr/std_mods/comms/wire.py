"""The SNR wire format: how a page crosses between two nodes (docs/wire-format.md).

A *frame* is a 4-byte big-endian unsigned length ``N`` followed by ``N`` bytes
of UTF-8 JSON text (the *body*). Every body is a JSON object with a version
``"v": 1`` and a ``"kind"``:

* ``"hello"``: the first frame each side sends; names its role.
* ``"page"``: one page, with the fields of `Page`.

Example::

    frame = encode_page(Page("depth_m", 3.2, origin="urov", created_at_s=1700000000.0))
    decoder = FrameDecoder()
    decoder.feed(frame)
    decode_body(decoder.next_frame())   # Page('depth_m', 3.2, 'urov', 1700000000.0, True)

The stdlib ``json`` module does the work: it is about 30 times faster than
dataclasses-json, and the bytes are exactly what the spec says. Nothing is
ever unpickled or evaluated, so a bad frame can only be *wrong*, never harmful.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass
from typing import Any, Dict, NoReturn, Optional, Union

from snr.prelude import NotSerializableError, Page, WireFormatError

__all__ = [
    "HEADER_BYTES",
    "MAX_FRAME_BYTES",
    "WIRE_VERSION",
    "Beat",
    "FrameDecoder",
    "Hello",
    "Message",
    "decode_body",
    "encode_beat",
    "encode_frame",
    "encode_hello",
    "encode_page",
]

WIRE_VERSION = 1
"""The ``"v"`` field of every frame this SNR writes and the only one it reads."""

HEADER_BYTES = 4
"""Length of the frame header: an unsigned 32-bit big-endian body length."""

MAX_FRAME_BYTES = 16 * 1024 * 1024
"""Largest body accepted or sent (16 MiB); a longer length header resets the link."""

_HEADER = struct.Struct(">I")
# Compact separators, strict JSON (no NaN/Infinity), ASCII output (valid UTF-8).
_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)


def _reject_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not valid JSON")


_DECODER = json.JSONDecoder(parse_constant=_reject_constant)


@dataclass(frozen=True)
class Hello:
    """The first frame on a link: who is on the other end.

    ``beat_s`` is how often the sender promises a sign of life while it has
    nothing else to send (a `Beat`); None from a peer that makes no promise
    (older SNR nodes, or a program that does not send beats).

    Example::

        decode_body(encode_hello("receiver", 1.0)[HEADER_BYTES:])
        # Hello(role='receiver', beat_s=1.0)
    """

    role: str
    beat_s: Optional[float] = None


@dataclass(frozen=True)
class Beat:
    """A sign of life: "I am still here", sent on an otherwise quiet link.

    Example::

        decode_body(encode_beat()[HEADER_BYTES:])   # Beat()
    """


Message = Union[Page, Hello, Beat]
"""What a frame carries: a `Page`, a `Hello` or a `Beat`."""


def encode_frame(body: bytes) -> bytes:
    """``body`` with its 4-byte length header in front: one frame, ready to send.

    Example::

        encode_frame(b'{}')   # b'\\x00\\x00\\x00\\x02{}'
    """
    return _HEADER.pack(len(body)) + body


def _encode(fields: Dict[str, Any], what: str) -> bytes:
    body = _ENCODER.encode(fields).encode("utf-8")
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
    fields = {
        "v": WIRE_VERSION,
        "kind": "page",
        "key": page.key,
        "data": page.data,
        "origin": page.origin,
        "created_at_s": page.created_at_s,
        "process": page.process,
    }
    try:
        return _encode(fields, f"the page under key {page.key!r}")
    except (TypeError, ValueError, RecursionError) as error:
        raise NotSerializableError(
            f"Cannot send the page under key {page.key!r} from {page.origin!r}: its data "
            f"is a {type(page.data).__name__} that JSON cannot carry ({error}). Only "
            "JSON values cross between nodes: numbers (not NaN or infinity), strings, "
            "bools, None, lists and dicts with string keys. Convert it first, e.g. "
            "list(my_set) or dataclasses.asdict(obj)."
        ) from error


def encode_hello(role: str, beat_s: Optional[float] = None) -> bytes:
    """The hello frame a node sends first on every link.

    With ``beat_s`` the node promises a beat at least that often while it has
    nothing else to send, so the peer can tell a silent link from a dead one.

    Example::

        encode_hello("receiver")   # b'\\x00\\x00\\x00,{"v":1,"kind":"hello","role":"receiver"}'
        encode_hello("receiver", 1.0)   # ...,"role":"receiver","beat_s":1.0}
    """
    fields: Dict[str, Any] = {"v": WIRE_VERSION, "kind": "hello", "role": role}
    if beat_s is not None:
        fields["beat_s"] = beat_s
    return _encode(fields, "the hello frame")


_BEAT_FRAME = encode_frame(b'{"v":1,"kind":"beat"}')


def encode_beat() -> bytes:
    """The beat frame: a sign of life on a quiet link (``{"v":1,"kind":"beat"}``).

    Example::

        encode_beat()   # b'\\x00\\x00\\x00\\x15{"v":1,"kind":"beat"}'
    """
    return _BEAT_FRAME


def _field(obj: Dict[str, Any], name: str, kind: type, what: str) -> Any:
    if name not in obj:
        raise WireFormatError(f"a {what} frame has no {name!r} field")
    value = obj[name]
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise WireFormatError(
                f"field {name!r} of a {what} frame must be a number, "
                f"not {type(value).__name__} {value!r:.40}"
            )
        try:
            return float(value)
        except OverflowError:
            raise WireFormatError(f"field {name!r} of a {what} frame is too large") from None
    if not isinstance(value, kind):
        raise WireFormatError(
            f"field {name!r} of a {what} frame must be a JSON "
            f"{'string' if kind is str else 'bool'}, not {type(value).__name__} {value!r:.40}"
        )
    return value


def _non_empty(value: str, name: str, what: str) -> str:
    if not value:
        raise WireFormatError(f"field {name!r} of a {what} frame must not be empty")
    return value


def decode_body(body: bytes) -> Message:
    """The `Page` or `Hello` in one frame's body (the bytes after the header).

    Raises:
        WireFormatError: the body is not UTF-8, not JSON, not an object, has
            another version, an unknown kind, or a missing or mistyped field.
            The message says which; the caller logs it and drops the frame.

    Example::

        decode_body(b'{"v":1,"kind":"hello","role":"urov"}')   # Hello(role='urov')
    """
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError as error:
        raise WireFormatError(f"the body is not UTF-8 text ({error})") from None
    try:
        obj = _DECODER.decode(text)
    except ValueError as error:  # json.JSONDecodeError and NaN/Infinity
        raise WireFormatError(f"the body is not JSON ({error}): {text[:60]!r}") from None
    except RecursionError:
        raise WireFormatError("the body nests lists or objects too deeply") from None
    if not isinstance(obj, dict):
        raise WireFormatError(f"the body is a JSON {type(obj).__name__}, not an object")
    version = obj.get("v")
    if version != WIRE_VERSION or isinstance(version, bool):
        raise WireFormatError(
            f"the frame has version {version!r}; this SNR speaks version {WIRE_VERSION} "
            "(the 'v' field); update the older side"
        )
    kind = obj.get("kind")
    if kind == "page":
        return _decode_page(obj)
    if kind == "beat":
        return Beat()
    if kind == "hello":
        role = _non_empty(_field(obj, "role", str, "hello"), "role", "hello")
        beat_s = obj.get("beat_s")
        if beat_s is None:
            return Hello(role)
        if isinstance(beat_s, bool) or not isinstance(beat_s, (int, float)) or not beat_s > 0:
            raise WireFormatError(
                f"the hello's 'beat_s' is {beat_s!r}; it must be a number of seconds above 0"
            )
        return Hello(role, float(beat_s))
    raise WireFormatError(
        f"unknown frame kind {kind!r}; known kinds are 'page', 'hello' and 'beat'"
    )


def _decode_page(obj: Dict[str, Any]) -> Page:
    key, origin = obj.get("key"), obj.get("origin")
    created, process = obj.get("created_at_s"), obj.get("process", True)
    # The common case, checked in one go; the slow path below names the problem.
    if (
        type(key) is str
        and key
        and type(origin) is str
        and origin
        and type(created) is float
        and type(process) is bool
        and "data" in obj
    ):
        return Page(key, obj["data"], origin, float(created), process)
    if "data" not in obj:
        raise WireFormatError("a page frame has no 'data' field")
    return Page(
        key=_non_empty(_field(obj, "key", str, "page"), "key", "page"),
        data=obj["data"],
        origin=_non_empty(_field(obj, "origin", str, "page"), "origin", "page"),
        created_at_s=_field(obj, "created_at_s", float, "page"),
        process=_field(obj, "process", bool, "page") if "process" in obj else True,
    )


class FrameDecoder:
    """Cuts a byte stream into frame bodies, however the bytes arrive.

    A ``recv`` may return half a frame or several frames; feed every chunk in
    and take whole bodies out until ``next_frame()`` returns None.

    Example::

        decoder = FrameDecoder()
        decoder.feed(frame[:3])
        decoder.next_frame()        # None: not all there yet
        decoder.feed(frame[3:])
        decoder.next_frame()        # the body
    """

    def __init__(self, max_frame_bytes: int = MAX_FRAME_BYTES) -> None:
        self.max_frame_bytes = max_frame_bytes
        self._buffer = bytearray()
        self._start = 0  # where the next frame begins in _buffer

    def feed(self, data: bytes) -> None:
        """Add bytes received from the peer."""
        self._buffer += data

    def next_frame(self) -> Optional[bytes]:
        """The next whole body, or None until more bytes arrive.

        Raises:
            WireFormatError: the length header is over the maximum frame size.
                The stream cannot be trusted after that: reset the connection.
        """
        buffer, start = self._buffer, self._start
        if len(buffer) - start >= HEADER_BYTES:
            (length,) = _HEADER.unpack_from(buffer, start)
            if length > self.max_frame_bytes:
                raise WireFormatError(
                    f"a length header says {length:,} bytes, over the "
                    f"{self.max_frame_bytes:,}-byte maximum frame size"
                )
            end = start + HEADER_BYTES + length
            if len(buffer) >= end:
                self._start = end
                return bytes(buffer[start + HEADER_BYTES : end])
        if start:  # drop what has been consumed, once per chunk
            del buffer[:start]
            self._start = 0
        return None

    def pending_bytes(self) -> int:
        """Bytes of an unfinished frame (non-zero at EOF means it was cut short)."""
        return len(self._buffer) - self._start
