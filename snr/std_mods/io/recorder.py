"""`RecorderEndpointFactory`: write pages to disk as they are stored (``docs/recording.md``).

JSON lines (a header, then a page per line), or a format an extra provides,
chosen by the file's extension (MCAP: `recording_formats`).
"""

from __future__ import annotations

import logging
import os
import sys
import time
from typing import IO, List, Optional, Sequence, Tuple, Union

from snr.core import Endpoint, EndpointFactory
from snr.core.logs import RepeatFilter
from snr.prelude import AbstractNode, ConfigError, DataKey, Page, SomeTasks, Task, TaskId, TaskType
from snr.std_mods.codec import PathLike, header_line, is_header, page_to_line
from snr.std_mods.io import recording_formats
from snr.std_mods.io.recording_formats import PageWriter
from snr.std_mods.io.replayer import _fields

__all__ = ["FILE_FORMATS", "RecorderEndpoint", "RecorderEndpointFactory", "kept_name"]

FILE_FORMATS = ("jsonl", "mcap")
"""The formats a recorder writes: JSON lines (the default) and MCAP (with ``snr.extras.viz``)."""

_PEEK_BYTES = 65536  # enough for the first line of any recording (its header)
_MAX_TIME = sys.float_info.max  # NaN, infinity and larger integers fail the comparison


class _LinesFile:
    """A JSON-lines recording open for writing: a line per page, flushed at once."""

    def __init__(self, file: IO[bytes], sync: bool) -> None:
        self.file, self.sync = file, sync

    def write(self, page: Page, line: Optional[str] = None) -> None:
        self.file.write(f"{line}\n".encode())  # one write per page: a kill cuts one line at most
        self.file.flush()
        if self.sync:
            os.fsync(self.file.fileno())

    def close(self) -> None:
        self.file.close()


class RecorderEndpoint(Endpoint):
    """Appends every page stored under its keys to the recording file.

    The file opens when the node starts and closes when it stops; after a hot
    reload the new endpoint goes on writing the same open file.

    Example::

        RecorderEndpointFactory("dive.jsonl", ["depth_m", "heading_deg"])
    """

    def __init__(self, factory: RecorderEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.recording = factory
        factory.endpoint = self  # the old one, ended after a reload, then leaves the file open
        self._write_failed = False
        if factory.repeats is None:  # on the factory: a reload does not repeat the messages
            factory.repeats = RepeatFilter(self.log, first=1)
        self._repeats = factory.repeats
        self.task_handlers = {(TaskType.store_page, key): self.record_page for key in factory.keys}

    def begin(self) -> None:
        """Open the file now, so a bad filename is reported at start-up."""
        self._open()

    def record_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Write the stored page as one line and flush it to the OS.

        A page that cannot be written as a valid line (data JSON cannot
        hold, nesting too deep, a time that is not a number) is logged with
        its key and skipped, whatever the error: recording goes on.
        """
        page, recording = task.page(), self.recording
        if page is None:  # SNR's node core says so too, but a student's may not
            self.warn("A store_page task for %r carries %r, not a Page", task.name, task.val_list)
            return None
        try:
            _check_fields(page)
            line = page_to_line(page)
        except Exception as error:  # never take the node down over one page
            self._skip(page, error)
            return None
        try:
            (recording.file or self._open()).write(page, line)
            recording.pages_written += 1
        except OSError as error:
            recording.pages_skipped += 1
            if not self._write_failed:  # a full disk would fail every page: say it once
                self._write_failed = True
                self.err(
                    "Cannot write to recording %s: %s. Pages are not being recorded (free "
                    "some disk space or choose another file); further failures are counted.",
                    recording.path,
                    error,
                )
        return None

    def terminate(self) -> None:
        """Close the file (every page is already flushed), unless a reload goes on with it."""
        self._repeats.flush()  # the counts of skipped pages not yet logged
        recording, file = self.recording, self.recording.file
        if recording.endpoint is not self or file is None:
            return
        recording.file = None
        try:
            file.close()  # an MCAP file gets its index
        except OSError as error:
            self.err("Could not finish the recording %s: %s", recording.path, error)
        done, skipped = recording.pages_written, recording.pages_skipped
        self.info(f"Recorded {done} pages to {recording.path} ({skipped} skipped)")

    def _open(self) -> PageWriter:
        """The recording, opened the first time as the factory's options say."""
        r = self.recording
        if r.file is not None:
            return r.file
        what = f"{type(r).__name__}({r.filename!r})"
        fmt = None
        if r.file_format != "jsonl":  # before any file is made or renamed
            fmt = recording_formats.get(r.file_format, what)
            fmt.require(what, compression=r.compression)
        reopen = r.started and fmt is None  # closed and opened again: go on writing it
        if not reopen:
            r.path, r.kept = r._choose_path()
        try:
            file = open(r.path, "ab" if reopen or r.append else "wb")  # noqa: SIM115 - kept open
            try:
                if fmt is not None:
                    r.file = fmt.writer(file, r.compression, sync=r.sync)
                else:
                    if not reopen:  # a run cut short mid-line: keep its last line apart
                        cut = r.append and not _ends_with_newline(r.path)
                        file.write(b"\n" * cut + header_line().encode() + b"\n")
                        file.flush()
                    r.file = _LinesFile(file, r.sync)
            except BaseException:
                file.close()
                raise
        except OSError as error:
            folder = os.path.dirname(os.path.abspath(r.path))
            raise ConfigError(
                f"{type(r).__name__} cannot open {r.path!r} for writing: "
                f"{error.strerror or error}. Check that the folder {folder!r} exists and that "
                "you may write there, or choose another filename."
            ) from error
        to = f"Recording {', '.join(r.keys)} to {r.path}"
        if not r.started and r.kept is not None:
            self.info(f"{to}; the recording that was there is kept as {r.kept}")
        elif not r.started and r.path != r.filename:
            self.warn(f"{to}: {r.filename} holds a recording that could not be renamed")
        elif not r.started:
            how = "appending" if r.append else "writing"
            self.info(f"{to} ({how}{'' if r.file_format == 'jsonl' else ' MCAP'})")
        r.started = True
        return r.file

    def _skip(self, page: Page, error: Exception) -> None:
        self.recording.pages_skipped += 1
        text = str(error)
        if not text.startswith("Cannot"):
            why = text if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"
            text = f"Cannot write the page stored under {page.key!r} to a recording: {why:.300}."
        data_type = type(page.data).__name__
        self._repeats.report(
            (page.key, data_type, type(error).__name__),
            f"Pages under {page.key!r} not recorded ({data_type} data)",
            logging.ERROR,
            f"Did not record a page: {text} Recording goes on; later pages like this one are "
            "counted.",
        )


def _check_fields(page: Page) -> None:
    """Refuse a page whose fields a reader would reject (only hand-made pages)."""
    created = page.created_at_s
    if not (type(created) in (float, int) and -_MAX_TIME <= created <= _MAX_TIME):
        raise ValueError(f"its created_at_s is {created!r:.40}, not a finite number")
    if type(page.origin) is not str:
        raise ValueError(f"its origin is {page.origin!r:.40}, not a string")
    if type(page.process) is not bool:
        raise ValueError(f"its process flag is {page.process!r:.40}, not True or False")


def kept_name(filename: PathLike, when_s: float) -> str:
    """The name a previous recording is kept under: its local time before the extension.

    Args:
        filename: the recording's file name.
        when_s: when it was last written (``os.path.getmtime``), seconds since 1970.

    Example::

        kept_name("logs/dive.jsonl", 1795564741.0)   # 'logs/dive-2026-11-24T23-59-01.jsonl' (UTC)
    """
    stem, extension = os.path.splitext(os.fspath(filename))
    return f"{stem}-{time.strftime('%Y-%m-%dT%H-%M-%S', time.localtime(when_s))}{extension}"


class RecorderEndpointFactory(EndpointFactory):
    """Builds a `RecorderEndpoint` that records ``keys`` into ``filename``.

    A recording already at ``filename`` is kept, renamed with the time it
    was last written (``dive-2026-11-24T23-59-01.jsonl``), and the new run
    goes to ``filename``; a file that is not a recording is left alone and
    the node does not start (``ConfigError``). Data JSON cannot hold is
    logged, naming its key and type, and skipped. See ``docs/recording.md``.

    Args:
        filename: the file to write.
        keys: the data keys to record (one key may be given as a string).
        sync: also ``os.fsync`` every page, so even a power cut loses at most
            one page (slower: every page waits for the disk).
        name: the endpoint's name (default ``"recorder"``).
        overwrite: replace whatever ``filename`` holds instead of keeping it.
        append: add this run's pages to the end of ``filename``, after a
            header line. JSON lines only.
        file_format: ``"jsonl"`` or ``"mcap"``; by default ``"mcap"`` when
            ``filename`` ends in ``.mcap`` (``pip install 'snr-robotics[mcap]'``),
            else ``"jsonl"`` (the thesis's format).
        compression: MCAP only: ``"zstd"`` or ``"lz4"`` compress the file in
            chunks of about 1 MiB; ``None`` (default) flushes each page.

    Raises:
        ConfigError: no keys, both ``overwrite`` and ``append``, an unknown
            ``file_format`` or ``compression``, or ``append`` or ``compression``
            where the format does not allow it.

    Example::

        config = Config({"robot": [
            DepthSensorFactory("depth_m"),
            RecorderEndpointFactory("dive.jsonl", ["depth_m"]),
            RecorderEndpointFactory("dive.mcap", ["depth_m"], name="mcap_recorder"),
        ]})

    Attributes:
        path: the file being written (``filename``, unless the previous
            recording could not be renamed: then a new name beside it).
        kept: where the previous recording was kept, or None.
        pages_written: pages written so far (kept across reloads).
        pages_skipped: pages that could not be written.
    """

    def __init__(
        self,
        filename: PathLike,
        keys: Union[DataKey, Sequence[DataKey]],
        sync: bool = False,
        name: Optional[str] = None,
        overwrite: bool = False,
        append: bool = False,
        file_format: Optional[str] = None,
        compression: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        self.filename = os.fspath(filename)
        self.keys: List[DataKey] = [keys] if isinstance(keys, str) else list(keys)
        call = f"RecorderEndpointFactory({self.filename!r}"
        if not self.keys or not all(isinstance(k, str) and k for k in self.keys):
            raise ConfigError(
                f"{call}, {keys!r}): keys must be a list of data keys to record, "
                "e.g. ['depth_m', 'heading_deg']."
            )
        if overwrite and append:
            raise ConfigError(
                f"{call}): choose overwrite=True (replace the file) or append=True "
                "(add to it), not both."
            )
        if file_format is None:
            file_format = recording_formats.format_of_name(self.filename)
        elif file_format not in FILE_FORMATS:
            raise ConfigError(
                f"{call}, file_format={file_format!r}): choose one of {FILE_FORMATS}, "
                "or leave it out to go by the file's extension."
            )
        if file_format != "jsonl":  # the format's own options, checked by its extra
            recording_formats.get(file_format, f"{call})").check(call, compression, append)
        elif compression is not None:
            compressions = recording_formats.get("mcap", f"{call})").compressions
            raise ConfigError(
                f"{call}, compression={compression!r}): compression is for MCAP recordings, "
                f"one of {compressions}."
            )
        self.file_format = file_format
        self.compression = compression or "none"
        self.sync = sync
        self.name = name or "recorder"
        self.overwrite = overwrite
        self.append = append
        self.path = self.filename
        self.kept: Optional[str] = None
        self.pages_written = 0
        self.pages_skipped = 0
        # What lasts across reloads: the open file, the endpoint writing it, the counts.
        self.repeats: Optional[RepeatFilter] = None
        self.started = False
        self.file: Optional[PageWriter] = None
        self.endpoint: Optional[RecorderEndpoint] = None

    def _choose_path(self) -> Tuple[str, Optional[str]]:
        """The file to write, and where the previous recording went (None: nowhere)."""
        name = self.filename
        if self.overwrite or self.append or not os.path.isfile(name):
            return name, None
        holds = _what_it_holds(name)
        if holds == "other":
            raise ConfigError(
                f"{type(self).__name__} will not write to {name!r}: the file exists "
                "and is not an SNR recording, so it is left as it is. Choose another "
                "filename, or pass overwrite=True to replace it."
            )
        if holds == "nothing":
            return name, None
        kept = _free_name(kept_name(name, os.path.getmtime(name)))
        try:
            os.rename(name, kept)
        except OSError:  # e.g. open in another program on Windows: write beside it
            return _free_name(kept_name(name, time.time())), None
        return name, kept

    def get(self, parent: AbstractNode) -> RecorderEndpoint:
        return RecorderEndpoint(self, parent)

    def __repr__(self) -> str:
        return f"RecorderEndpointFactory({self.filename!r}, {self.keys!r})"


def _what_it_holds(path: str) -> str:
    """``"nothing"`` (no pages), ``"recording"`` or ``"other"``, from the file's start."""
    try:
        with open(path, "rb") as file:
            start = file.read(_PEEK_BYTES)
    except OSError:
        return "recording"  # unreadable: do not write over it; renaming keeps it safe
    if recording_formats.format_of_bytes(start) != "jsonl":
        return "recording"
    lines = [_fields(line) for line in start.split(b"\n") if line.strip()]
    if not lines:
        return "nothing"
    first, whole = lines[0], len(start) < _PEEK_BYTES
    if first is None:  # not JSON, or a first line cut short by the size limit
        return "other" if whole or len(lines) > 1 else "recording"
    if "key" not in first and not (is_header(first) and first.get("format") == "snr-pages"):
        return "other"
    if whole and all(f is not None and is_header(f) for f in lines):
        return "nothing"
    return "recording"


def _free_name(path: str) -> str:
    """``path``, or ``path`` with ``-2``, ``-3``... before its extension, whichever is free."""
    stem, extension = os.path.splitext(path)
    candidate, n = path, 1
    while os.path.exists(candidate):
        n += 1
        candidate = f"{stem}-{n}{extension}"
    return candidate


def _ends_with_newline(path: str) -> bool:
    """True for an empty file or one whose last byte is a newline."""
    try:
        with open(path, "rb") as file:
            file.seek(max(file.seek(0, os.SEEK_END) - 1, 0))
            return file.read(1) in (b"", b"\n")
    except OSError:
        return True
