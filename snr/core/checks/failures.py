"""What a node does with a failed handler or loop: says it, and stops (unless DEPLOYED).

`snr.core.dispatch.HandlerRunner` hands each failure to the node's `FailureReport`,
in the words of `snr.core.checks.explain`; DEPLOYED logs it (repeats counted) and runs on.

Example::

    failures = FailureReport("robot", Mode.DEBUG, node.log, node.set_terminate_flag)
    failures.handler_failed(handler, task, component, error)
    failures.failure      # the HandlerError that stopped the node
"""

from __future__ import annotations

import logging
from typing import Any, Callable, Hashable, Optional, Set

from snr.core.checks.explain import (
    bad_result_error,
    handler_failure,
    loop_failure,
    slow_handler_text,
)
from snr.core.checks.repeats import RepeatFilter
from snr.prelude.abstract import AbstractComponent, AbstractLoop
from snr.prelude.errors import SNRError
from snr.prelude.names import Mode, TaskHandler
from snr.prelude.task import Task

__all__ = ["FailureReport"]


class FailureReport:
    """Logs a node's failures in words; outside DEPLOYED mode the first one stops the node.

    Args:
        role: the node's role, for messages.
        mode: DEBUG/TEST stop the node on the first failure; DEPLOYED logs.
        log: the node's logger.
        stop: called with a reason to stop the node (``Node.set_terminate_flag``).

    Example::

        report = FailureReport("robot", Mode.TEST, log, node.set_terminate_flag)
        report.bad_result(5, handler, task)   # "Task handler ... returned 5 ..."

    Attributes:
        failure: the first error that stopped the node (DEBUG/TEST), or None.
        repeats: the `RepeatFilter` that keeps repeated failures from flooding the log.
    """

    def __init__(
        self, role: str, mode: Mode, log: logging.Logger, stop: Callable[[str], None]
    ) -> None:
        self.role = role
        self.mode = mode
        self.log = log
        self.stop = stop
        self.failure: Optional[SNRError] = None
        self.repeats = RepeatFilter(log)
        self._slow_reported: Set[Any] = set()

    def handler_failed(
        self,
        handler: TaskHandler,
        task: Task,
        component: Optional[AbstractComponent],
        error: Exception,
        run_size: int = 1,
    ) -> None:
        """Report ``error`` raised by ``handler`` (``run_size``: a burst's tasks, ``task`` first).

        Example::

            report.handler_failed(motor.forward, task, motor, ZeroDivisionError("x"))
        """
        deployed = self.mode is Mode.DEPLOYED
        failure = handler_failure(handler, task, component, error, deployed, run_size)
        self.record(failure, (getattr(handler, "__func__", handler), type(error)))

    def bad_result(self, result: Any, handler: TaskHandler, task: Task) -> None:
        """Report a handler that returned ``result``, which is not a task or list of tasks.

        Example::

            report.bad_result(5, motor.forward, task)
        """
        self.record(bad_result_error(result, handler, task), getattr(handler, "__func__", handler))

    def loop_failed(self, loop: AbstractLoop, error: BaseException) -> None:
        """Report a loop's thread ending with ``error``; ``sys.exit()`` or Ctrl-C stops the node.

        Example::

            report.loop_failed(sonar_loop, OSError("device gone"))
        """
        failure = loop_failure(loop, error, self.mode is Mode.DEPLOYED)
        if isinstance(error, (SystemExit, KeyboardInterrupt)):
            self.log.warning("%s The node stops.", failure)
            what = "sys.exit()" if isinstance(error, SystemExit) else "Ctrl-C"
            self.stop(f"{what} in loop {loop.name!r}")
            return
        self.record(failure, (id(loop), type(error)))

    def record(self, error: SNRError, key: Hashable) -> None:
        """Log ``error``; outside DEPLOYED mode the first one also stops the node.

        Example::

            report.record(HandlerError("..."), "my key")
        """
        if self.mode is Mode.DEPLOYED:
            text = str(error)
            if "The node keeps running" not in text:
                text += " The node keeps running."
            first_line = text.split("\n", 1)[0]
            self.repeats.report(key, first_line, logging.ERROR, "%s", text)
            return
        if self.failure is None:
            # loop() raises it once the node has stopped: one line now, not a copy.
            self.failure = error
            first_sentence = str(error).split("\n", 1)[0].split(". ", 1)[0].rstrip(".")
            self.log.error("Stopping node %r: %s.", self.role, first_sentence)
        else:
            self.log.error("%s", error)
        self.stop(f"stopped by a {type(error).__name__}")

    def report_slow(self, handler: TaskHandler, task: Task, took_s: float) -> None:
        """Warn once per handler that it held the node's thread for ``took_s`` (SNR's: debug).

        Example::

            report.report_slow(planner.plan, task, 0.4)   # "Task handler ... took 0.400 s"
        """
        func = getattr(handler, "__func__", handler)  # one key for every instance's handler
        if self.mode is Mode.DEPLOYED or func in self._slow_reported:
            return
        self._slow_reported.add(func)
        # SNR's own (a reload waiting for a goodbye): the advice is not the student's.
        ours = getattr(func, "__module__", "").startswith("snr.")
        self.log.log(
            logging.DEBUG if ours else logging.WARNING,
            "%s",
            slow_handler_text(handler, task, took_s),
        )
