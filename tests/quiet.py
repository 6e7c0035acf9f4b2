"""Keeping a passing test silent: its log lines are captured, not printed.

A test that makes SNR warn on purpose wraps that code in ``assertLogs`` and
checks the line: the test gets stronger and the run stays quiet. Where a line
may or may not come (it depends on timing, e.g. a summary of repeats at
shutdown), or a node in DEBUG mode logs its INFO lines, `captured_logs` keeps
them without demanding any::

    with captured_logs("snr.robot") as lines:
        run_the_node()
    self.assertLessEqual(len(lines), 3, lines)

or, for a whole test (e.g. one that runs a DEBUG node to check something else),
``capture_test_logs(self)`` as its first line.

A node's handlers slower than 0.1 s are reported (`Node.slow_handler_s`). The
suite's handlers are quick, but on a busy machine a handler may wait that long for
the CPU, and a reload waits for the old loop's thread: the nodes of such tests
set `SLOW_HANDLER_S` (``node.slow_handler_s = SLOW_HANDLER_S``, or the component
`SlowHandlerLimitFactory` where a runner builds the node), so a line comes only
when a handler really held its node up.
"""

from __future__ import annotations

import contextlib
import logging
import unittest
from typing import Dict, Iterator, List, Optional

from snr import AbstractNode, Endpoint, EndpointFactory, Node

__all__ = ["SLOW_HANDLER_S", "SlowHandlerLimitFactory", "capture_test_logs", "captured_logs"]

SLOW_HANDLER_S = 1.0
"""The slow-handler threshold of the suite's nodes that run quick handlers on a busy machine."""


class _Keep(logging.Handler):
    def __init__(self, lines: List[str]) -> None:
        super().__init__()
        self.lines = lines

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(f"{record.levelname}:{record.name}:{record.getMessage()}")


def _levels_under(name: str) -> Dict[str, int]:
    loggers = logging.Logger.manager.loggerDict
    return {
        other: logger.level
        for other, logger in loggers.items()
        if isinstance(logger, logging.Logger) and (other == name or other.startswith(name + "."))
    }


@contextlib.contextmanager
def captured_logs(name: str = "snr", level: Optional[int] = None) -> Iterator[List[str]]:
    """What logger ``name`` and its children log meanwhile, kept in a list (none is fine).

    The lines look like ``assertLogs`` output: ``"WARNING:snr.robot:Turned away ..."``.
    With ``level``, the logger is set to it meanwhile. Afterwards every level under
    ``name`` is as it was: a node sets its logger's level from its mode the first
    time its role is used, and a DEBUG node must not leave the next test's TEST
    node of the same role logging INFO lines.

    It replaces the handlers of ``name`` while it lasts: start it before any
    ``assertLogs`` on the same logger (first thing in the test, or in setUp).
    """
    logger = logging.getLogger(name)
    lines: List[str] = []
    levels = _levels_under(name)
    saved = logger.handlers[:], logger.propagate
    logger.handlers, logger.propagate = [_Keep(lines)], False
    if level is not None:
        logger.setLevel(level)
    try:
        yield lines
    finally:
        logger.handlers, logger.propagate = saved
        for other, now in _levels_under(name).items():
            if now != levels.get(other, logging.NOTSET):
                logging.getLogger(other).setLevel(levels.get(other, logging.NOTSET))


def capture_test_logs(test: unittest.TestCase, name: str = "snr") -> List[str]:
    """`captured_logs` from now until ``test`` ends; returns the list of lines.

    Example::

        def test_the_profiler_counts(self) -> None:
            capture_test_logs(self)  # the DEBUG node's INFO lines stay out of the run's output
            node = Node("test", self.get_config([...], Mode.DEBUG))
    """
    capture = captured_logs(name)
    lines = capture.__enter__()
    test.addCleanup(capture.__exit__, None, None, None)
    return lines


class SlowHandlerLimitFactory(EndpointFactory):
    """A component that sets its node's `Node.slow_handler_s` (for a node a runner builds).

    Example::

        components = [robot, brain, TimeoutLoopFactory(seconds=5), SlowHandlerLimitFactory()]
        TestRunner("sim", Config({"sim": components}, mode=Mode.TEST), 30.0).run()
    """

    def __init__(self, seconds: float = SLOW_HANDLER_S) -> None:
        super().__init__()
        self.seconds = seconds

    def get(self, parent: AbstractNode) -> Endpoint:
        assert isinstance(parent, Node), parent
        parent.slow_handler_s = self.seconds
        return Endpoint(self, parent, "slow_handler_limit")
