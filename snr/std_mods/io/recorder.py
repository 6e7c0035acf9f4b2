"""`RecorderEndpointFactory`: write pages to disk as they are stored.

JSON lines (``snr.std_mods.codec``: a header line, then a page per line), or
a format an extra provides, chosen by the file's extension (MCAP for
``*.mcap``: see `recording_formats`). Each page is flushed as it is written,
so a killed process loses at most that page. Replay the file with
`ReplayerLoopFactory` or read it with `PageReader`.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from typing import IO, Any, Dict, List, Optional, Sequence, Tuple, Union

from snr.core import Endpoint, EndpointFactory
from snr.core.logs import RepeatFilter
from snr.prelude import AbstractNode, ConfigError, DataKey, Page, SomeTasks, Task, TaskId, TaskType
from snr.std_mods.codec import PathLike, decode_line, header_line, is_header, page_to_line
from snr.std_mods.io import recording_formats
from snr.std_mods.io.recording_formats import PageWriter

__all__ = ["FILE_FORMATS", "RecorderEndpoint", "RecorderEndpointFactory", "kept_name"]

FILE_FORMATS = ("jsonl", "mcap")
"""The formats a recorder writes: JSON lines (the default) and MCAP (with ``snr.extras.viz``)."""

_PEEK_BYTES = 65536  # enough for the first line of any recording (its header)
_MAX_TIME = sys.float_info.max  # NaN, infinity and larger integers fail the comparison


class _LinesFile:
    """A JSON-lines recording open for writing: a line per page, flushed at once."""

    def __init__(self, file: IO[str], sync: bool) -> None:
        self.file, self.sync = file, sync

    def write(self, page: Page, line: Optional[str] = None) -> None:
        self.file.write(f"{line}\n")  # one write per page, so a kill cuts one line at most
        self.file.flush()
        if self.sync:
            os.fsync(self.file.fileno())

    def close(self) -> None:
        self.file.close()


class RecorderEndpoint(Endpoint):
    """Appends every page stored under its keys to the recording file.

    The file opens when the node starts and closes when it stops. After a
    hot reload the new endpoint goes on writing the same open file.

    Example::

        RecorderEndpointFactory("dive.jsonl", ["depth_m", "heading_deg"])
    """

    def __init__(self, factory: RecorderEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.recording = factory
        # A reload builds the new endpoint before the old one terminates: the
        # old one then knows to leave the file open.
        factory.endpoint = self
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
        if page is None:
            self.warn("A store_page task for %r carries %r, not a Page", task.name, task.val_list)
            return None
        try:
            _check_fields(page)
            line = page_to_line(page)
        except Exception as error:  # never take the node down over one page
            self._skip(page, error)
            return None
        try:
            self._open().write(page, line)
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
        recording = self.recording
        if recording.endpoint is self and recording.close_file(self.log):
            self.info(
                "Recorded %d pages to %s (%d skipped)",
                recording.pages_written,
                recording.path,
                recording.pages_skipped,
            )

    def _open(self) -> PageWriter:
        first = self.recording.file is None and not self.recording.started
        file = self.recording.open_file()
        if first:
            self._say_where()
        return file

    def _say_where(self) -> None:
        recording, keys = self.recording, ", ".join(self.recording.keys)
        if recording.kept is not None:
            self.info(
                "Recording %s to %s; the recording that was there is kept as %s",
                keys,
                recording.path,
                recording.kept,
            )
        elif recording.path != recording.filename:
            self.warn(
                "Recording %s to %s: %s holds a recording that could not be renamed",
                keys,
                recording.path,
                recording.filename,
            )
        else:
            how = "appending" if recording.append else "writing"
            how += "" if recording.file_format == "jsonl" else f" {recording.file_format.upper()}"
            self.info("Recording %s to %s (%s)", keys, recording.path, how)

    def _skip(self, page: Page, error: Exception) -> None:
        self.recording.pages_skipped += 1
        data_type = type(page.data).__name__
        if str(error).startswith("Cannot"):
            text = str(error)
        else:
            why = (
                str(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"
            )
            text = f"Cannot write the page stored under {page.key!r} to a recording: {why:.300}."
        self._repeats.report(
            (page.key, data_type, type(error).__name__),
            f"Pages under {page.key!r} not recorded ({data_type} data)",
            logging.ERROR,
            "Did not record a page: %s Recording goes on; later pages like this one are counted.",
            text,
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
    """The name a previous recording is kept under: its time before the extension.

    Args:
        filename: the recording's file name.
        when_s: when it was last written (``os.path.getmtime``), seconds since 1970.

    Example::

        kept_name("logs/dive.jsonl", 1795564741.0)   # 'logs/dive-2026-11-24T23-59-01.jsonl' (UTC)
    """
    stem, extension = os.path.splitext(os.fspath(filename))
    stamp = time.strftime("%Y-%m-%dT%H-%M-%S", time.localtime(when_s))
    return f"{stem}-{stamp}{extension}"


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
        self.file_format = file_format
        if file_format != "jsonl":  # the format's own options, checked by its extra
            recording_formats.get(file_format, f"{call})").check(call, compression, append)
        elif compression is not None:
            compressions = recording_formats.get("mcap", f"{call})").compressions
            raise ConfigError(
                f"{call}, compression={compression!r}): compression is for MCAP recordings, "
                f"one of {compressions}."
            )
        self.compression = compression or "none"
        self.sync = sync
        self.name = name or "recorder"
        self.overwrite = overwrite
        self.append = append
        self.path = self.filename
        self.kept: Optional[str] = None
        self.pages_written = 0
        self.pages_skipped = 0
        self.repeats: Optional[RepeatFilter] = None
        self.started = False
        self.file: Optional[PageWriter] = None  # open while the node runs, across reloads
        self.endpoint: Optional[RecorderEndpoint] = None

    def open_file(self) -> PageWriter:
        """Open the recording (the first time as chosen above), or give the one already open.

        After a reload the new endpoint gets the file still open. A JSON-lines
        file closed earlier (the recorder removed and added again) is appended
        to; another format's file (MCAP) cannot be, so a new one starts and the
        closed one is kept.

        Raises:
            ConfigError: the file cannot be created (no such folder, no
                permission), or it exists and is not a recording, or its
                format needs a package that is not installed; the message
                names the file and the fix.
        """
        if self.file is not None:
            return self.file
        other = None
        if self.file_format != "jsonl":  # before any file is made or renamed
            what = f"{type(self).__name__}({self.filename!r})"
            other = recording_formats.get(self.file_format, what)
            other.require(what, compression=self.compression)
        elif self.started:
            self.file = _LinesFile(self._open("a"), self.sync)
            return self.file
        self.path, self.kept = self._choose_path()
        file = self._open("wb" if other else "a" if self.append else "w")
        try:
            if other is not None:
                self.file = other.writer(file, self.compression, sync=self.sync)
            else:
                if self.append and not _ends_with_newline(self.path):
                    file.write("\n")  # a run cut short mid-line: keep its last line apart
                file.write(header_line() + "\n")
                file.flush()
                self.file = _LinesFile(file, self.sync)
        except Exception as error:
            file.close()
            if isinstance(error, OSError):
                raise self._cannot_write(error) from error
            raise
        self.started = True
        return self.file

    def close_file(self, log: logging.Logger) -> bool:
        """Close the recording if it is open (an MCAP file gets its index); True if it was.

        A failure to write the end of the file is logged, not raised.
        """
        file, self.file = self.file, None
        if file is None:
            return False
        try:
            file.close()
        except OSError as error:
            log.error("Could not finish the recording %s: %s", self.path, error)
        return True

    def _open(self, mode: str) -> IO[Any]:
        try:  # kept open between pages (closed by close_file), hence no `with`
            if "b" in mode:
                return open(self.path, mode)
            return open(self.path, mode, encoding="utf-8", newline="\n")
        except OSError as error:
            raise self._cannot_write(error) from error

    def _choose_path(self) -> Tuple[str, Optional[str]]:
        """The file to write and where the previous recording went (None: nowhere)."""
        if self.overwrite or self.append or not os.path.isfile(self.filename):
            return self.filename, None
        holds = _what_it_holds(self.filename)
        if holds == "nothing":
            return self.filename, None
        if holds == "other":
            raise ConfigError(
                f"{type(self).__name__} will not write to {self.filename!r}: the file exists "
                "and is not an SNR recording, so it is left as it is. Choose another "
                "filename, or pass overwrite=True to replace it."
            )
        kept = _free_name(kept_name(self.filename, os.path.getmtime(self.filename)))
        try:
            os.rename(self.filename, kept)
        except OSError:  # e.g. open in another program on Windows: write beside it
            return _free_name(kept_name(self.filename, time.time())), None
        return self.filename, kept

    def _cannot_write(self, error: OSError) -> ConfigError:
        folder = os.path.dirname(os.path.abspath(self.path))
        return ConfigError(
            f"{type(self).__name__} cannot open {self.path!r} for writing: "
            f"{error.strerror or error}. Check that the folder {folder!r} exists and "
            "that you may write there, or choose another filename."
        )

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
    first = lines[0]
    if first is None:  # a first line cut short by the size limit, or not JSON at all
        return "recording" if len(lines) == 1 and len(start) == _PEEK_BYTES else "other"
    if not (is_header(first) and first.get("format") == "snr-pages") and "key" not in first:
        return "other"
    if len(start) < _PEEK_BYTES and all(f is not None and is_header(f) for f in lines):
        return "nothing"
    return "recording"


def _fields(line: bytes) -> Optional[Dict[str, Any]]:
    """The JSON object on ``line``, or None when it is not one."""
    try:
        return decode_line(line)
    except Exception:
        return None


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
            return file.seek(0, os.SEEK_END) == 0 or (
                file.seek(-1, os.SEEK_END) >= 0 and file.read(1) == b"\n"
            )
    except OSError:
        return True
