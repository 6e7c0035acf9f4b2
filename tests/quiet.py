"""Keeping a passing test silent: its log lines are captured, not printed.

A test that makes SNR warn on purpose wraps that code in ``assertLogs`` and
checks the line: the test gets stronger and the run stays quiet. Where a line
may or may not come (it depends on timing, e.g. a summary of repeats at
shutdown), `captured_logs` keeps it without demanding it::

    with captured_logs("snr.robot") as lines:
        run_the_node()
    self.assertLessEqual(len(lines), 3, lines)
"""

from __future__ import annotations

import contextlib
import logging
from typing import Iterator, List

__all__ = ["captured_logs"]


class _Keep(logging.Handler):
    def __init__(self, lines: List[str]) -> None:
        super().__init__()
        self.lines = lines

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(f"{record.levelname}:{record.name}:{record.getMessage()}")


@contextlib.contextmanager
def captured_logs(name: str = "snr") -> Iterator[List[str]]:
    """What logger ``name`` and its children log meanwhile, kept in a list (none is fine).

    The lines look like ``assertLogs`` output: ``"WARNING:snr.robot:Turned away ..."``.
    Levels are left as they are: only what would have been printed is kept.
    """
    logger = logging.getLogger(name)
    lines: List[str] = []
    saved = logger.handlers[:], logger.propagate
    logger.handlers, logger.propagate = [_Keep(lines)], False
    try:
        yield lines
    finally:
        logger.handlers, logger.propagate = saved
