"""What a node does with a failed handler or loop: says it, and stops (unless DEPLOYED).

`snr.core.dispatch.HandlerRunner` hands each failure to the node's `FailureReport`,
which words it (what ran, on which task, the student's frames, the fix); DEPLOYED logs
it (repeats counted) and runs on.

Example::

    failures = FailureReport("robot", Mode.DEBUG, node.log, node.set_terminate_flag)
    failures.handler_failed(handler, task, component, error)
    failures.failure      # the HandlerError that stopped the node
"""

from __future__ import annotations

import inspect
import logging
from typing import Any, Callable, Hashable, Optional, Set

from snr.core.checks.error_text import exception_text, short_repr
from snr.core.checks.explain import page_hint, returning_lines
from snr.core.checks.repeats import RepeatFilter
from snr.core.checks.student_code import (
    code_name,
    code_of,
    describe_callable,
    describe_class,
    failure_frames,
    short_path,
    source_block,
)
from snr.prelude.abstract import AbstractComponent, AbstractLoop
from snr.prelude.errors import HandlerError, LoopError, SNRError
from snr.prelude.names import Mode
from snr.prelude.page import Page
from snr.prelude.task import Task, TaskHandler, format_task

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
            # Task handler Motor.forward (robot.py:30) of endpoint 'motor' raised ...
        """
        where = ""
        if component is not None:
            kind = "loop" if isinstance(component, AbstractLoop) else "endpoint"
            where = f" of {kind} {component.name!r}"
        handling = f"the task {format_task(task, values='none')}"
        if run_size > 1:
            handling = f"a run of {run_size} tasks given to it at once, the first being {handling}"
        values: object = task.val_list  # a task built by hand may hold anything
        if isinstance(values, list) and len(values) == 1 and isinstance(values[0], Page):
            carrying = (
                f"carrying the page {values[0].key!r} with data {short_repr(values[0].data, 200)}"
            )
        else:
            carrying = f"with values {short_repr(values, 200)}"
        if not isinstance(values, list):
            carrying += (
                f". Its val_list is {short_repr(values, 60)} ({type(values).__name__}), not a "
                "list: whoever built the task must pass the values in a list, e.g. "
                f"Task(TaskType.{task.type.name}, {task.name!r}, [value])"
            )
        fix = self._fix(
            error,
            "handler",
            "",
            "Fix the handler, or catch the error in it if it can happen in normal use "
            "(in Mode.DEPLOYED the node logs it and keeps running).",
        )
        failure = HandlerError(
            f"Task handler {describe_callable(handler)}{where} raised "
            f"{page_hint(error, exception_text(error))}\nwhile handling {handling} {carrying}."
            f"{failure_frames(error)}\n{fix}"
        )
        failure.__cause__ = error
        self.record(failure, (getattr(handler, "__func__", handler), type(error)))

    def bad_result(self, result: Any, handler: TaskHandler, task: Task) -> None:
        """Report a handler that returned ``result``, which is not a task or list of tasks.

        The error points at the ``return`` that gave it (each that may have, if unsure).

        Example::

            report.bad_result(42, doubler.double, task)
            # Task handler Doubler.double returned 42 (int) at robot.py:12 while handling ...
            #   File "/home/student/rov/robot.py", line 12, in Doubler.double (defined at line 11)
            #     return task.val_list[0].data * 2
        """
        fix = (
            f"A handler must return a Task, a list of Tasks, or None.{_bad_result_hint(result)} "
            "To store a value, return self.store_data_task(key, value); to announce "
            "something, return tasks.event('name', [value])."
        )
        returned = f"returned {short_repr(result)} ({type(result).__name__})"
        if isinstance(result, list):
            index, bad = next((i, t) for i, t in enumerate(result) if not isinstance(t, Task))
            returned = (
                f"returned a list whose item {index} is {short_repr(bad)} ({type(bad).__name__}),"
                " not a Task,"
            )
        handling = f"while handling {format_task(task, values='none')}"
        code, lines = code_of(handler), returning_lines(handler, result)
        if code is None or not lines:
            text = f"Task handler {describe_callable(handler)} {returned} {handling}. {fix}"
        else:
            name = code_name(code, getattr(handler, "__qualname__", code.co_name))
            short = short_path(code.co_filename)
            at = f"at {short}:{lines[0]}"
            if len(lines) > 1:  # the source cannot tell which: show each
                at = f"at one of its returns, {short}:{', '.join(str(n) for n in lines)},"
            context = f" (defined at line {code.co_firstlineno})"
            blocks = "\n".join(source_block(code.co_filename, n, name, context) for n in lines)
            text = f"Task handler {name} {returned} {at} {handling}.\n{blocks}\n{fix}"
        self.record(HandlerError(text), getattr(handler, "__func__", handler))

    def loop_failed(self, loop: AbstractLoop, error: BaseException) -> None:
        """Report a loop's thread ending with ``error``; ``sys.exit()`` or Ctrl-C stops the node.

        Example::

            report.loop_failed(sonar_loop, OSError("device gone"))
        """
        what = page_hint(error, exception_text(error), in_a_loop=True)
        if isinstance(error, SystemExit):
            what = f"sys.exit({'' if error.code is None else repr(error.code)})"
            fix = (
                "sys.exit() in a loop ends only the loop's thread, not the program. To stop "
                "this loop, call self.set_terminate_flag('why'); to stop the node, "
                "self.schedule(tasks.terminate('why'))."
            )
        elif isinstance(error, KeyboardInterrupt):
            fix = "Ctrl-C stops the whole node; a loop need not catch or raise it."
        else:
            fix = self._fix(
                error,
                "loop",
                " without this loop",
                "Fix loop() (or setup()), or catch the error there if it can happen in "
                "normal use (in Mode.DEPLOYED the node keeps running without the loop).",
            )
        failure = LoopError(
            f"Loop {loop.name!r} ({describe_class(type(loop))}) stopped: it raised {what}"
            f"{failure_frames(error)}\n{fix}"
        )
        failure.__cause__ = error
        if isinstance(error, (SystemExit, KeyboardInterrupt)):
            self.log.warning("%s The node stops.", failure)
            what = "sys.exit()" if isinstance(error, SystemExit) else "Ctrl-C"
            self.stop(f"{what} in loop {loop.name!r}")
            return
        self.record(failure, (id(loop), type(error)))

    def _fix(self, error: BaseException, what: str, kept: str, fix: str) -> str:
        """The last line of a failure: the node goes on (DEPLOYED), or how to fix ``what``."""
        if self.mode is Mode.DEPLOYED:
            return f"The node keeps running{kept}."
        if isinstance(error, SNRError):
            return f"Fix the {what} as the message above says."
        return fix

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
            "Task handler %s took %.3f s handling %s. While it runs the node can run no other "
            "task. Move slow or blocking work (time.sleep, waiting for a device) into a "
            "ThreadLoop, and let the handler only read and store data.",
            describe_callable(handler),
            took_s,
            format_task(task, values="none"),
        )


def _bad_result_hint(result: Any) -> str:
    """A hint for the likely slip behind a bad return value (or "")."""
    items = result if isinstance(result, (list, tuple)) else []
    if isinstance(result, tuple) and all(isinstance(t, Task) for t in items):
        return " Return a list, [task1, task2], not a tuple."
    if isinstance(result, Page):
        return " To store a page, return tasks.store_page(page)."
    if isinstance(result, bool):
        return " Return None when there is nothing to do."
    if inspect.isgenerator(result):
        return " A handler cannot yield its tasks: return them in a list."
    if any(t is None for t in items):
        return " Leave None out of the list."
    if any(isinstance(t, (list, tuple)) for t in items):
        return " Return one flat list of Tasks (join lists with + or extend)."
    return ""
