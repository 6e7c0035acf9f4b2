"""`RecorderEndpointFactory`: write pages to disk as they are stored.

The file is in the JSON-lines page format (``snr.std_mods.codec``): a header line,
then one page per line. Each line is flushed as soon as it is written, so a
process that is killed loses at most the page it was writing; replay the
file with `ReplayerLoopFactory` or read it with `PageReader`.
"""

from __future__ import annotations

import os
import sys
from typing import IO, List, Optional, Sequence, Set, Tuple, Union

from snr.core import Endpoint, EndpointFactory
from snr.prelude import (
    AbstractNode,
    ConfigError,
    DataKey,
    NotSerializableError,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)
from snr.std_mods.codec import PathLike, header_line, page_to_line

__all__ = ["RecorderEndpoint", "RecorderEndpointFactory"]


class RecorderEndpoint(Endpoint):
    """Appends every page stored under its keys to the recording file.

    The file opens when the node starts and closes when it stops. After a
    hot reload the new endpoint appends to the same file.

    Example::

        RecorderEndpointFactory("dive.jsonl", ["depth_m", "heading_deg"])
    """

    def __init__(self, factory: RecorderEndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.recording = factory
        self._file: Optional[IO[str]] = None
        self._write_failed = False
        self.task_handlers = {(TaskType.store_page, key): self.record_page for key in factory.keys}

    def begin(self) -> None:
        """Open the file now, so a bad filename is reported at start-up."""
        self._open()

    def record_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Write the stored page as one line and flush it to the OS."""
        page = task.val_list[0] if task.val_list else None
        if not isinstance(page, Page):
            self.warn("A store_page task for %r carries %r, not a Page", task.name, page)
            return None
        try:
            line = page_to_line(page)
        except NotSerializableError as error:
            self._skip(page, error)
            return None
        self._write(line)
        return None

    def terminate(self) -> None:
        """Close the file (every line is already flushed)."""
        if self._file is not None:
            self._file.close()
            self._file = None
            self.info(
                "Recorded %d pages to %s (%d skipped)",
                self.recording.pages_written,
                self.recording.filename,
                self.recording.pages_skipped,
            )

    # -- helpers ------------------------------------------------------------
    def _open(self) -> IO[str]:
        if self._file is None:
            self._file = self.recording.open_file()
        return self._file

    def _write(self, line: str) -> None:
        try:
            file = self._open()
            file.write(line + "\n")  # one write per page, so a kill cuts one line at most
            file.flush()
            if self.recording.sync:
                os.fsync(file.fileno())
        except OSError as error:
            self.recording.pages_skipped += 1
            if not self._write_failed:  # a full disk would fail every page: say it once
                self._write_failed = True
                self.err(
                    "Cannot write to recording %s: %s. Pages are not being recorded (free "
                    "some disk space or choose another file); further failures are counted.",
                    self.recording.filename,
                    error,
                )
            return
        self.recording.pages_written += 1

    def _skip(self, page: Page, error: NotSerializableError) -> None:
        self.recording.pages_skipped += 1
        kind = (page.key, type(page.data).__name__)
        if kind in self.recording.reported:
            self.dbg("Skipped another %s page under %r", kind[1], page.key)
            return
        self.recording.reported.add(kind)
        self.err(
            "Did not record a page: %s Recording goes on; later pages like this one are "
            "skipped without a message.",
            error,
        )


class RecorderEndpointFactory(EndpointFactory):
    """Builds a `RecorderEndpoint` that records ``keys`` into ``filename``.

    Args:
        filename: the file to write; it is replaced when the node starts.
        keys: the data keys to record (one key may be given as a string).
        sync: also ``os.fsync`` every page, so even a power cut loses at most
            one page (slower: every page waits for the disk).
        name: the endpoint's name (default ``"recorder"``).

    Data that JSON cannot hold (a set, an object) is logged, naming its key
    and type, and skipped; recording goes on.

    Example::

        config = Config({"robot": [
            DepthSensorFactory("depth_m"),
            RecorderEndpointFactory("dive.jsonl", ["depth_m"]),
        ]})

    Attributes:
        pages_written: pages written so far (kept across reloads).
        pages_skipped: pages that could not be written.
    """

    def __init__(
        self,
        filename: PathLike,
        keys: Union[DataKey, Sequence[DataKey]],
        sync: bool = False,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        self.filename = os.fspath(filename)
        self.keys: List[DataKey] = [keys] if isinstance(keys, str) else list(keys)
        if not self.keys or not all(isinstance(k, str) and k for k in self.keys):
            raise ConfigError(
                f"RecorderEndpointFactory({self.filename!r}, {keys!r}): keys must be a list "
                "of data keys to record, e.g. ['depth_m', 'heading_deg']."
            )
        self.sync = sync
        self.name = name or "recorder"
        self.pages_written = 0
        self.pages_skipped = 0
        self.reported: Set[Tuple[DataKey, str]] = set()
        self._started = False

    def open_file(self) -> IO[str]:
        """Open the recording: a new file with a header first, then append.

        Raises:
            ConfigError: the file cannot be created (no such folder, no
                permission), naming the file and the fix.
        """
        mode = "a" if self._started else "w"
        try:
            # Kept open between pages (closed in terminate), hence no `with`.
            file = open(self.filename, mode, encoding="utf-8", newline="\n")  # noqa: SIM115
        except OSError as error:
            raise self._cannot_write(error) from error
        if not self._started:
            try:
                file.write(header_line() + "\n")
                file.flush()
            except OSError as error:
                file.close()
                raise self._cannot_write(error) from error
            self._started = True
        return file

    def _cannot_write(self, error: OSError) -> ConfigError:
        folder = os.path.dirname(os.path.abspath(self.filename))
        return ConfigError(
            f"{type(self).__name__} cannot open {self.filename!r} for writing: "
            f"{error.strerror or error}. Check that the folder {folder!r} exists and "
            "that you may write there, or choose another filename."
        )

    def get(self, parent: AbstractNode) -> RecorderEndpoint:
        return RecorderEndpoint(self, parent)

    def __repr__(self) -> str:
        return f"RecorderEndpointFactory({self.filename!r}, {self.keys!r})"
