"""The SNR wire format: how a page crosses between two nodes (docs/wire-format.md).

A *frame* is a 4-byte big-endian unsigned length ``N`` followed by ``N`` bytes
of UTF-8 JSON text (the *body*). Every body is a JSON object with a version
``"v": 1`` and a ``"kind"``:

* ``"hello"``: the first frame each side sends; names its role (version 2 also
  its system and, with a secret, a challenge).
* ``"proof"``: the answer to the peer's challenge (version 2, with a secret).
* ``"page"``: one page, with the fields of `Page`.
* ``"beat"``: a sign of life on a quiet link.
* ``"bye"``: the last frame before an orderly close ("my node is stopping").

Example::

    frame = encode_page(Page("depth_m", 3.2, origin="urov", created_at_s=1700000000.0))
    decoder = FrameDecoder()
    decoder.feed(frame)
    decode_body(decoder.next_frame())   # Page('depth_m', 3.2, 'urov', 1700000000.0, True)

The JSON inside is the page codec's (``snr.std_mods.codec``): the same strict
rules, backends and error messages as recordings and serial links. This module
adds what only a byte stream needs: the version and kind fields, the length
header, and cutting a stream into frames. Nothing is ever unpickled or
evaluated, so a bad frame can only be *wrong*, never harmful.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Union

from snr.prelude import NotSerializableError, Page, WireFormatError
from snr.std_mods.codec import PageEncoder, dump_json, load_object, page_from_fields

__all__ = [
    "HEADER_BYTES",
    "HELLO_VERSION",
    "MAX_FRAME_BYTES",
    "WIRE_VERSION",
    "Beat",
    "Bye",
    "FrameDecoder",
    "Hello",
    "Message",
    "Proof",
    "decode_body",
    "encode_beat",
    "encode_bye",
    "encode_hello",
    "encode_page",
    "encode_proof",
]

WIRE_VERSION = 1
"""The ``"v"`` field of page, beat and bye frames, and of the first hello (no system)."""

HELLO_VERSION = 2
"""The ``"v"`` of the hello that names a system and may carry a challenge, and of proofs.

A node that names no system and has no secret still sends a version 1
hello, so older nodes understand it (docs/wire-format.md, section 3.1).
"""

HEADER_BYTES = 4
"""Length of the frame header: an unsigned 32-bit big-endian body length."""

MAX_FRAME_BYTES = 16 * 1024 * 1024
"""Largest body accepted or sent (16 MiB); a longer length header resets the link."""

_HEADER = struct.Struct(">I")
_page_body = PageEncoder({"v": WIRE_VERSION, "kind": "page"})


@dataclass(frozen=True)
class Hello:
    """The first frame on a link: who is on the other end.

    ``beat_s`` is how often the sender promises a sign of life while it has
    nothing else to send (a `Beat`); None from a peer that makes no promise
    (older SNR nodes, or a program that does not send beats). ``bye`` is
    true when the sender understands a `Bye` frame (older nodes do not, so
    they are never sent one). ``system`` is the system the sender belongs to
    (None from a version 1 hello, or one that names none), and ``nonce`` its
    challenge: 64 hex digits from a node with a secret, else None.

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
    """The answer to the peer's challenge: ``mac`` proves the sender knows the secret.

    64 lowercase hex digits of an HMAC-SHA256 (see ``handshake.proof_mac``).

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

    The peer then knows the end of the connection that follows is no fault.

    Example::

        decode_body(encode_bye()[HEADER_BYTES:])   # Bye()
    """


Message = Union[Page, Hello, Beat, Bye, Proof]
"""What a frame carries: a `Page`, a `Hello`, a `Beat`, a `Bye` or a `Proof`."""


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


def encode_hello(
    role: str,
    beat_s: Optional[float] = None,
    bye: bool = False,
    system: Optional[str] = None,
    nonce: Optional[str] = None,
) -> bytes:
    """The hello frame a node sends first on every link.

    With ``beat_s`` the node promises a beat at least that often while it has
    nothing else to send, so the peer can tell a silent link from a dead one.
    With ``bye`` it says it understands a bye frame. With a ``system`` or a
    ``nonce`` (a challenge, from a node with a secret) it is a version 2
    hello; without either, the version 1 hello older nodes know.

    Example::

        encode_hello("receiver")   # b'\\x00\\x00\\x00,{"v":1,"kind":"hello","role":"receiver"}'
        encode_hello("receiver", 1.0, bye=True)   # ...,"beat_s":1.0,"bye":true}
        encode_hello("receiver", system="team7")  # {"v":2,...,"system":"team7"}
    """
    version = HELLO_VERSION if system is not None or nonce is not None else WIRE_VERSION
    fields: Dict[str, Any] = {"v": version, "kind": "hello", "role": role}
    if beat_s is not None:
        fields["beat_s"] = beat_s
    if bye:
        fields["bye"] = True
    if version == HELLO_VERSION:
        fields["system"] = system
        if nonce is not None:
            fields["nonce"] = nonce
    return _frame(dump_json(fields, "the hello frame"), "the hello frame")


def encode_proof(mac: str) -> bytes:
    """The proof frame: the answer to the peer's challenge (``{"v":2,"kind":"proof",...}``).

    Example::

        encode_proof("ab" * 32)   # b'...{"v":2,"kind":"proof","mac":"abab..."}'
    """
    fields = {"v": HELLO_VERSION, "kind": "proof", "mac": mac}
    return _frame(dump_json(fields, "the proof frame"), "the proof frame")


_BEAT_FRAME = _frame(b'{"v":1,"kind":"beat"}', "a beat")


def encode_beat() -> bytes:
    """The beat frame: a sign of life on a quiet link (``{"v":1,"kind":"beat"}``).

    Example::

        encode_beat()   # b'\\x00\\x00\\x00\\x15{"v":1,"kind":"beat"}'
    """
    return _BEAT_FRAME


_BYE_FRAME = _frame(b'{"v":1,"kind":"bye"}', "a bye")


def encode_bye() -> bytes:
    """The bye frame: the last one before an orderly close (``{"v":1,"kind":"bye"}``).

    Send it only to a peer whose hello said ``"bye": true``.

    Example::

        encode_bye()   # b'\\x00\\x00\\x00\\x14{"v":1,"kind":"bye"}'
    """
    return _BYE_FRAME


def _non_empty(value: str, name: str, what: str) -> str:
    if not value:
        raise WireFormatError(f"field {name!r} of a {what} frame must not be empty")
    return value


def decode_body(body: bytes) -> Message:
    """The `Page`, `Hello`, `Beat` or `Bye` in one frame's body (the bytes after the header).

    Raises:
        WireFormatError: the body is not UTF-8, not strict JSON (NaN,
            ``1e999``, a lone surrogate, nesting too deep...), not an object,
            has another version, an unknown kind, or a missing or mistyped
            field. The message says which; the caller logs it and drops the frame.

    Example::

        decode_body(b'{"v":1,"kind":"hello","role":"urov"}')   # Hello(role='urov', ...)
    """
    try:
        obj = load_object(body)
    except WireFormatError as error:
        raise WireFormatError(f"the body: {error}") from None
    version = obj.get("v")
    kind = obj.get("kind")
    if type(version) is not int or not (
        version == WIRE_VERSION or (version == HELLO_VERSION and kind in ("hello", "proof"))
    ):
        raise WireFormatError(
            f"the frame has version {version!r:.40}; this SNR speaks version {WIRE_VERSION} "
            f"(and {HELLO_VERSION} for hellos and proofs; the 'v' field, a whole number); "
            "update the older side"
        )
    if kind == "proof":
        return _decode_proof(obj, version)
    if kind == "page":
        return page_from_fields(obj, default_origin=None)
    if kind == "beat":
        return Beat()
    if kind == "bye":
        return Bye()
    if kind == "hello":
        role = obj.get("role")
        if "role" not in obj:
            raise WireFormatError("a hello frame has no 'role' field")
        if type(role) is not str:
            raise WireFormatError(
                f"field 'role' of a hello frame must be a JSON string, not "
                f"{type(role).__name__} {role!r:.40}"
            )
        if not role:
            raise WireFormatError("field 'role' of a hello frame must not be empty")
        beat_s = obj.get("beat_s")
        if beat_s is not None and (
            isinstance(beat_s, bool) or not isinstance(beat_s, (int, float)) or not beat_s > 0
        ):
            raise WireFormatError(
                f"the hello's 'beat_s' is {beat_s!r:.40}; it must be a number of seconds above 0"
            )
        bye = obj.get("bye", False)
        if type(bye) is not bool:
            raise WireFormatError(f"the hello's 'bye' is {bye!r:.40}; it must be true or false")
        if beat_s is not None:
            try:
                beat_s = float(beat_s)  # a whole number past a double's range cannot be
            except OverflowError:
                raise WireFormatError(
                    "the hello's 'beat_s' is a whole number too large for a double; it must "
                    "be a number of seconds above 0"
                ) from None
        if version == WIRE_VERSION:
            return Hello(role, beat_s, bye)  # the first hello: no system, no challenge
        system = obj.get("system")
        if system is not None and (type(system) is not str or not system):
            raise WireFormatError(
                f"the hello's 'system' is {system!r:.40}; it must be a non-empty string or null"
            )
        nonce = obj.get("nonce")
        if nonce is not None and not _is_hex(nonce):
            raise WireFormatError(
                f"the hello's 'nonce' is {nonce!r:.40}; it must be {_HEX_DIGITS} lowercase "
                "hex digits"
            )
        return Hello(role, beat_s, bye, system, nonce)
    raise WireFormatError(
        f"unknown frame kind {kind!r:.40}; known kinds are 'page', 'hello', 'beat', 'bye' "
        "and 'proof'"
    )


_HEX_DIGITS = 64  # a nonce (32 random bytes) and an HMAC-SHA256 are both this long in hex
_HEX = frozenset("0123456789abcdef")


def _is_hex(value: object) -> bool:
    return type(value) is str and len(value) == _HEX_DIGITS and _HEX.issuperset(value)


def _decode_proof(obj: Dict[str, Any], version: object) -> Proof:
    if version != HELLO_VERSION:
        raise WireFormatError(f"a proof frame must have version {HELLO_VERSION}")
    mac = obj.get("mac")
    if not _is_hex(mac):
        raise WireFormatError(
            f"the proof's 'mac' is {mac!r:.40}; it must be {_HEX_DIGITS} lowercase hex digits"
        )
    assert isinstance(mac, str)
    return Proof(mac)


def _too_long(length: int, limit: int) -> str:
    return f"a length header says {length:,} bytes, over the {limit:,}-byte maximum frame size"


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
                raise WireFormatError(_too_long(length, self.max_frame_bytes))
            end = start + HEADER_BYTES + length
            if len(buffer) >= end:
                self._start = end
                return bytes(buffer[start + HEADER_BYTES : end])
        if start:  # drop what has been consumed, once per chunk
            del buffer[:start]
            self._start = 0
        return None

    def cut_frames(self, data: bytes, bodies: List[bytes]) -> None:
        """Add ``data`` and append every whole body now available to ``bodies``, in order.

        The same as `feed` followed by `next_frame` until it returns None, in
        one call: a read of whole frames (the usual case) is cut straight from
        ``data`` without going through the buffer.

        Raises:
            WireFormatError: a length header is over the maximum frame size.
                ``bodies`` then holds the whole frames before it; reset the
                connection.

        Example::

            bodies: List[bytes] = []
            decoder.cut_frames(frame + frame[:3], bodies)   # [body]; 3 bytes wait
        """
        limit = self.max_frame_bytes
        if len(self._buffer) != self._start:
            # Part of a frame waits (a big read usually ends mid-frame): complete
            # that one frame from the head of ``data``, then cut the rest
            # straight from ``data``, not through the buffer.
            buffer = self._buffer
            if self._start:
                del buffer[: self._start]
                self._start = 0
            if len(buffer) < HEADER_BYTES:
                taken = HEADER_BYTES - len(buffer)
                buffer += data[:taken]
                data = data[taken:]
                if len(buffer) < HEADER_BYTES:
                    return
            (length,) = _HEADER.unpack_from(buffer, 0)
            if length > limit:
                raise WireFormatError(_too_long(length, limit))
            taken = HEADER_BYTES + length - len(buffer)
            buffer += data[:taken]
            if len(buffer) < HEADER_BYTES + length:
                return  # the frame is not all there yet
            data = data[taken:]
            bodies.append(bytes(buffer[HEADER_BYTES:]))
        if self._start or self._buffer:  # everything buffered has been taken: start afresh
            self._buffer = bytearray()
            self._start = 0
        start, size = 0, len(data)
        while size - start >= HEADER_BYTES:
            (length,) = _HEADER.unpack_from(data, start)
            if length > limit:
                raise WireFormatError(_too_long(length, limit))
            end = start + HEADER_BYTES + length
            if end > size:
                break
            bodies.append(data[start + HEADER_BYTES : end])
            start = end
        if start < size:  # the beginning of the next frame
            self._buffer = bytearray(data[start:])
            self._start = 0

    def pending_bytes(self) -> int:
        """Bytes of an unfinished frame (non-zero at EOF means it was cut short)."""
        return len(self._buffer) - self._start
