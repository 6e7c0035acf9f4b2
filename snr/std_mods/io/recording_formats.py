"""The extension point of the recorder and replayer: recording formats besides JSON lines.

An extra adds a format as an entry point of the group ``snr.recording_formats``
(`snr.core.plugins`): its name is the file extension that chooses it, its
object a `RecordingFormat`. MCAP (``snr.extras.viz.mcap_format``) is one. The
recorder asks for a format by the file's name, the reader by its first bytes.

Example::

    format_of_name("dive.mcap")             # 'mcap' (with snr.extras.viz installed)
    get("mcap", "Writing dive.mcap").magic  # b'\\x89MCAP0\\r\\n'
"""

from __future__ import annotations

import os
from typing import IO, Any, Callable, Iterator, Optional, Protocol, Tuple

from snr.core import plugins
from snr.prelude import Page
from snr.std_mods.codec import PathLike

__all__ = ["GROUP", "PageWriter", "RecordingFormat", "format_of_bytes", "format_of_name", "get"]

GROUP = "snr.recording_formats"
"""The entry point group of recording formats."""


class PageWriter(Protocol):
    """A recording open for writing: a page at a time, then ``close``."""

    def write(self, page: Page, line: Optional[str] = None) -> None:
        """Write one page (``line``: the page already as a JSON line, if at hand)."""

    def close(self) -> None:
        """Finish the file and close it."""


class RecordingFormat(Protocol):
    """A recording format: a writer and a reader (see ``snr.extras.viz.mcap_format``).

    Attributes:
        magic: the bytes every file of this format starts with.
        unit: what the reader calls one record in messages, e.g. ``"message"``.
        compressions: the ``compression`` choices, ``"none"`` first.
    """

    magic: bytes
    unit: str
    compressions: Tuple[str, ...]

    def check(self, call: str, compression: Optional[str], append: bool) -> None:
        """Refuse a recorder's options the format cannot honour, with a `ConfigError`."""

    def require(self, what: str, part: str = "writer", compression: str = "none") -> Any:
        """Fail with a `ConfigError` naming the install command if a package is missing."""

    def writer(
        self, file: IO[bytes], compression: str = "none", flush: bool = True, sync: bool = False
    ) -> PageWriter:
        """A writer of pages to ``file``, opened for writing bytes."""

    def read_pages(
        self, filename: PathLike, report: Callable[[int, str], None]
    ) -> Iterator[Tuple[int, Page, bool]]:
        """The pages of a file: ``(number, page, had a time)``; bad ones go to ``report``."""


def get(name: str, what: str) -> RecordingFormat:
    """The recording format ``name``, or a `ConfigError` saying what to install for ``what``.

    Example::

        get("mcap", "Reading dive.mcap").require("Reading dive.mcap", "stream_reader")
    """
    found: RecordingFormat = plugins.load(GROUP, name, what)
    return found


def format_of_name(filename: PathLike) -> str:
    """The format a file's name asks for: its extension if a format has it, else ``"jsonl"``.

    Example::

        format_of_name("dive.MCAP"), format_of_name("dive.jsonl")   # ('mcap', 'jsonl')
    """
    extension = os.path.splitext(os.fspath(filename))[1][1:].lower()
    return extension if extension in plugins.names(GROUP) else "jsonl"


def format_of_bytes(start: bytes) -> str:
    """The format a file starting with ``start`` is in: a format whose magic it has, or ``"jsonl"``.

    Example::

        format_of_bytes(b'{"format":"snr-pages","version":1}')   # 'jsonl'
    """
    for name in plugins.names(GROUP):
        if start.startswith(get(name, "Reading a recording").magic):
            return name
    return "jsonl"
