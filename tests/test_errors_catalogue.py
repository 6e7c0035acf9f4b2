"""docs/errors.md sections 1-11 and 14, run as printed: each program's real output is the page's.

Every entry there is a complete ``robot.py`` with the command that runs it and
what that prints. Each test here runs that very program in this process (see
`tests.test_errors_silence.run_program`: the real `CliRunner`, node and
components) with that command line, and compares its output with the page's,
line by line and in order. A ``...`` line on the page stands for any lines.

What is normalised before comparing, as the page's introduction says:

* time stamps (``11:44:47``), and Python's ``^^^^`` markers under a line;
* the program's folder, shown as ``/home/student/rov``;
* the node's hint times, cut short so the suite stays fast, are compared as
  their defaults: a key nobody stores is reported after 0.3 s instead of
  ``node.key_hints.missing_s`` (5 s), and a link's keys are checked 0.2 s after
  it comes up instead of ``link_s`` (3 s); a handler's measured time
  (``took 0.503 s``) is shown as the page's 0.500 s when it is at least that
  (a busy machine wakes a 0.5 s sleep late);
* ports: the page's 9001 is a free port, and a client's own port is any.

As in `tests.test_errors_silence`, the program's `TimeoutLoopFactory` ends the
node as soon as everything the page shows has been printed.
"""

from __future__ import annotations

import logging
import re
import socket
import threading
import unittest
from pathlib import Path
from typing import Dict, List, NamedTuple, Optional, Sequence, Tuple
from unittest import mock

import tests.test_errors_silence as silence
from snr import AbstractNode, Config, SynchronousRunner
from snr.std_mods import runners as std_runners
from tests.examples_support import ROOT

BOUND_S = silence.BOUND_S
DOCS = Path(ROOT, "docs", "errors.md")
MISSING_S = 0.3  # node.key_hints.missing_s while testing (5 s by default)
LINK_S = 0.2  # node.key_hints.link_s while testing (3 s by default)

# (what the run prints, what the page shows instead): the normalisations above.
AS_ON_THE_PAGE: List[Tuple[str, str]] = [
    (r"has been read for \d+\.\d s", "has been read for 5.0 s"),
    (rf"in the {LINK_S:.1f} s since", "in the 3.0 s since"),
    (r"took (?:0\.[5-9]|[1-9]\.)\d\d s", "took 0.500 s"),
    (r"127\.0\.0\.1:\d+", "127.0.0.1:PORT"),
]


class Run(NamedTuple):
    """One command of an entry: its arguments and what the page shows it print."""

    argv: List[str]  # ["robot.py", "robot"]
    output: List[str]
    status: int


class Entry(NamedTuple):
    label: str  # "2a"
    program: str
    runs: List[Run]  # one per terminal


SECTIONS = [*range(1, 12), 14]  # 12, 13 and 15-18 are run by the tests named on the page


def catalogue() -> Dict[str, Entry]:
    """The entries of sections 1 to 11 and 14 of docs/errors.md, by label."""
    text = DOCS.read_text("utf-8")
    chunks: List[str] = []
    for number in SECTIONS:
        start = text.index(f"\n## {number}. ")
        chunks += text[start : text.index("\n## ", start + 1)].split("\n### ")[1:]
    entries: Dict[str, Entry] = {}
    for chunk in chunks:
        label = chunk.split(".", 1)[0]
        program = chunk.split("```python\n", 1)[1].split("```", 1)[0]
        runs = []
        for block in re.findall(r"```text\n(.*?)```", chunk, re.S):
            shown = block.splitlines()
            command = shown[0].split("$ python ", 1)[1].split()
            status = int(shown[shown.index("$ echo $?") + 1])
            output = shown[1 : shown.index("$ echo $?")]
            runs.append(Run(command, output, status))
        entries[label] = Entry(label, program, runs)
    return entries


def as_on_the_page(line: str) -> Optional[str]:
    """A line of output as compared (see the module's docstring); None if not compared."""
    compared = silence.comparable(line)
    if compared is None:
        return None
    for pattern, shown in AS_ON_THE_PAGE:
        compared = re.sub(pattern, shown, compared)
    return compared.rstrip()


def as_shown(line: str) -> Optional[str]:
    """A line of the page as compared: as `as_on_the_page`, but ``...`` is kept."""
    return "..." if line.strip() == "..." else as_on_the_page(line)


def fragments(line: str) -> List[str]:
    """The parts of a page's line that the run prints exactly (to know when it is done)."""
    varies = [p for pattern, shown in AS_ON_THE_PAGE for p in (pattern, re.escape(shown))]
    parts = re.split("|".join(varies), silence.TIME_STAMP.sub("", line))
    return [part for part in parts if part.strip()]


def matches(shown: List[str], printed: List[str]) -> bool:
    """True if ``printed`` is ``shown`` line by line; a ``...`` on the page stands for any lines."""
    pattern = "".join(r"(?:.*\n)*?" if line == "..." else re.escape(line) + r"\n" for line in shown)
    return re.fullmatch(pattern, "".join(line + "\n" for line in printed)) is not None


def tune(node: AbstractNode) -> None:
    """Cut the node's hint times short (see the module's docstring)."""
    hints = getattr(node, "key_hints", None)
    if hints is not None:
        hints.missing_s = MISSING_S
        hints.link_s = LINK_S
        hints.handlers_s = 3.0  # as the page says; the fast timeout runs the check sooner


class TestCatalogue(unittest.TestCase):
    """Each program of sections 1 to 11 and 14 prints what the page shows."""

    def test_every_entry_of_the_sections_is_here(self) -> None:
        numbers = {int(re.sub(r"\D", "", label)) for label in catalogue()}
        self.assertEqual(numbers, set(SECTIONS))
        self.assertGreaterEqual(len(catalogue()), 25)

    def test_dots_on_the_page_stand_for_any_lines(self) -> None:
        self.assertTrue(matches(["a", "...", "d"], ["a", "b", "c", "d"]))
        self.assertTrue(matches(["a", "...", "d"], ["a", "d"]))
        self.assertFalse(matches(["a", "d"], ["a", "b", "d"]))
        self.assertFalse(matches(["a", "...", "d"], ["a", "b", "d", "e"]))

    def check(self, label: str) -> None:
        entry = catalogue()[label]
        if len(entry.runs) > 1:
            results = run_side_by_side(entry)
        else:
            (run,) = entry.runs
            results = [run_program(entry.program, run)]
        for run, (lines, status) in zip(entry.runs, results):
            shown = [c for c in map(as_shown, run.output) if c is not None]
            printed = [c for c in map(as_on_the_page, lines) if c is not None]
            why = f"{label} ({' '.join(run.argv)}) printed:\n" + "\n".join(lines)
            if not matches(shown, printed):
                self.assertEqual(printed, shown, why)  # shows where they differ
                self.fail(why)
            self.assertEqual(status, run.status, why)


def run_program(program: str, run: Run) -> Tuple[List[str], int]:
    """``run`` of ``program``: the lines it prints and its exit status."""
    wanted = [part for line in run.output for part in fragments(line) if "terminated:" not in line]
    return silence.run_program(program, wanted, run.argv, tune)


def run_side_by_side(entry: Entry) -> List[Tuple[List[str], int]]:
    """Each run of ``entry`` as in terminals side by side; their outputs and statuses.

    The program runs once with every role on its command line, and instead of
    a process per role (`MultiProcRunner`) each role's node runs as its own
    ``python robot.py ROLE`` would (`SynchronousRunner`), in a thread of this
    process, the next starting once the one before has printed its first line.
    The output is split by the node's name in each line (``snr.topside ...``).
    Each node ends once every line the page shows before its "terminated"
    (by the time stamps, of either terminal) has been printed.
    """
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        ports = {"9001": str(probe.getsockname()[1])}
    roles = [run.argv[1] for run in entry.runs]
    lines_shown = [line for run in entry.runs for line in run.output]
    wanted: Dict[str, List[str]] = {}
    for role, run in zip(roles, entry.runs):
        end = next(line[:8] for line in run.output if "terminated:" in line)
        wanted[role] = [
            part.replace("9001", ports["9001"])
            for line in lines_shown
            if "terminated:" not in line and line[:8] < end
            for part in fragments(line)
        ]

    def done(output: str) -> bool:  # asked by each node's timeout loop, on its thread
        role = threading.current_thread().name.split("-")[1]  # "snr-urov-timeout_loop"
        return all(part in output for part in wanted.get(role, []))

    statuses: Dict[str, int] = {}
    program = entry.program.replace("9001", ports["9001"])
    # The "snr.<role>" loggers outlive a node: an earlier test may have left one at WARNING.
    loggers = [logging.getLogger(f"snr.{role}") for role in roles]
    levels = [log.level for log in loggers]
    try:
        for log in loggers:
            log.setLevel(logging.INFO)
        with mock.patch.object(std_runners, "MultiProcRunner", side_by_side(statuses)):
            lines, _ = silence.run_program(program, [], ["robot.py", *roles], tune, done)
    finally:
        for log, level in zip(loggers, levels):
            log.setLevel(level)
    lines = [line.replace(ports["9001"], "9001") for line in lines]
    return [
        (
            [line for line in lines if re.match(rf"(\d\d:\d\d:\d\d )?snr\.{role}\b", line)],
            statuses[role],
        )
        for role in roles
    ]


def side_by_side(statuses: Dict[str, int]) -> type:
    """A stand-in for `MultiProcRunner` that runs each role's node in a thread (see above)."""

    class SideBySide:
        def __init__(self, roles: Sequence[str], config: Config) -> None:
            self.roles, self.config = list(roles), config

        def run(self) -> None:
            threads = [threading.Thread(target=self.run_role, args=(r,)) for r in self.roles]
            for role, thread in zip(self.roles, threads):
                started = threading.Event()
                first_line = FirstLine(started)
                logging.getLogger(f"snr.{role}").addHandler(first_line)
                thread.start()
                started.wait(BOUND_S)
                logging.getLogger(f"snr.{role}").removeHandler(first_line)
            for thread in threads:
                thread.join(2 * BOUND_S)

        def run_role(self, role: str) -> None:
            try:
                SynchronousRunner(role, self.config).run()
                statuses[role] = 0
            except SystemExit as end:
                statuses[role] = end.code if isinstance(end.code, int) else 1

    return SideBySide


class FirstLine(logging.Handler):
    """Sets ``event`` when a record is logged."""

    def __init__(self, event: threading.Event) -> None:
        super().__init__()
        self.event = event

    def emit(self, record: logging.LogRecord) -> None:
        self.event.set()


silence.add_entry_tests(TestCatalogue, catalogue())


if __name__ == "__main__":
    unittest.main()
