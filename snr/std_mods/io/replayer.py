"""Replay recordings: pages written by the recorder, or text lines (``docs/recording.md``).

`PageReader` reads a recording; `ReplayerLoopFactory` stores its pages into a
node again, timed as recorded or fast. `TextReader` and `TextReplayerFactory`
do the same for a text file, a page per line.
"""

from __future__ import annotations

import heapq
import logging
import math
import os
import sys
import threading
import time
from collections import deque
from contextlib import closing
from itertools import islice
from typing import (
    Any,
    Deque,
    Dict,
    Generator,
    Iterable,
    Iterator,
    List,
    NamedTuple,
    Optional,
    Sequence,
    Tuple,
    Union,
)

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
from snr.std_mods.codec import PathLike, check_header, decode_line, is_header, page_from_fields
from snr.std_mods.io import recording_formats

__all__ = [
    "MAX_GAP_S",
    "MAX_PROBLEMS",
    "PageReader",
    "REORDER_WINDOW",
    "RecordedPage",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
    "in_created_order",
]

_log = logging.getLogger("snr.replay")

DRAIN_ROUNDS = 100
"""How many times ``exit_when_done`` lets the queue go round before stopping."""

MAX_GAP_S = 10.0
"""Default longest wait between two timed pages, in seconds: a longer gap is likely a clock jump."""

REORDER_WINDOW = 1000
"""How many pages ahead the replayer looks for an earlier-made page of the same origin."""

MAX_PROBLEMS = 100
"""How many problems `PageReader.problems` keeps in full; `PageReader.bad_lines` counts all."""


class RecordedPage(NamedTuple):
    """A page read from a recording, with where it was and whether it had a time.

    Attributes:
        line: the line number in the file (the header is line 1); in an MCAP
            file, the message number (the first message is 1).
        page: the page.
        timed: False when the line had no ``created_at_s`` (the page then
            holds the time it was read).

    Example::

        for line, page, timed in PageReader("dive.jsonl").recorded_pages():
            print(line, page.key, page.created_at_s if timed else "no time")
    """

    line: int
    page: Page
    timed: bool


def _check_readable(filename: str, what: str) -> None:
    if not os.path.isfile(filename):
        raise ConfigError(
            f"{what} cannot read {filename!r}: there is no such file (looked in "
            f"{os.path.dirname(os.path.abspath(filename))!r}). Check the name, and that the "
            f"program runs in the folder you expect (it runs in {os.getcwd()!r})."
        )


def _fields(line: bytes) -> Optional[Dict[str, Any]]:
    """The JSON object on ``line``, or None when it is not one."""
    try:
        return decode_line(line)
    except Exception:
        return None


class PageReader:
    """Reads the pages of a recording in order; iterate over it.

    A file in another format an extra provides (MCAP: known by its first
    bytes, whatever its name; ``pip install 'snr-robotics[mcap]'``) is read by
    that extra, its messages taken as lines are ("message N" for "line N").
    Any line that is not a valid page is logged with its line number, listed
    in ``problems`` and skipped, a last line cut short included: the first
    five in full, then a count every 5 s, and a summary with the total at the
    end (``docs/recording.md``, "Reading").

    Args:
        filename: a file written by `RecorderEndpointFactory`.

    Raises:
        ConfigError: the file does not exist, or is MCAP and the mcap
            package is not installed.
        WireFormatError: the file starts with the header of a newer SNR's
            format, or of another format.

    Attributes:
        problems: the first `MAX_PROBLEMS` bad lines, each as
            ``"file:line: reason"`` (MCAP: ``"file: message N: reason"``).
        bad_lines: how many bad lines (or MCAP messages) were skipped in all.
        file_format: ``"jsonl"``, or the format an extra reads (``"mcap"``).
        is_mcap: True when the file is MCAP.

    Example::

        for page in PageReader("dive.jsonl"):
            print(page.key, page.data)
    """

    def __init__(self, filename: PathLike) -> None:
        self.filename = os.fspath(filename)
        _check_readable(self.filename, "PageReader")
        self.problems: List[str] = []
        self.bad_lines = 0
        with open(self.filename, "rb") as file:
            first = file.readline()  # MCAP's magic ends with a newline too
        self.file_format = recording_formats.format_of_bytes(first)
        self.is_mcap = self.file_format == "mcap"
        self._format: Optional[recording_formats.RecordingFormat] = None
        if self.file_format != "jsonl":  # fail now if its package is missing
            what = f"Reading the {self.file_format.upper()} file {self.filename!r}"
            self._format = recording_formats.get(self.file_format, what)
            self._format.require(what, "stream_reader")
            return
        fields = _fields(first)  # not JSON: reported as a bad line when read
        if fields is not None and is_header(fields):
            try:  # a newer format fails now, not halfway through a replay
                check_header(fields)
            except WireFormatError as error:
                raise WireFormatError(f"Cannot replay {self.filename!r}: {error}.") from error

    def __iter__(self) -> Iterator[Page]:
        with closing(self.recorded_pages()) as recorded:  # the file closes if iteration stops
            for item in recorded:
                yield item.page

    def recorded_pages(self) -> Generator[RecordedPage, None, None]:
        """The pages with their line numbers, and whether each line had a time.

        Reading starts again at the top of the file on each call; the
        counts of bad lines start again too.

        Example::

            for recorded in PageReader("dive.jsonl").recorded_pages():
                print(f"line {recorded.line}: {recorded.page.data}")
        """
        self.problems, self.bad_lines = [], 0
        self._numbers: List[int] = []  # the first ten, for the summary
        self._repeats = RepeatFilter(_log, first=5)  # a corrupt file may hold thousands
        fmt, name = self._format, self.filename
        unit = "line" if fmt is None else fmt.unit
        pages = (
            self._lines()
            if fmt is None
            else fmt.read_pages(name, lambda n, why: self._report(n, f"{name}: {unit} {n}: {why}"))
        )
        try:
            for number, page, timed in pages:
                yield RecordedPage(number, page, timed)
        finally:
            getattr(pages, "close", lambda: None)()  # the file, now
            bad, units = self.bad_lines, unit if self.bad_lines == 1 else unit + "s"
            shown = ", ".join(map(str, self._numbers)) + (", ..." if bad > 10 else "")
            more = f", {bad - 5} more times than logged in full above" if bad > 5 else ""
            if bad:
                _log.warning(
                    f"{name}: skipped {bad} bad {units} in all ({units} {shown}){more}; "
                    f"every other {unit} was read."
                )

    def _lines(self) -> Iterator[Tuple[int, Page, bool]]:
        with open(self.filename, "rb") as file:
            for number, raw in enumerate(file, start=1):
                try:
                    if not raw.strip():
                        continue
                    fields = decode_line(raw)
                    if is_header(fields):
                        check_header(fields)  # e.g. two recordings joined with `cat`
                        continue
                    page = page_from_fields(fields)
                except Exception as error:  # whatever a line holds, replay goes on
                    why = str(error) if isinstance(error, WireFormatError) else repr(error)[:200]
                    where = f"{self.filename}:{number}: skipped a bad line"
                    if not raw.endswith(b"\n"):
                        where += " (cut short: the recorder stopped mid-line)"
                    self._report(number, f"{where}: {why}")
                    continue
                yield number, page, "created_at_s" in fields

    def _report(self, number: int, problem: str) -> None:
        name, self.bad_lines = self.filename, self.bad_lines + 1
        if len(self.problems) < MAX_PROBLEMS:
            self.problems.append(problem)
        if len(self._numbers) < 10:
            self._numbers.append(number)
        self._repeats.report(name, f"Bad lines in {name}", logging.WARNING, problem)


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
                raw = raw.rstrip(b"\r\n")
                try:
                    line = raw.decode(self.encoding)
                except UnicodeDecodeError as error:
                    problem = (
                        f"{self.filename}:{number}: not valid {self.encoding} ({error.reason}); "
                        "replayed with the bad bytes replaced"
                    )
                    self.problems.append(problem)
                    _log.warning(problem)
                    line = raw.decode(self.encoding, errors="replace")
                yield line


class ReplayerLoop(ThreadLoop):
    """Stores the pages of a recording, each with its key, data, origin and time; or text lines.

    Each origin's pages are stored in the order they were made, even where
    the file's lines are out of order (see `in_created_order`). With original
    timing each page waits as long after the previous one as it was created
    after it, following each origin's clock on its own; a page with no time,
    a gap over ``max_gap_s`` or a time going back is stored right away (or
    after ``max_gap_s``) and logged with its line number. The factory says
    what to store and when (``items``); the count of items replayed lives on
    it, so after a hot reload the replay goes on where it was.

    Example::

        ReplayerLoopFactory("dive.jsonl", fast=True, exit_when_done=True)
    """

    def __init__(self, factory: _ReplayFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.replay = factory
        self._items = factory.items()  # now: a missing file fails the build
        self._done_event = f"{self.name}_done"
        if factory.exit_when_done:
            self.task_handlers = {(TaskType.event, self._done_event): self.finish_node}

    def loop(self) -> None:
        try:
            step = next(self._items, None)
            if step is None:
                self.set_terminate_flag("replayed the whole file")
                if self.replay.exit_when_done:  # finish_node says it, after what they printed
                    self._schedule_exit(True)
                else:
                    self._say_replayed()
            elif not (step[0] > 0 and self.wait_s(step[0])):  # True: the node is stopping
                self.store(step[1])
                self.replay.position += 1
        except Exception:
            # Reported by the node like any loop's error. In DEPLOYED mode the
            # node keeps running without this loop: exit_when_done still stops it.
            self._schedule_exit(False)
            raise

    def store(self, item: Union[Page, Tuple[DataKey, str]]) -> None:
        """Store one item: a recorded page as it was made, or a text line as ``(key, line)``."""
        if isinstance(item, Page):
            self.store_page(item)  # origin and created_at_s as recorded
        else:
            self.store_data(*item)

    def _say_replayed(self) -> None:
        replay = self.replay
        self.info(f"Replayed {replay.position} items from {replay.filename}{replay.summary()}")

    def _schedule_exit(self, replayed: bool) -> None:  # once: the loop stops after it
        if self.replay.exit_when_done:
            self.schedule(tasks.event(self._done_event, [0, replayed]))

    def finish_node(self, task: Task, key: TaskId) -> SomeTasks:
        """Stop the node once it has handled what the replayed items caused.

        The event goes to the back of the queue again while other tasks wait
        (the pages' ``process_data`` tasks and what they trigger), at most
        ``DRAIN_ROUNDS`` times, so nothing replayed is cut off by the stop.
        """
        # [rounds, whole file replayed] from the loop; [rounds] or [] by hand, as before.
        rounds = task.val_list[0] if task.val_list else DRAIN_ROUNDS
        replayed = len(task.val_list) > 1 and bool(task.val_list[1])
        queue = getattr(self.parent, "queue", None)  # a real Node's task queue
        if queue and rounds < DRAIN_ROUNDS:
            return tasks.event(self._done_event, [rounds + 1, replayed])
        if replayed:  # the whole file, not a failed loop
            self._say_replayed()
        return tasks.terminate(f"replayed {self.replay.filename}")

    def terminate(self) -> None:
        """Close the file if the replay stopped before its end."""
        getattr(self._items, "close", lambda: None)()


class TextReplayerLoop(ReplayerLoop):
    """Stores each line of a text file as data under one key, ``period_s`` apart.

    The `ReplayerLoop` a `TextReplayerFactory` builds, its items text lines;
    a class of its own so that its log and error messages name it.

    Example::

        TextReplayerFactory("gps_log.txt", "nmea", period_s=0.1)
    """


def in_created_order(
    recorded: Iterable[RecordedPage], max_jump_s: float, window: int = REORDER_WINDOW
) -> Iterator[RecordedPage]:
    """``recorded`` with each origin's pages in the order they were made (``created_at_s``).

    A recording's lines can be out of order (the 2021 node handled the newest
    task first). Each page takes the place in the file of one of its origin's
    pages, so the origins stay interleaved as recorded and their clocks are
    never compared. Pages further apart than ``window`` lines are not swapped,
    and neither are pages on either side of a clock jump (more than
    ``max_jump_s`` either way): those are timing problems, left to `ReplayerLoop`.
    Pages without a time keep their places.

    Example::

        for recorded in in_created_order(PageReader("old.jsonl").recorded_pages(), 10.0):
            print(recorded.page.created_at_s)
    """
    ahead: Deque[Optional[str]] = deque()  # the origin of each page read ahead, in file order
    heaps: Dict[Optional[str], List[Tuple[int, float, int, RecordedPage]]] = {}
    last: Dict[str, Tuple[int, float]] = {}  # origin -> (clock segment, time) of its last page
    for item in recorded:
        origin: Optional[str] = None  # no time: a stream of its own, in file order
        segment, created = 0, 0.0
        if item.timed:
            origin, created = item.page.origin, item.page.created_at_s
            segment, previous = last.get(origin, (0, created))
            segment += abs(created - previous) > max_jump_s
            last[origin] = (segment, created)
        heapq.heappush(heaps.setdefault(origin, []), (segment, created, item.line, item))
        ahead.append(origin)
        if len(ahead) > window:
            yield heapq.heappop(heaps[ahead.popleft()])[-1]
    while ahead:
        yield heapq.heappop(heaps[ahead.popleft()])[-1]


def _seconds(value: float) -> str:
    """A number of seconds for a message, short even when absurd."""
    return f"{value:.3g}" if math.isfinite(value) else "an unbounded number of"


class _ReplayFactory(LoopFactory):
    """What both replayer factories share: the file, the loop's name, where the replay is."""

    def __init__(self, filename: PathLike, exit_when_done: bool, name: str) -> None:
        super().__init__(sys.modules[__name__])
        self.filename = os.fspath(filename)
        self.exit_when_done = exit_when_done
        self.name = name
        self.position = 0

    def items(self) -> Iterator[Tuple[float, Any]]:
        """``(seconds to wait, item)`` for each item after the first ``position``."""
        raise NotImplementedError

    def summary(self) -> str:
        """What went wrong with the file, for the last log line ("" if nothing)."""
        return ""


class ReplayerLoopFactory(_ReplayFactory):
    """Builds a `ReplayerLoop` that replays a recording into the node.

    Args:
        filename: a file written by `RecorderEndpointFactory`.
        fast: store the pages as fast as possible instead of with their
            original spacing in time.
        exit_when_done: stop the node after the last page (once the node has
            handled what the pages caused), in every mode.
        keys: replay only pages under these keys (default: all).
        name: the loop's name (default ``"replayer"``).
        max_gap_s: with original timing, the longest wait between two pages
            (default `MAX_GAP_S`, 10 s); a longer gap in the recording is
            cut to this and logged with its line number.

    Raises:
        ConfigError: ``max_gap_s`` is negative, not finite or too large.

    Example::

        config = Config({"sim": [
            ReplayerLoopFactory("dive.jsonl", exit_when_done=True),
            MovingAvgFilterFactory("depth_m", "depth_smooth", 5),
        ]})

    Attributes:
        position: pages replayed so far (kept across reloads).
        bad_lines: bad lines skipped, known at the end of the file.
        retimed: pages not stored at their recorded time (no time, a gap
            over ``max_gap_s``, time going back).
    """

    def __init__(
        self,
        filename: PathLike,
        fast: bool = False,
        exit_when_done: bool = False,
        keys: Optional[Sequence[DataKey]] = None,
        name: Optional[str] = None,
        max_gap_s: float = MAX_GAP_S,
    ) -> None:
        super().__init__(filename, exit_when_done, name or "replayer")
        self.fast = fast
        self.keys: Optional[List[DataKey]] = None if keys is None else list(keys)
        # NaN fails the comparison, infinity is over TIMEOUT_MAX.
        if not (isinstance(max_gap_s, (int, float)) and 0 <= max_gap_s <= threading.TIMEOUT_MAX):
            raise ConfigError(
                f"ReplayerLoopFactory({self.filename!r}, max_gap_s={max_gap_s!r}): use a "
                "number of seconds, 0 or more (e.g. 10.0)."
            )
        self.max_gap_s = float(max_gap_s)
        self.bad_lines = 0
        self.retimed = 0

    def items(self) -> Iterator[Tuple[float, Any]]:
        """``(seconds to wait, item)`` for each item after the first ``position``.

        The file opens now, so a missing one fails when the node is built.

        Example::

            wait_s, page = next(ReplayerLoopFactory("dive.jsonl").items())
        """
        return self._timed(PageReader(self.filename))

    def _timed(self, reader: PageReader) -> Iterator[Tuple[float, Page]]:
        keys, warn = self.keys, RepeatFilter(_log, first=5).report
        due: Optional[float] = None  # when the previous page was due (monotonic)
        offsets: Dict[str, float] = {}  # origin -> replay time minus created_at_s
        with closing(reader.recorded_pages()) as recorded:
            wanted = (r for r in recorded if keys is None or r.page.key in keys)
            ordered = in_created_order(wanted, max(self.max_gap_s, MAX_GAP_S))
            for item in islice(ordered, self.position, None):
                now = time.monotonic()
                if self.fast or (due is None and not item.timed):
                    due = now
                else:  # the first page (also after a reload) is due now
                    due, why = self._next_due(item, now if due is None else due, offsets)
                    if why:  # counted, and logged (the first five of each kind in full)
                        self.retimed += 1
                        kind, text = why
                        what = f"Replay timing of {self.filename} ({kind})"
                        warn(
                            kind, what, logging.WARNING, f"{self.filename}:{item.line}: the {text}"
                        )
                yield due - now, item.page
        self.bad_lines = reader.bad_lines

    def _next_due(
        self, item: RecordedPage, previous: float, offsets: Dict[str, float]
    ) -> Tuple[float, Optional[Tuple[str, str]]]:
        """When ``item`` is due, given when the page before it was due, and why.

        Returns ``(due, why)``: ``why`` is ``(kind, warning)`` when the page
        is not stored at its recorded time, else None.
        """
        page, max_gap = item.page, self.max_gap_s
        if not item.timed:
            text = f"page under {page.key!r} has no created_at_s: stored right after the"
            return previous, ("no time", text + " previous page.")
        # An origin's first page starts its clock; later ones follow it, within max_gap.
        offset = offsets.setdefault(page.origin, previous - page.created_at_s)
        gap = page.created_at_s + offset - previous
        if gap > max_gap:
            due, kind = previous + max_gap, "gap"
            text = (
                f"page under {page.key!r} was created {_seconds(gap)} s after the one "
                f"before it: waiting {max_gap:g} s instead (max_gap_s)."
            )
        elif gap < -max_gap:
            due, kind = previous, "back"
            text = (
                f"time of the page under {page.key!r} goes back by {_seconds(-gap)} s: "
                "stored right after the previous page."
            )
        else:  # a little back (two nodes' clocks): no wait
            return previous + max(gap, 0.0), None
        offsets[page.origin] = due - page.created_at_s  # follow the clock from here
        return due, (kind, text)

    def summary(self) -> str:
        """The bad lines skipped and the pages retimed, for the last log line.

        Example::

            ReplayerLoopFactory("dive.jsonl").summary()  # "" until a replay finds problems
        """
        parts = [f"{self.bad_lines} bad lines skipped"] if self.bad_lines else []
        if self.retimed:
            parts.append(f"{self.retimed} pages not stored at their recorded time")
        return f" ({'; '.join(parts)}; see the warnings above)" if parts else ""

    def get(self, parent: AbstractNode) -> ReplayerLoop:
        return ReplayerLoop(self, parent)

    def __repr__(self) -> str:
        return f"ReplayerLoopFactory({self.filename!r}, fast={self.fast})"


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

    def items(self) -> Iterator[Tuple[float, Any]]:
        lines = islice(TextReader(self.filename, self.encoding), self.position, None)
        return ((self.period_s if n else 0.0, (self.key, line)) for n, line in enumerate(lines))

    def get(self, parent: AbstractNode) -> TextReplayerLoop:
        return TextReplayerLoop(self, parent)

    def __repr__(self) -> str:
        return f"TextReplayerFactory({self.filename!r}, {self.key!r})"
