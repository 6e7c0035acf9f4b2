"""MCAP recordings: pages as JSON messages that Foxglove, Lichtblick and ROS 2 tools open.

MCAP (https://mcap.dev) is the default file format of ``ros2 bag``. SNR writes
it with the ``mcap`` package, an optional extra (``pip install 'snr-robotics[mcap]'``):
nothing here imports it until an MCAP file is written or read, and a missing
package is a one-line `ConfigError` naming that install command. The package is
pure Python, but its metadata requires lz4 and zstandard, which PyPI has no
wheels of for 32-bit Raspberry Pi OS: there, install Debian's ``python3-lz4``
and ``python3-zstandard`` first (``docs/raspberry-pi.md``).

How pages map onto MCAP (see ``docs/recording.md``):

* **Topic** ``"/" + key`` (the ROS convention): ``depth_m`` is ``/depth_m``.
* **Channel**: one per key and origin, so the origin is in the channel's
  metadata (``key``, ``origin``, and ``format``/``version`` of the page format).
* **Message**: JSON (encoding ``"json"``), exactly the page's line in the
  JSON-lines format: ``{"key":...,"data":...,"origin":...,"created_at_s":...,
  "process":...}``. So the same strict codec writes and reads it, and a JSON
  lines file converts to MCAP and back byte for byte. In Foxglove the data is
  at the message path ``/depth_m.data``.
* **Log time** (and publish time): ``created_at_s`` in nanoseconds, clamped to
  what MCAP's unsigned 64-bit time can hold (the exact value is in the message).
* **Schema**: one JSON Schema (encoding ``"jsonschema"``) per key, inferred from
  the key's first page (`page_schema`). Schemas describe; they do not filter:
  a later page whose data has another shape is recorded all the same.

Without compression (the default) each message is written as its own record
and flushed, like a JSON line: a killed recorder loses at most the page it was
writing, and the file, missing only its index at the end, still reads (SNR's
reader says it was cut short; ``mcap recover`` adds the index). With
``compression="zstd"`` or ``"lz4"`` pages are gathered in compressed chunks of
about 1 MiB, so a kill loses the unfinished chunk.

Example::

    with open("dive.mcap", "wb") as file:
        writer = McapPageWriter(file)
        writer.write(Page("depth_m", 3.2, "urov", 1700000000.25))
        writer.close()
"""

from __future__ import annotations

import importlib
import json
import math
import os
from typing import IO, Any, Callable, Dict, Iterator, Optional, Tuple

from snr.extras.viz.page_schema import page_schema as any_page_schema
from snr.prelude import ConfigError, Page, WireFormatError
from snr.prelude.install import install_hint
from snr.std_mods.codec import (
    FORMAT_NAME,
    FORMAT_VERSION,
    PathLike,
    check_header,
    decode_line,
    load_json,
    page_from_fields,
    page_to_line,
)

__all__ = [
    "COMPRESSIONS",
    "COMPRESSION_PACKAGES",
    "DEBIAN_HINT",
    "INSTALL_HINT",
    "MCAP_MAGIC",
    "MAX_RECORD_BYTES",
    "McapPageWriter",
    "format_of_name",
    "is_mcap_file",
    "log_time_ns",
    "page_schema",
    "read_mcap_pages",
    "require_mcap",
]

MCAP_MAGIC = b"\x89MCAP0\r\n"
"""The 8 bytes every MCAP file starts (and ends) with."""

INSTALL_HINT = install_hint("mcap")
"""The command that installs what MCAP files need."""

COMPRESSIONS = ("none", "zstd", "lz4")
"""The ``compression`` choices; ``"none"`` needs only the pure-Python ``mcap`` package."""

COMPRESSION_PACKAGES = {"zstd": "zstandard", "lz4": "lz4"}
"""The package each compression needs besides ``mcap`` (the ``mcap`` extra brings both)."""

DEBIAN_HINT = "on 32-bit Raspberry Pi OS: sudo apt install python3-lz4 python3-zstandard"
"""Where a 32-bit Pi gets the compression packages: PyPI has no armv7l wheels of them."""

MAX_RECORD_BYTES = 256 * 2**20
"""Largest MCAP record read (256 MiB): a damaged length field is reported, not allocated."""

_CHUNK_BYTES = 2**20  # with compression: about 1 MiB of pages per chunk
_MAX_LOG_TIME = 2**64 - 1  # MCAP times are unsigned 64-bit nanoseconds


def require_mcap(what: str, part: str = "writer") -> Any:
    """The ``mcap.<part>`` module, or a one-line `ConfigError` naming the install command.

    Args:
        what: what needs it, for the message, e.g. ``"Writing dive.mcap"``.
        part: the submodule, e.g. ``"writer"``, ``"stream_reader"``, ``"records"``.

    Example::

        writer_module = require_mcap("Writing dive.mcap")
    """
    try:
        return importlib.import_module(f"mcap.{part}")
    except ImportError:
        raise ConfigError(
            f"{what} needs the mcap package, which is not installed: {INSTALL_HINT}"
        ) from None


def is_mcap_file(filename: PathLike) -> bool:
    """True when the file starts with the MCAP magic bytes (False if it cannot be read).

    Example::

        is_mcap_file("dive.mcap")   # True
    """
    try:
        with open(filename, "rb") as file:
            return file.read(len(MCAP_MAGIC)) == MCAP_MAGIC
    except OSError:
        return False


def format_of_name(filename: PathLike) -> str:
    """``"mcap"`` for a name ending in ``.mcap`` (any case), else ``"jsonl"``.

    Example::

        format_of_name("dive.MCAP"), format_of_name("dive.jsonl")   # ('mcap', 'jsonl')
    """
    return "mcap" if os.fspath(filename).lower().endswith(".mcap") else "jsonl"


def log_time_ns(created_at_s: float) -> int:
    """``created_at_s`` as MCAP's log time: whole nanoseconds, clamped to 0 ... 2**64 - 1.

    Example::

        log_time_ns(1700000000.25)   # 1700000000250000000
    """
    seconds = math.floor(created_at_s)
    nanoseconds = seconds * 1_000_000_000 + round((created_at_s - seconds) * 1e9)
    return min(max(nanoseconds, 0), _MAX_LOG_TIME)


# -- schemas --------------------------------------------------------------------------


def page_schema(key: str, data: Any) -> Dict[str, Any]:
    """The JSON Schema of the messages under ``key``: a page whose ``data`` is like ``data``.

    Example::

        page_schema("depth_m", 3.2)["properties"]["data"]   # {'type': 'number'}
    """
    schema = any_page_schema(data)  # the same inference as the live view's channels
    schema["title"] = key
    schema["description"] = f"SNR pages stored under {key!r}; data inferred from the first page"
    schema["required"] = ["key", "data"]
    return schema


# -- writing --------------------------------------------------------------------------


class McapPageWriter:
    """Writes pages to an MCAP file: a channel per key and origin, a schema per key.

    Args:
        file: a file opened for writing bytes (``open(name, "wb")``).
        compression: ``"none"`` (default: each page written and flushed on its
            own), ``"zstd"`` or ``"lz4"`` (chunks of about 1 MiB; needs the
            ``zstandard`` or ``lz4`` package).
        flush: flush the file to the OS after every page (uncompressed only).
        sync: also ``os.fsync`` after every page.

    Raises:
        ConfigError: the mcap package (or the compression's package) is not
            installed, or ``compression`` is unknown.

    `close` writes the index at the end of the file and closes it; until then
    the file holds every page written (uncompressed) but no index.

    Example::

        with open("dive.mcap", "wb") as file:
            writer = McapPageWriter(file, compression="zstd")
            writer.write(Page("depth_m", 3.2, "urov", 1700000000.25))
            writer.close()
    """

    def __init__(
        self, file: IO[bytes], compression: str = "none", flush: bool = True, sync: bool = False
    ) -> None:
        name = getattr(file, "name", None)
        what = f"Writing the MCAP file {name!r}" if isinstance(name, str) else "Writing MCAP"
        module = require_mcap(what)
        if compression not in COMPRESSIONS:
            raise ConfigError(
                f"{what}: unknown compression {compression!r}; choose one of {COMPRESSIONS}"
            )
        chunked = compression != "none"
        exceptions = require_mcap(what, "exceptions")
        try:
            self._writer = module.Writer(
                file,
                compression=getattr(module.CompressionType, compression.upper()),
                use_chunking=chunked,
                chunk_size=_CHUNK_BYTES,
            )
        except exceptions.UnsupportedCompressionError as error:
            package = COMPRESSION_PACKAGES.get(compression, compression)
            raise ConfigError(
                f"{what} with compression={compression!r} needs the {package} package "
                f"({error}): {INSTALL_HINT} ({DEBIAN_HINT}), or write it uncompressed"
            ) from None
        self.file = file
        self.compression = compression
        self._flush = flush and not chunked
        self._sync = sync
        self._schemas: Dict[str, int] = {}
        self._channels: Dict[Tuple[str, str], int] = {}
        self._sequence = 0
        self._writer.start(
            profile="", library=f"snr; {getattr(module, 'LIBRARY_IDENTIFIER', 'mcap-python')}"
        )
        self._after_write()

    def write(self, page: Page, line: Optional[str] = None) -> None:
        """Write one page as one message (``line``: the page already encoded, if at hand).

        Raises:
            NotSerializableError: data JSON cannot hold (nothing is written).
            OSError: the file cannot be written.
        """
        text = page_to_line(page) if line is None else line
        channel = self._channels.get((page.key, page.origin))
        if channel is None:
            channel = self._add_channel(page, text)
        when = log_time_ns(page.created_at_s)
        self._sequence = (self._sequence + 1) & 0xFFFFFFFF  # MCAP's field is 32 bits
        self._writer.add_message(
            channel_id=channel,
            log_time=when,
            data=text.encode("ascii"),
            publish_time=when,
            sequence=self._sequence,
        )
        self._after_write()

    def _add_channel(self, page: Page, line: str) -> int:
        schema = self._schemas.get(page.key)
        if schema is None:
            data = decode_line(line)["data"]  # as a reader will see it: tuples are lists
            body = json.dumps(page_schema(page.key, data), separators=(",", ":")).encode()
            schema = self._writer.register_schema(
                name=f"snr.Page:{page.key}", encoding="jsonschema", data=body
            )
            self._schemas[page.key] = schema
        metadata = {
            "key": page.key,
            "origin": page.origin,
            "format": FORMAT_NAME,
            "version": str(FORMAT_VERSION),
        }
        channel: int = self._writer.register_channel(
            topic="/" + page.key, message_encoding="json", schema_id=schema, metadata=metadata
        )
        self._channels[(page.key, page.origin)] = channel
        return channel

    def _after_write(self) -> None:
        if self._flush:
            self.file.flush()
            if self._sync:
                os.fsync(self.file.fileno())

    def close(self) -> None:
        """Write the index and summary at the end of the file, then close the file."""
        try:
            self._writer.finish()
        finally:
            self.file.close()


# -- reading --------------------------------------------------------------------------

Report = Callable[[int, str], None]
"""Told about each message that is skipped: its number and why."""


def read_mcap_pages(filename: PathLike, report: Report) -> Iterator[Tuple[int, Page, bool]]:
    """The pages of an MCAP file in file order: ``(message number, page, had a time)``.

    Messages on SNR channels are page lines, read with the same strict codec
    as JSON lines. Messages on other JSON channels (written by another
    program) become pages too: key = topic without its leading ``/``, data =
    the message, origin = the channel's ``origin`` metadata (or ``""``),
    ``created_at_s`` = log time. A message that is not a valid page, or on a
    channel that is not JSON, is passed to ``report`` and skipped. A file that
    ends early (a killed recorder) or is damaged ends the reading, reported
    once, with every message before it read.

    Raises:
        ConfigError: the mcap package is not installed.

    Example::

        for number, page, timed in read_mcap_pages("dive.mcap", print):
            print(number, page.key, page.data)
    """
    name = os.fspath(filename)
    stream_reader = require_mcap(f"Reading the MCAP file {name!r}", "stream_reader")
    records = require_mcap(f"Reading the MCAP file {name!r}", "records")
    channels: Dict[int, Callable[[Any], Tuple[Page, bool]]] = {}
    number = 0
    with open(name, "rb") as file:
        try:
            reader = stream_reader.StreamReader(file, record_size_limit=MAX_RECORD_BYTES)
        except TypeError:  # an older mcap, without the limit
            reader = stream_reader.StreamReader(file)
        items = iter(reader.records)
        while True:
            try:
                record = next(items, None)
            except Exception as error:  # cut short, damaged, a compression not installed
                report(number + 1, _damage(number, error))
                return
            if record is None:
                return
            if isinstance(record, records.Channel):
                channels[record.id] = _channel_reader(record)
            elif isinstance(record, records.Message):
                number += 1
                try:
                    read = channels.get(record.channel_id)
                    if read is None:
                        raise WireFormatError(f"its channel {record.channel_id} is not described")
                    page, timed = read(record)
                except Exception as error:  # whatever a message holds, reading goes on
                    why = str(error) if isinstance(error, WireFormatError) else repr(error)[:200]
                    report(number, f"skipped a bad message: {why}")
                    continue
                yield number, page, timed


def _damage(number: int, error: Exception) -> str:
    kind = type(error).__name__
    if kind == "EndOfFile" or "unpack requires" in str(error):
        return (
            f"the file ends after message {number}, without its index: cut short (the "
            "recorder stopped before closing it); every message before was read"
        )
    return f"the file is damaged after message {number} ({kind}: {str(error)[:200]}); stopped there"


def _channel_reader(channel: Any) -> Callable[[Any], Tuple[Page, bool]]:
    """How to turn the messages of ``channel`` into pages."""
    metadata: Dict[str, str] = dict(channel.metadata)
    origin = metadata.get("origin", "")
    if channel.message_encoding != "json":
        problem = (
            f"its channel {channel.topic!r} holds {channel.message_encoding!r} messages; "
            "SNR reads JSON channels only"
        )

        def refuse(message: Any) -> Tuple[Page, bool]:
            raise WireFormatError(problem)

        return refuse
    if metadata.get("format") == FORMAT_NAME:
        version = metadata.get("version", "")

        def page_line(message: Any) -> Tuple[Page, bool]:
            check_header(
                {"format": FORMAT_NAME, "version": int(version) if version.isdigit() else version}
            )
            fields = decode_line(message.data)
            page = page_from_fields(fields, origin, message.log_time / 1e9)
            return page, "created_at_s" in fields

        return page_line
    key = channel.topic[1:] if channel.topic.startswith("/") else channel.topic

    def json_message(message: Any) -> Tuple[Page, bool]:
        if not key:
            raise WireFormatError(f"its topic {channel.topic!r} gives no data key")
        return Page(key, load_json(message.data), origin, message.log_time / 1e9), True

    return json_message
