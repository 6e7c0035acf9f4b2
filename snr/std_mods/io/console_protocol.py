"""The console protocol, ``snr-console/1``, and who may talk: see docs/console.md, "The protocol".

Console → node: lines of UTF-8 text (`LineReader`); node → console: frames of a
header ``snr-console/1 <status> <length>\\n`` and ``<length>`` bytes of text.

Example::

    Reply(Status.OK, "pong").encode()      # b'snr-console/1 ok 4\\npong'
"""

from __future__ import annotations

import enum
import json
import os
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, List, Optional, Tuple, Union

from snr.prelude import ConfigError, WireFormatError
from snr.prelude.errors import ConsoleConnectionError  # in the tree of every SNR error

__all__ = [
    "DEFAULT_CONSOLE_PORT",
    "MAX_LINE_BYTES",
    "MAX_REPLY_BYTES",
    "PROTOCOL",
    "SECRET_TOKEN_PURPOSE",
    "TOKEN_ENV_VAR",
    "ConsoleConnectionError",
    "ConsoleSession",
    "LineReader",
    "Reply",
    "ReplyDecoder",
    "Status",
    "check_listen_policy",
    "default_token",
    "is_loopback",
    "parse_address",
    "parse_values",
    "tokens_match",
]

PROTOCOL = "snr-console/1"
"""Name and version of the protocol; the first word of every reply header."""

DEFAULT_CONSOLE_PORT = 9123
"""The TCP port a `CommandReceiverFactory` listens on unless told otherwise."""

MAX_LINE_BYTES = 4096
"""Longest request line the node accepts (without its ``\\n``)."""

MAX_REPLY_BYTES = 1 << 20
"""Longest reply body the node sends; longer replies are cut with a note."""

_MAX_HEADER_BYTES = 64
_TRUNCATION_ROOM = 256  # the "(reply cut)" note added to a reply at the limit

TOKEN_ENV_VAR = "SNR_CONSOLE_TOKEN"
"""Environment variable holding the shared console token (node and console)."""

SECRET_TOKEN_PURPOSE = "console-token"
"""What the console token made from the node's secret is for (see `default_token`)."""


def default_token(token: Optional[str], where: str) -> Optional[str]:
    """The console token of a node or console that was given ``token`` (None: the default).

    ``token`` if given, else ``$SNR_CONSOLE_TOKEN`` if set, else a word made
    from the node's secret (``$SNR_SECRET`` or the secret file), else None:
    no token (docs/console.md, "Security").

    Raises:
        ConfigError: the secret is empty or its file cannot be read.

    Example::

        default_token("s3cret-word", "CommandReceiverFactory")   # 's3cret-word'
        default_token(None, "CommandReceiverFactory")   # None, or '9a1e...' with $SNR_SECRET
    """
    if token is not None:
        return token
    if os.environ.get(TOKEN_ENV_VAR):
        return os.environ[TOKEN_ENV_VAR]
    # Here, not at the top: it loads OpenSSL, and only a node with a secret needs it.
    from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, derived_word, find_secret

    secret = find_secret(FROM_ENVIRONMENT, where)
    return None if secret is None else derived_word(secret, SECRET_TOKEN_PURPOSE)


class Status(enum.Enum):
    """What kind of reply a frame is.

    Example::

        Reply(Status.ERROR, "Unknown command 'relaod'.")

    Members:
        HELLO: greeting after connecting; commands may follow.
        AUTH: greeting of a node that needs a token: send ``auth <token>`` first.
        OK: the command worked; the text says what happened.
        ERROR: the command was refused or failed; the text says why.
        BYE: the node closes the connection after this frame.
    """

    HELLO = "hello"
    AUTH = "auth"
    OK = "ok"
    ERROR = "error"
    BYE = "bye"


@dataclass(frozen=True)
class Reply:
    """One reply frame: a status and readable text.

    Example::

        Reply(Status.OK, "Reloaded 'counter'.").encode()
    """

    status: Status
    text: str

    def encode(self) -> bytes:
        """The frame's bytes; a body over `MAX_REPLY_BYTES` is cut with a note."""
        body = self.text.encode("utf-8")
        if len(body) > MAX_REPLY_BYTES:
            kept = body[:MAX_REPLY_BYTES].decode("utf-8", errors="ignore")
            cut = len(body) - len(kept.encode("utf-8"))
            body = f"{kept}\n... (reply cut: {cut} more bytes)".encode()
        return f"{PROTOCOL} {self.status.value} {len(body)}\n".encode("ascii") + body


class ConsoleSession(ABC):
    """One console the node is talking to: where a command's reply goes.

    A console loop hands each command line to the node with its session; the
    `CommandProcessorEndpoint` runs the command on the node's thread and calls
    ``session.send(reply)``, so ``send`` must be quick and never block or
    raise, even when the console has gone.

    Example::

        class PrintSession(ConsoleSession):
            def send(self, reply: Reply) -> None:
                print(reply.text)
    """

    @abstractmethod
    def send(self, reply: Reply) -> None:
        """Deliver ``reply`` to the console (a ``BYE`` reply also closes it)."""


class ReplyDecoder:
    """Turns the bytes a console receives into `Reply` frames.

    Feed it whatever ``recv`` returned; it keeps partial frames until the rest
    arrives.

    Example::

        decoder = ReplyDecoder()
        decoder.feed(b"snr-console/1 ok 5\\nhel")   # [] (waiting for the rest)
        decoder.feed(b"lo")                          # [Reply(Status.OK, 'hello')]
    """

    def __init__(self) -> None:
        self._buffer = bytearray()

    def feed(self, data: bytes) -> List[Reply]:
        """Every reply completed by ``data``.

        Raises:
            WireFormatError: the bytes are not this protocol (wrong header,
                unknown status, oversized frame, or text that is not UTF-8).
        """
        self._buffer += data
        replies: List[Reply] = []
        while True:  # a frame's header is read again until its body is all there
            newline = self._buffer.find(b"\n", 0, _MAX_HEADER_BYTES + 1)
            if newline < 0 and len(self._buffer) > _MAX_HEADER_BYTES:
                raise WireFormatError(_bad_header(bytes(self._buffer)))
            if newline < 0:
                return replies
            status, length = _parse_header(bytes(self._buffer[:newline]))
            end = newline + 1 + length
            if len(self._buffer) < end:
                return replies
            body = bytes(self._buffer[newline + 1 : end])
            del self._buffer[:end]
            try:
                replies.append(Reply(status, body.decode("utf-8")))
            except UnicodeDecodeError as error:
                raise WireFormatError(
                    f"A {status.value} reply is not UTF-8 text: {error}"
                ) from None


def _parse_header(header: bytes) -> Tuple[Status, int]:
    words = header.split()
    try:
        if len(words) != 3 or words[0] != PROTOCOL.encode() or not words[2].isdigit():
            raise ValueError
        status = Status(words[1].decode("ascii"))  # UnicodeDecodeError is a ValueError
    except ValueError:
        raise WireFormatError(_bad_header(header)) from None
    if int(words[2]) > MAX_REPLY_BYTES + _TRUNCATION_ROOM:
        raise WireFormatError(
            f"A reply announced {int(words[2])} bytes, more than the {MAX_REPLY_BYTES} "
            "a node sends; the stream is corrupt."
        )
    return status, int(words[2])


def _bad_header(header: bytes) -> str:
    return (
        f"Expected a reply header like '{PROTOCOL} ok 12', got {header[:40]!r}. "
        "Is this port an SNR console receiver (CommandReceiverFactory)?"
    )


class LineReader:
    """Cuts the bytes a console sends into request lines, as the protocol says.

    A line longer than `MAX_LINE_BYTES` is dropped up to its newline, and a
    line that is not UTF-8 is not run: each gets an ``error`` reply instead.

    Example::

        lines = LineReader()
        lines.feed(b"help\\nstats\\n")
        lines.next_request(), lines.next_request()   # ('help', 'stats')
    """

    def __init__(self) -> None:
        self.inbox = bytearray()  # bytes read, not yet taken as lines
        self._skipping = False  # dropping the rest of a line that was too long

    def feed(self, data: bytes) -> None:
        """Keep ``data`` until its lines are taken."""
        self.inbox += data

    def next_request(self, at_end: bool = False) -> Union[str, Reply, None]:
        """The next line (stripped), the ``error`` reply refusing it, or None: no line yet.

        ``at_end``: nothing more will come, so a last line without newline counts.
        """
        while True:
            newline = self.inbox.find(b"\n")
            if newline < 0 and at_end and self.inbox:
                newline = len(self.inbox)
            if newline < 0 and len(self.inbox) <= MAX_LINE_BYTES:
                return None
            if newline < 0:
                self.inbox.clear()
                skipping, self._skipping = self._skipping, True
                return None if skipping else _LINE_TOO_LONG
            raw = bytes(self.inbox[:newline])
            del self.inbox[: newline + 1]
            if self._skipping:  # the tail of a line already refused
                self._skipping = False
            elif len(raw) > MAX_LINE_BYTES:
                return _LINE_TOO_LONG
            else:
                try:
                    return raw.decode("utf-8").strip()
                except UnicodeDecodeError:
                    return Reply(Status.ERROR, "Ignored a line that is not UTF-8 text.")


_LINE_TOO_LONG = Reply(Status.ERROR, f"Ignored a line longer than {MAX_LINE_BYTES} bytes.")
_json_decoder = json.JSONDecoder()


def parse_values(text: str) -> List[Any]:
    """Values typed after a task's name: JSON literals where they parse, else words.

    Nothing is ever evaluated as Python: ``1`` is a number, ``[1, 2]`` a list,
    ``"a b"`` one string with a space, ``true``/``null`` are True/None, and
    any other word (``A``, ``3abc``) is a string.

    Example::

        parse_values('1 2.5 true "a b" [1, 2] {"k": 3} hello')
        # [1, 2.5, True, 'a b', [1, 2], {'k': 3}, 'hello']
    """
    values: List[Any] = []
    words = text.split()
    position = 0
    while words:
        position = text.index(words[0], position)
        try:
            value, stop = _json_decoder.raw_decode(text, position)
        except ValueError:
            stop = -1
        if stop == len(text) or (stop > position and text[stop].isspace()):
            values.append(value)  # it may span several words: "a b", [1, 2]
            words = text[stop:].split()
            position = stop
        else:
            values.append(words.pop(0))
            position += len(values[-1])
    return values


def parse_address(text: str, default_host: str = "127.0.0.1") -> Tuple[str, int]:
    """``"HOST:PORT"`` (or ``"PORT"``, or ``"[::1]:PORT"``) as ``(host, port)``.

    Raises:
        ValueError: with a sentence saying what a valid address looks like.

    Example::

        parse_address("robot.local:9123")   # ('robot.local', 9123)
        parse_address("9123")               # ('127.0.0.1', 9123)
    """
    host, _, port_text = text.strip().rpartition(":")
    host = host.strip("[]") or default_host
    if not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise ValueError(
            f"{text!r} is not a console address. Write HOST:PORT, e.g. 127.0.0.1:"
            f"{DEFAULT_CONSOLE_PORT}, with a port from 1 to 65535."
        )
    return host, int(port_text)


def is_loopback(host: str) -> bool:
    """True when ``host`` is reachable only from this machine.

    ``""`` and ``"0.0.0.0"`` mean every network interface, so they are not.

    Example::

        is_loopback("127.0.0.1"), is_loopback("0.0.0.0")   # (True, False)
    """
    import ipaddress  # here, not at the top: only a listening console needs it

    try:
        return host.lower() == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name (or ""): it may be reachable from outside


def check_listen_policy(host: str, token: Optional[str]) -> None:
    """Refuse to listen beyond this machine without a token; check the token.

    Raises:
        ConfigError: the host is not loopback and there is no token, or the
            token is empty, too long or has spaces.

    Example::

        check_listen_policy("127.0.0.1", None)         # fine
        check_listen_policy("0.0.0.0", None)           # ConfigError
        check_listen_policy("0.0.0.0", "s3cret-word")  # fine
    """
    if token is not None and (not token or len(token) > 256 or any(c.isspace() for c in token)):
        raise ConfigError(
            "The console token must be 1 to 256 characters with no spaces "
            f"(it is sent as `auth <token>` on one line); got {len(token)} "
            "characters. Pick a long random word, e.g. from "
            '`python -c "import secrets; print(secrets.token_urlsafe())"`.'
        )
    if token is None and not is_loopback(host):
        raise ConfigError(
            f"CommandReceiverFactory(host={host!r}) would let anyone who can reach this "
            "machine control the node: run tasks, reload code, stop it. Keep the default "
            "host='127.0.0.1' (reach it from another computer with `ssh -L`), or set a "
            f"shared secret: CommandReceiverFactory(host={host!r}, token='...') or the "
            f"environment variable {TOKEN_ENV_VAR}, and give the same token to "
            "`snr-console HOST:PORT --token ...`."
        )


def tokens_match(expected: str, given: str) -> bool:
    """Compare tokens in constant time, so timing does not leak the token.

    Example::

        tokens_match("s3cret", "s3cret"), tokens_match("s3cret", "guess")  # (True, False)
    """
    import hmac  # here, not at the top: it loads OpenSSL, and only tokens need it

    return hmac.compare_digest(expected.encode("utf-8"), given.encode("utf-8"))
