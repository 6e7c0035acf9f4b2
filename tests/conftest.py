"""pytest only (``python -m unittest`` never reads this file): run the whole suite in parallel.

Most of the suite's time is waiting (for a child process, a socket, a
node's loop), so with pytest-xdist installed (the ``dev`` extra) a plain
``python -m pytest`` runs the tests on `WORKERS` processes. Naming a file or
a test (``python -m pytest tests/test_node.py``) runs it in this process, as
does ``-n 0``; without pytest-xdist everything runs in this process.
"""

from __future__ import annotations

import os

import pytest

WORKERS = 3
"""Processes for a whole-suite run: one more than the 2 cores of the machines we
test on, since a worker is often waiting rather than computing."""


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
