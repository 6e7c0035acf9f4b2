"""Replay recordings: pages written by the recorder, or plain text lines.

* `PageReader` reads a recording (format: ``snr.std_mods.codec``) back, page by page.
* `ReplayerLoopFactory` stores those pages into a node again, with their
  original spacing in time or as fast as possible.
* `TextReader` / `TextReplayerFactory` do the same for a plain text file: one
  page per line, e.g. a log of NMEA sentences from a GPS.

A malformed line is reported with its line number and skipped; the rest of
the file is still replayed.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from typing import Generic, Iterator, List, Optional, Sequence, TypeVar

from snr.core import LoopFactory, ThreadLoop, tasks
from snr.core.logs import RepeatFilter
from snr.prelude import (
    AbstractNode,
    ConfigError,
    DataKey,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    WireFormatError,
)
from snr.std_mods.codec import (
    PathLike,
    check_header,
    decode_line,
    is_header,
    page_from_fields,
)

__all__ = [
    "PageReader",
    "ReplayLoop",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
]

_log = logging.getLogger("snr.replay")

DRAIN_ROUNDS = 100
"""How many times ``exit_when_done`` lets the queue go round before stopping."""


def _check_readable(filename: str, what: str) -> None:
    if not os.path.isfile(filename):
        folder = os.path.dirname(os.path.abspath(filename))
        raise ConfigError(
            f"{what} cannot read {filename!r}: there is no such file (looked in {folder!r}). "
            "Check the name, and that the program runs in the folder you expect "
            f"(it runs in {os.getcwd()!r})."
        )


class PageReader:
    """Reads the pages of a recording, in order; iterate over it.

    Bad lines are logged with their line number, listed in ``problems`` and
    skipped. A last line cut short (the recorder was killed mid-write) is
    reported the same way.

    Args:
        filename: a file written by `RecorderEndpointFactory`.

    Raises:
        ConfigError: the file does not exist.
        WireFormatError: the file starts with the header of a newer SNR's
            format, or of another format.

    Example::

        for page in PageReader("dive.jsonl"):
            print(page.key, page.data)
    """

    def __init__(self, filename: PathLike) -> None:
        self.filename = os.fspath(filename)
        _check_readable(self.filename, "PageReader")
        self.problems: List[str] = []
        # A corrupt file can hold thousands of bad lines: log the first few in full.
        self._repeats = RepeatFilter(_log, first=5)
        with open(self.filename, "rb") as file:
            self._check_if_header(file.readline())  # fail now, not halfway through a replay

    def __iter__(self) -> Iterator[Page]:
        try:
            with open(self.filename, "rb") as file:
                for number, raw in enumerate(file, start=1):
                    page = self._parse(number, raw)
                    if page is not None:
                        yield page
        finally:
            self._repeats.flush()  # the count of bad lines not logged one by one

    def _check_if_header(self, raw: bytes) -> None:
        try:
            fields = decode_line(raw)
        except WireFormatError:
            return  # not a header: _parse reports the line when it comes to it
        if is_header(fields):
            try:
                check_header(fields)
            except WireFormatError as error:
                raise WireFormatError(f"Cannot replay {self.filename!r}: {error}.") from error

    def _parse(self, number: int, raw: bytes) -> Optional[Page]:
        if not raw.strip():
            return None
        try:
            fields = decode_line(raw)
            if is_header(fields):
                check_header(fields)  # e.g. two recordings joined with `cat`
                return None
            return page_from_fields(fields)
        except WireFormatError as error:
            cut = "" if raw.endswith(b"\n") else " (cut short: the recorder stopped mid-line)"
            self._report(f"{self.filename}:{number}: skipped a bad line{cut}: {error}")
            return None

    def _report(self, problem: str) -> None:
        self.problems.append(problem)
        self._repeats.report(
            self.filename, f"Bad lines in {self.filename}", logging.WARNING, "%s", problem
        )


class TextReader:
    """Reads a text file line by line, without the line endings.

    Lines that are not valid UTF-8 are reported with their line number and
    kept, with the bad bytes replaced by ``\\ufffd``.

    Example::

        for line in TextReader("gps_log.txt"):
            print(line)
    """

    def __init__(self, filename: PathLike, encoding: str = "utf-8") -> None:
        self.filename = os.fspath(filename)
        _check_readable(self.filename, "TextReader")
        self.encoding = encoding
        self.problems: List[str] = []

    def __iter__(self) -> Iterator[str]:
        with open(self.filename, "rb") as file:
            for number, raw in enumerate(file, start=1):
                yield self._decode(number, raw.rstrip(b"\r\n"))

    def _decode(self, number: int, raw: bytes) -> str:
        try:
            return raw.decode(self.encoding)
        except UnicodeDecodeError as error:
            problem = (
                f"{self.filename}:{number}: not valid {self.encoding} ({error.reason}); "
                "replayed with the bad bytes replaced"
            )
            self.problems.append(problem)
            _log.warning("%s", problem)
            return raw.decode(self.encoding, errors="replace")


Item = TypeVar("Item")


class ReplayLoop(ThreadLoop, Generic[Item]):
    """What both replayers share: step through a file, then stop.

    Subclasses say how to read the file (``items``), how long to wait before
    each item (``delay_s``) and how to store it (``store``). The count of
    items replayed lives on the factory, so after a hot reload the replay
    goes on where it was instead of starting over.

    Example: see `ReplayerLoop` and `TextReplayerLoop`.
    """

    def __init__(self, factory: _ReplayFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.replay = factory
        self._items: Optional[Iterator[Item]] = None
        self._done_event = f"{self.name}_done"
        if factory.exit_when_done:
            self.task_handlers = {(TaskType.event, self._done_event): self.finish_node}

    # -- what subclasses fill in ---------------------------------------------
    def items(self) -> Iterator[Item]:
        """The items of the file, in order."""
        raise NotImplementedError

    def delay_s(self, item: Item) -> float:
        """Seconds to wait before storing ``item``."""
        raise NotImplementedError

    def store(self, item: Item) -> None:
        """Store ``item`` in the node."""
        raise NotImplementedError

    # -- the loop -------------------------------------------------------------
    def setup(self) -> None:
        self._items = self.items()
        for _ in range(self.replay.position):  # resume after a reload
            if next(self._items, None) is None:
                break

    def loop(self) -> None:
        assert self._items is not None  # set in setup()
        item = next(self._items, None)
        if item is None:
            self._finished()
            return
        delay = self.delay_s(item)
        if delay > 0 and self.wait_s(delay):
            return  # the node is stopping; this item was not stored
        self.store(item)
        self.replay.position += 1

    def _finished(self) -> None:
        self.info("Replayed %d items from %s", self.replay.position, self.replay.filename)
        self.set_terminate_flag("replayed the whole file")
        if self.replay.exit_when_done:
            self.schedule(tasks.event(self._done_event, [0]))

    def finish_node(self, task: Task, key: TaskId) -> SomeTasks:
        """Stop the node once it has handled what the replayed items caused.

        The event goes to the back of the queue again while other tasks wait
        (the pages' ``process_data`` tasks and what they trigger), at most
        ``DRAIN_ROUNDS`` times, so nothing replayed is cut off by the stop.
        """
        rounds = task.val_list[0] if task.val_list else DRAIN_ROUNDS
        queue = getattr(self.parent, "queue", None)  # a real Node's task queue
        if queue is not None and len(queue) > 0 and rounds < DRAIN_ROUNDS:
            return tasks.event(self._done_event, [rounds + 1])
        return tasks.terminate(f"replayed {self.replay.filename}")

    def terminate(self) -> None:
        """Close the file if the replay stopped before its end."""
        items, self._items = self._items, None
        close = getattr(items, "close", None)
        if close is not None:
            close()


class _ReplayFactory(LoopFactory):
    """Options shared by both replayer factories (the position survives reload)."""

    def __init__(self, filename: PathLike, exit_when_done: bool, name: str) -> None:
        super().__init__(sys.modules[__name__])
        self.filename = os.fspath(filename)
        self.exit_when_done = exit_when_done
        self.name = name
        self.position = 0


class ReplayerLoop(ReplayLoop[Page]):
    """Stores the pages of a recording, each with its key, data, origin and time.

    With original timing, page *n* is stored ``created_at_s[n] -
    created_at_s[0]`` seconds after the first one.

    Example::

        ReplayerLoopFactory("dive.jsonl", fast=True, exit_when_done=True)
    """

    def __init__(self, factory: ReplayerLoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent)
        self.options = factory
        self.reader = PageReader(factory.filename)
        self._started_at: Optional[float] = None
        self._first_created_s = 0.0

    def items(self) -> Iterator[Page]:
        pages = iter(self.reader)
        if self.options.keys is None:
            return pages
        keys = set(self.options.keys)
        return (page for page in pages if page.key in keys)

    def delay_s(self, item: Page) -> float:
        if self.options.fast:
            return 0.0
        now = time.monotonic()
        if self._started_at is None:
            self._started_at, self._first_created_s = now, item.created_at_s
        due = self._started_at + (item.created_at_s - self._first_created_s)
        return due - now

    def store(self, item: Page) -> None:
        self.store_page(item)  # the page as recorded: origin and created_at_s kept


class ReplayerLoopFactory(_ReplayFactory):
    """Builds a `ReplayerLoop` that replays a recording into the node.

    Args:
        filename: a file written by `RecorderEndpointFactory`.
        fast: store the pages as fast as possible instead of with their
            original spacing in time.
        exit_when_done: stop the node after the last page (once the node has
            handled what the pages caused).
        keys: replay only pages under these keys (default: all).
        name: the loop's name (default ``"replayer"``).

    Example::

        config = Config({"sim": [
            ReplayerLoopFactory("dive.jsonl", exit_when_done=True),
            MovingAvgFilterFactory("depth_m", "depth_smooth", 5),
        ]})
    """

    def __init__(
        self,
        filename: PathLike,
        fast: bool = False,
        exit_when_done: bool = False,
        keys: Optional[Sequence[DataKey]] = None,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(filename, exit_when_done, name or "replayer")
        self.fast = fast
        self.keys: Optional[List[DataKey]] = None if keys is None else list(keys)

    def get(self, parent: AbstractNode) -> ReplayerLoop:
        return ReplayerLoop(self, parent)

    def __repr__(self) -> str:
        return f"ReplayerLoopFactory({self.filename!r}, fast={self.fast})"


class TextReplayerLoop(ReplayLoop[str]):
    """Stores each line of a text file as data under one key.

    Example::

        TextReplayerFactory("gps_log.txt", "nmea", period_s=0.1)
    """

    def __init__(self, factory: TextReplayerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent)
        self.options = factory
        self.reader = TextReader(factory.filename, factory.encoding)
        self._first = True

    def items(self) -> Iterator[str]:
        return iter(self.reader)

    def delay_s(self, item: str) -> float:
        first, self._first = self._first, False
        return 0.0 if first else self.options.period_s

    def store(self, item: str) -> None:
        self.store_data(self.options.key, item)


class TextReplayerFactory(_ReplayFactory):
    """Builds a `TextReplayerLoop`: one page per line of a text file.

    Args:
        filename: the text file.
        key: the data key to store each line under (newline stripped).
        period_s: seconds between lines (0: as fast as possible).
        exit_when_done: stop the node after the last line.
        encoding: the file's text encoding.
        name: the loop's name (default ``"text_replayer"``).

    Example::

        TextReplayerFactory("commands.txt", "command", period_s=0.5, exit_when_done=True)
    """

    def __init__(
        self,
        filename: PathLike,
        key: DataKey,
        period_s: float = 0.0,
        exit_when_done: bool = False,
        encoding: str = "utf-8",
        name: Optional[str] = None,
    ) -> None:
        super().__init__(filename, exit_when_done, name or "text_replayer")
        if period_s < 0:
            raise ConfigError(f"TextReplayerFactory(period_s={period_s}): use 0 or more seconds.")
        self.key = key
        self.period_s = period_s
        self.encoding = encoding

    def get(self, parent: AbstractNode) -> TextReplayerLoop:
        return TextReplayerLoop(self, parent)

    def __repr__(self) -> str:
        return f"TextReplayerFactory({self.filename!r}, {self.key!r})"
