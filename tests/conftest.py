"""pytest only (``python -m unittest`` never reads this file): run the whole suite in parallel.

Most of the suite's time is waiting (for a child process, a socket, a
node's loop), so with pytest-xdist installed (the ``dev`` extra) a plain
``python -m pytest`` runs the tests on `WORKERS` processes. Naming a file or
a test (``python -m pytest tests/test_node.py``) runs it in this process, as
does ``-n 0``; without pytest-xdist everything runs in this process.

Workers take whole files, slowest first (by the times of the last run, kept
in pytest's cache), so no long file starts near the end while the other
workers run out of work.
"""

from __future__ import annotations

import compileall
import math
import os
from collections import Counter, defaultdict
from typing import DefaultDict, Dict, List

import pytest

WORKERS = 4
"""Processes for a whole-suite run: two for each of the 2 cores of the machines we
test on, since a worker is mostly waiting rather than computing (a fifth saves
little: the suite's CPU time then keeps both cores busy)."""


def _names_tests(config: pytest.Config) -> bool:
    """Whether the command line named files, folders or tests to run."""
    return any(
        not arg.startswith("-") and os.path.exists(arg.split("::")[0])
        for arg in config.invocation_params.args
    )


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config: pytest.Config) -> None:
    """Ask pytest-xdist for `WORKERS` processes, unless told otherwise (before it reads ``-n``)."""
    if not config.pluginmanager.hasplugin("xdist"):
        return
    if hasattr(config, "workerinput") or "PYTEST_XDIST_WORKER" in os.environ:
        return  # a worker (where xdist sets -n to None): it must not start workers of its own
    if getattr(config.option, "numprocesses", 0) is not None:
        return  # -n given on the command line, or set by another plugin
    if _names_tests(config) or config.option.collectonly or config.option.usepdb:
        return
    config.option.numprocesses = WORKERS
    if config.option.dist == "no":
        # A file's tests stay on one worker, so its setUpModule and a class's
        # setUpClass (a docs build, started programs) run once, not once on
        # every worker that runs a part of the file.
        config.option.dist = "loadfile"
        config.option.loadscopereorder = False  # the order is `pytest_collection_modifyitems`'s


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def pytest_sessionstart(session: pytest.Session) -> None:
    """In the process that starts xdist's workers: compile SNR and the tests to bytecode once.

    Where ``PYTHONDONTWRITEBYTECODE`` is set (as on our CI machines), no
    interpreter keeps what it compiled, so each worker and each of the
    example scripts the tests start (about 60) would compile SNR again:
    over a third of the suite's CPU time. Bytecode written here is read by
    all of them (the variable only stops writing). Python checks each file's
    time and size against its source on import, so an edited file is never
    run from old bytecode.
    """
    config = session.config
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    for folder in ("snr", "tests", "examples"):
        compileall.compile_dir(os.path.join(ROOT, folder), quiet=2, workers=1)


SLOWEST_FILES = (
    "tests/test_lesson_assignments.py",
    "tests/test_lesson_command.py",
    "tests/test_comms_zenoh_trust.py",
    "tests/test_comms_zenoh.py",
    "tests/test_errors_rules.py",
    "tests/test_comms_interop.py",
    "tests/test_console_zenoh.py",
    "tests/test_bench_smoke.py",
    "tests/test_examples_tutorial.py",
    "tests/test_comms_sockets.py",
    "tests/test_docs.py",
    "tests/test_example_controller.py",
    "tests/test_lesson_scan.py",
    "tests/test_errors_silence.py",
    "tests/test_codec.py",
    "tests/test_errors.py",
)
"""The files that took longest in a whole-suite run, slowest first. Without pytest's cache
(a fresh checkout, CI, ``-p no:cacheprovider``) they go first, so that none of them starts
last and keeps one worker busy after the others are done; the order need not be exact."""

SECONDS_KEY = "snr/seconds_per_file"
"""pytest's cache entry: each test file's seconds (setup, call, teardown) in the last run."""

_seconds: DefaultDict[str, float] = defaultdict(float)


def _file_of(nodeid: str) -> str:
    return nodeid.split("::", 1)[0]


def pytest_collection_modifyitems(config: pytest.Config, items: List[pytest.Item]) -> None:
    """In an xdist worker: the files slowest first (by the cache; else `SLOWEST_FILES`, then
    the most tests first).

    xdist hands out files in the order its workers collected them; every
    worker reads the same cache, so they all agree on it. A file the cache
    does not know yet goes first.
    """
    if not hasattr(config, "workerinput"):
        return
    cache = getattr(config, "cache", None)  # None with -p no:cacheprovider
    known: Dict[str, float] = cache.get(SECONDS_KEY, {}) if cache is not None else {}
    tests = Counter(_file_of(item.nodeid) for item in items)
    if known:
        items.sort(key=lambda item: -known.get(_file_of(item.nodeid), math.inf))
    else:
        rank = {name: n for n, name in enumerate(SLOWEST_FILES)}
        items.sort(
            key=lambda item: (
                rank.get(_file_of(item.nodeid), len(rank)),
                -tests[_file_of(item.nodeid)],
            )
        )


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    _seconds[_file_of(report.nodeid)] += report.duration


def pytest_sessionfinish(session: pytest.Session) -> None:
    """In the process that ran xdist's workers: keep each file's seconds for the next run."""
    config = session.config
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    cache = getattr(config, "cache", None)
    if cache is not None and _seconds:
        known: Dict[str, float] = cache.get(SECONDS_KEY, {})
        known.update({name: round(seconds, 3) for name, seconds in _seconds.items()})
        cache.set(SECONDS_KEY, known)
