"""A recording as columns, one per key, for a notebook: `read_recording`.

`PageReader` gives a recording page by page; to plot a run you want it the
other way round, key by key: the times in one list, the values in another.
`read_recording` reads the whole file (JSON lines or MCAP) with `PageReader`
and returns a `Recording`, a dict of `Column` by key, made of plain lists
(no pandas needed)::

    import matplotlib.pyplot as plt
    from snr import read_recording

    run = read_recording("dive.jsonl")
    depth = run["depth_m"]
    plt.plot(depth.t_s, depth.fields["depth_m"])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, Iterable, List, Optional, Tuple

from snr.core.checks.error_text import did_you_mean
from snr.prelude import ConfigError, DataKey
from snr.std_mods.codec import PathLike, decode_line, is_header, page_from_fields
from snr.std_mods.io.replayer import PageReader

__all__ = ["Column", "Recording", "read_recording"]


@dataclass
class Column:
    """The pages of one key in a recording, as lists of the same length, in file order.

    Attributes:
        key: the data key, e.g. ``"depth_m"``.
        t_s: each page's time in seconds since the recording's first page
            (from ``created_at_s``); NaN for a line that had no time.
        data: each page's data, as stored.
        origin: the role of the node that made each page, e.g. ``"urov"``.
        fields: when every page's data is a number, or a dict or list of
            numbers, one list of floats per field: a number's one field is
            named after the key, a dict's fields by its keys, a list's by
            position (``"0"``, ``"1"``, ...). A field a page lacks is NaN
            there (matplotlib leaves a gap). Empty when the data is not
            numbers; then ``not_numeric`` says why.
        not_numeric: "" when ``fields`` is filled, else the first page whose
            data is not numbers, e.g. ``"page 3 of 'mode' holds 'on' (str)"``.

    Example::

        heading = read_recording("dive.jsonl")["heading_deg"]
        print(len(heading.t_s), heading.data[0], list(heading.fields))
        plt.plot(heading.t_s, heading.fields["heading_deg"])
    """

    key: DataKey
    t_s: List[float] = field(default_factory=list)
    data: List[Any] = field(default_factory=list)
    origin: List[str] = field(default_factory=list)
    fields: Dict[str, List[float]] = field(default_factory=dict)
    not_numeric: str = ""


class Recording(Dict[DataKey, Column]):
    """A recording read by `read_recording`: a dict of `Column` by key, in order of first page.

    A key that is not in it raises a `ConfigError` (not a `KeyError`) that
    names the keys that are; ``key in run`` and ``run.get(key)`` ask without
    raising.

    Attributes:
        filename: the file it was read from.
        start_s: the ``created_at_s`` of its earliest page (the zero of every
            ``t_s``), or NaN if it holds no timed page.
        problems: the bad lines skipped, as ``PageReader.problems`` lists them.

    Example::

        run = read_recording("dive.jsonl")
        print(run.filename, list(run), run.start_s)
    """

    def __init__(self, filename: str, start_s: float, problems: List[str]) -> None:
        super().__init__()
        self.filename = filename
        self.start_s = start_s
        self.problems = problems

    def __missing__(self, key: DataKey) -> Column:
        raise _not_recorded(self.filename, key, list(self))


def _not_recorded(filename: str, key: str, keys: List[str]) -> ConfigError:
    """The error for a key a recording holds no page of: it names the keys it holds."""
    if not keys:
        return ConfigError(f"{filename!r} holds no pages at all, so no page of key {key!r}.")
    known = ", ".join(map(repr, keys))
    return ConfigError(
        f"{filename!r} holds no page of key {key!r}; its keys are {known}."
        + did_you_mean(key, keys)
    )


def read_recording(filename: PathLike, keys: Optional[Iterable[DataKey]] = None) -> Recording:
    """Read a recording (JSON lines or MCAP) into one `Column` per key.

    Bad lines are skipped, logged and listed in ``problems``, as
    `PageReader` does.

    Args:
        filename: a file written by `RecorderEndpointFactory` (or
            ``python -m snr convert``).
        keys: read only these keys (default: all); each must be in the file.

    Raises:
        ConfigError: the file does not exist, is not a recording, is MCAP
            and the mcap package is missing, or holds no page of one of
            ``keys`` (the message names the keys it holds).

    Example::

        run = read_recording("dive.jsonl")
        for key, column in run.items():
            print(key, len(column.t_s), "pages")
        depth = run["depth_m"]
        plt.plot(depth.t_s, depth.fields["depth_m"])
    """
    reader = PageReader(filename)
    if not reader.is_mcap:
        _check_first_line(reader.filename)
    wanted = None if keys is None else list(keys)
    columns: Dict[DataKey, Column] = {}
    times: List[float] = []
    seen: Dict[DataKey, None] = {}  # every key in the file, in order, for the error below
    for _, page, timed in reader.recorded_pages():
        seen[page.key] = None
        if wanted is not None and page.key not in wanted:
            continue
        column = columns.setdefault(page.key, Column(page.key))
        column.t_s.append(page.created_at_s if timed else math.nan)
        column.data.append(page.data)
        column.origin.append(page.origin)
        if timed:
            times.append(page.created_at_s)
    start_s = min(times) if times else math.nan
    recording = Recording(reader.filename, start_s, reader.problems)
    for key, column in columns.items():
        column.t_s = [t - start_s for t in column.t_s]
        column.fields, column.not_numeric = _fields(column)
        recording[key] = column
    for key in wanted or ():
        if key not in recording:
            raise _not_recorded(recording.filename, key, list(seen))
    return recording


def _check_first_line(filename: str) -> None:
    """Refuse a file that is not JSON lines of pages now, before a warning per line."""
    with open(filename, "rb") as file:
        first = file.readline()
    if not first.strip():
        return  # empty: a recording of nothing
    try:
        fields = decode_line(first)
        if not is_header(fields):
            page_from_fields(fields)
    except Exception as error:
        shown = first[:60].decode("utf-8", errors="replace").rstrip()
        raise ConfigError(
            f"{filename!r} is not a recording: its first line ({shown!r}) is neither SNR's "
            f"header nor a page ({error}). read_recording reads the files "
            "RecorderEndpointFactory writes (JSON lines or MCAP; docs/recording.md)."
        ) from None


def _fields(column: Column) -> Tuple[Dict[str, List[float]], str]:
    """``column``'s numeric fields, or ({}, why not) if a page's data is not numbers."""
    rows: List[Dict[str, float]] = []
    for number, data in enumerate(column.data, start=1):
        row = _numbers(column.key, data)
        if row is None:
            shown = repr(data) if len(repr(data)) <= 40 else repr(data)[:37] + "..."
            return {}, f"page {number} of {column.key!r} holds {shown} ({type(data).__name__})"
        rows.append(row)
    fields: Dict[str, List[float]] = {}
    for row in rows:
        for name in row:
            fields.setdefault(name, [])
    for name, values in fields.items():
        values.extend(row.get(name, math.nan) for row in rows)
    return fields, ""


def _numbers(key: str, data: Any) -> Optional[Dict[str, float]]:
    """A page's data as named numbers, or None if it is not a number, dict or list of numbers."""
    if _is_number(data):
        return {key: float(data)}
    if isinstance(data, dict) and data and all(_is_number(v) for v in data.values()):
        return {str(name): float(value) for name, value in data.items()}
    if isinstance(data, (list, tuple)) and data and all(_is_number(v) for v in data):
        return {str(index): float(value) for index, value in enumerate(data)}
    return None


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
