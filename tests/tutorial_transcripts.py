"""What docs/tutorial.md shows a step printing, and the rules to compare it with a run.

A *transcript* on the page is a fenced block whose first line is a command, as
typed (``$ python step01_first_endpoint.py``); the lines after it are what the
terminal shows: stdout and stderr, log lines included, in the order they come.

`compare` checks a run's output against a transcript, line by line, after
these rules, and no others:

1. **Clock times.** A log line starts with the time of day: ``12:00:00 `` on
   the page, the real time in a run. Both become ``HH:MM:SS ``.
2. **Ports.** A run listens on a port the test picked, where the page says
   9010 or 9123: the picked number is replaced by the page's. A port the OS
   picks (a client's end, ``from 127.0.0.1:53302``) becomes
   ``127.0.0.1:<ephemeral>`` on both sides.
3. **Durations.** ``Ran 5 tests in 0.034s`` becomes ``Ran 5 tests in <t>s``.
4. **Repeats.** A page line ``...`` says the line just above it stands for one
   or more lines *of the same shape*: the same text once every number is
   replaced by ``#`` (``depth 2.33 m`` and ``depth 2.62 m`` have the same
   shape). How many readings a loop makes in a given time depends on timing.
5. **Lines that come or not with timing,** listed in `TIMING_LINES` with the
   reason, are dropped from the run's output. The page explains them in words.

Anything else (a line added, removed or changed) is a difference, reported
as a diff of the page's block against the run's output.
"""

from __future__ import annotations

import difflib
import re
from typing import Dict, List, Optional, Sequence

REPEAT = "..."
"""The page line that says: more lines of the shape of the one above."""

TIMING_LINES: Dict[str, str] = {
    r"INFO: No peer is connected, so the page under ": (
        "step 4: whether the sensor's first reading is stored before its link to "
        "the display is up depends on which thread runs first"
    ),
}
"""Rule 5: a pattern of a log line that appears in some runs only -> why."""

_CLOCK = re.compile(r"^\d\d:\d\d:\d\d ")
_ANY_PORT = re.compile(r"127\.0\.0\.1:(\d+)")
_DURATION = re.compile(r"\b(Ran \d+ tests?) in [\d.]+s\b")
_NUMBER = re.compile(r"\d+(?:\.\d+)?")


def transcripts(markdown: str) -> Dict[str, List[str]]:
    """Every transcript of a page: ``{command line: the lines it prints}``.

    Raises:
        ValueError: two transcripts start with the same command line.
    """
    found: Dict[str, List[str]] = {}
    for lines in _fenced_blocks(markdown):
        if not lines or not lines[0].startswith("$ "):
            continue
        if lines[0] in found:
            raise ValueError(f"Two transcripts start with {lines[0]!r}: make them differ.")
        found[lines[0]] = lines[1:]
    return found


def _fenced_blocks(markdown: str) -> List[List[str]]:
    """The lines inside each ``` fence (of any language), in order."""
    blocks: List[List[str]] = []
    inside: Optional[List[str]] = None
    for line in markdown.splitlines():
        if line.lstrip().startswith("```"):
            if inside is None:
                inside = []
            else:
                blocks.append(inside)
                inside = None
        elif inside is not None:
            inside.append(line)
    return blocks


def normalise(line: str, ports: Optional[Dict[int, int]] = None) -> str:
    """``line`` after rules 1 to 3; ``ports`` maps a port the test picked to the page's."""
    line = _CLOCK.sub("HH:MM:SS ", line)
    for picked, shown in (ports or {}).items():
        line = re.sub(rf"(?<!\d){picked}(?!\d)", str(shown), line)
    shown_ports = {str(port) for port in (ports or {}).values()}
    line = _ANY_PORT.sub(
        lambda m: m.group(0) if m.group(1) in shown_ports else "127.0.0.1:<ephemeral>", line
    )
    return _DURATION.sub(r"\1 in <t>s", line)


def shape(line: str) -> str:
    """Rule 4: the line with every number replaced by ``#``."""
    return _NUMBER.sub("#", line)


def comes_with_timing(line: str) -> bool:
    """Rule 5: the line is one of `TIMING_LINES`."""
    return any(re.search(pattern, line) for pattern in TIMING_LINES)


def compare(
    page: Sequence[str], output: str, ports: Optional[Dict[int, int]] = None
) -> Optional[str]:
    """None when ``output`` is what the page shows, else a diff saying where it is not."""
    expected = [normalise(line, ports) for line in page]
    actual = [normalise(line, ports) for line in output.splitlines() if not comes_with_timing(line)]
    problem = _first_difference(expected, actual)
    if problem is None:
        return None
    diff = "\n".join(
        difflib.unified_diff(expected, actual, "the page", "the run", lineterm="", n=2)
    )
    return f"{problem}\n{diff}"


def _first_difference(expected: List[str], actual: List[str]) -> Optional[str]:
    i = j = 0  # i: the page's line, j: the run's
    while i < len(expected):
        line = expected[i]
        if i + 1 < len(expected) and expected[i + 1] == REPEAT:
            repeats = 0
            while j < len(actual) and shape(actual[j]) == shape(line):
                j += 1
                repeats += 1
            if repeats == 0:
                got = actual[j] if j < len(actual) else "(the end of the output)"
                return f"Page line {i + 1}: expected lines like {line!r}, got {got!r}."
            i += 2
            continue
        if j >= len(actual):
            return f"Page line {i + 1}: expected {line!r}, but the output ended."
        if actual[j] != line:
            return f"Page line {i + 1}: expected {line!r}, got {actual[j]!r}."
        i += 1
        j += 1
    if j < len(actual):
        return f"The output goes on after the page's last line: {actual[j]!r}."
    return None
