"""Pointing at the student's code, not SNR's: where a class, function or call is.

Every SNR message names the student's file and line. This module is the one
place that works them out: from a class or function (`describe_class`,
`describe_callable`, `def_block`), from a traceback (`student_frames`,
`trim_runtime_frames`), from the call in progress (`caller_location`,
`caller_block`) and from another thread (`running_line`).
Frames of SNR's runtime (``snr/core``, ``snr/prelude``) are plumbing the
student did not write, so they are skipped.

Example::

    describe_class(DepthSensor)      # 'DepthSensor (robot.py:3)'
    caller_location()                # 'robot.py:42 in Rogue.loop'
    print(def_block(Doubler.double))
    #   File "/home/student/rov/robot.py", line 11, in Doubler.double
    #     def double(self, task: Task, key: TaskId) -> SomeTasks:
"""

from __future__ import annotations

import ast
import inspect
import linecache
import os
import sys
import threading
import traceback
from types import CodeType, FrameType, TracebackType
from typing import Any, Optional

__all__ = [
    "caller_block",
    "caller_location",
    "code_name",
    "def_block",
    "describe_callable",
    "describe_class",
    "frame_location",
    "is_runtime_file",
    "line_with_code",
    "outside_runtime",
    "parse_source",
    "running_line",
    "short_path",
    "source_block",
    "student_frames",
    "trim_runtime_frames",
]

_SNR_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_RUNTIME_DIRS = tuple(os.path.join(_SNR_DIR, sub) + os.sep for sub in ("core", "prelude"))


def short_path(path: Optional[str]) -> str:
    """``path`` as messages show it: relative to the current folder when that is shorter.

    Example::

        short_path("/home/student/rov/robot.py")   # 'robot.py' when run in /home/student/rov
    """
    if not path:
        return "<unknown file>"
    try:
        rel = os.path.relpath(path)
    except ValueError:  # different drive on Windows
        return path
    return rel if not rel.startswith(".." + os.sep + "..") else path


def code_name(code: CodeType, fallback: str) -> str:
    """``"Doubler.double"``: the qualified name of ``code``, or ``fallback`` before Python 3.11.

    Example::

        code_name(Doubler.double.__code__, Doubler.double.__qualname__)   # 'Doubler.double'
    """
    return getattr(code, "co_qualname", None) or fallback


def describe_class(cls: type) -> str:
    """``"MyEndpoint (robot.py:12)"``: a class with where it is defined.

    Example::

        describe_class(MovingAvgEndpoint)  # 'MovingAvgEndpoint (filters.py:40)'
    """
    if cls.__module__.split(".", 1)[0] == "snr":
        return f"{cls.__qualname__} (part of SNR)"  # not the student's file: no path
    try:
        path = inspect.getsourcefile(cls)
        line = inspect.getsourcelines(cls)[1]
        return f"{cls.__qualname__} ({short_path(path)}:{line})"
    except (TypeError, OSError):
        return cls.__qualname__


def describe_callable(func: Any) -> str:
    """``"MyEndpoint.on_depth (robot.py:30)"``: a function with where it is.

    Example::

        describe_callable(endpoint.update_filter)
    """
    target = getattr(func, "__func__", func)
    name = getattr(target, "__qualname__", None) or repr(func)
    code = getattr(target, "__code__", None)
    if code is None:
        return str(name)
    return f"{name} ({short_path(code.co_filename)}:{code.co_firstlineno})"


def is_runtime_file(filename: str) -> bool:
    """True for files of SNR's runtime (``snr/core``, ``snr/prelude``).

    Frames from these files are framework plumbing: the student did not write
    them, so reports skip them. ``snr/std_mods`` is component code and stays.

    Example::

        is_runtime_file(snr.core.node.__file__)   # True
    """
    return filename.startswith(_RUNTIME_DIRS)


def outside_runtime(frame: Optional[FrameType]) -> Optional[FrameType]:
    """``frame`` or the nearest frame that called it from outside SNR's runtime, or None.

    Example::

        outside_runtime(sys._getframe(1))   # the student's frame that called into SNR
    """
    while frame is not None and is_runtime_file(frame.f_code.co_filename):
        frame = frame.f_back
    return frame


def student_frames(tb: Optional[TracebackType]) -> str:
    """A traceback as text, with the frames of SNR's runtime left out.

    Example::

        except Exception as error:
            print(student_frames(error.__traceback__))
            #   File "robot.py", line 30, in on_depth
            #     return 1 / 0
    """
    frames = traceback.extract_tb(tb)
    theirs = traceback.StackSummary.from_list(
        [f for f in frames if not is_runtime_file(f.filename)]
    )
    if not theirs:  # nothing but SNR: show it all (a bug in SNR itself)
        theirs = frames
    return "".join(theirs.format()).rstrip()


def trim_runtime_frames(error: BaseException) -> None:
    """Drop SNR's leading frames from ``error``'s traceback, in place.

    Python's own report of the error (e.g. as the cause of a HandlerError)
    then starts at the student's code.

    Example::

        trim_runtime_frames(error)
        raise HandlerError("...") from error
    """
    tb = error.__traceback__
    while tb is not None and is_runtime_file(tb.tb_frame.f_code.co_filename):
        tb = tb.tb_next
    if tb is not None:
        error.__traceback__ = tb


def frame_location(frame: FrameType, line: Optional[int] = None) -> str:
    """``"robot.py:12 in MyFactory.get"``: where a frame is (at ``line``, or now).

    Example::

        frame_location(sys._getframe())
    """
    at = frame.f_lineno if line is None else line
    return f"{short_path(frame.f_code.co_filename)}:{at} in {_frame_name(frame)}"


def _frame_name(frame: FrameType) -> str:
    """``"MyFactory.get"``: the qualified name of the function a frame runs."""
    code = frame.f_code
    name: Optional[str] = getattr(code, "co_qualname", None)  # Python 3.11+
    if name is None:
        # Older Pythons know only the function's name: add the class of
        # `self` (or `cls`) when the frame has one, as co_qualname would.
        owner = frame.f_locals.get("self", frame.f_locals.get("cls"))
        owner_class = owner if isinstance(owner, type) else type(owner)
        name = code.co_name
        if owner is not None and code.co_name in vars(owner_class):
            name = f"{owner_class.__qualname__}.{code.co_name}"
    return name


def caller_location(skip: int = 1) -> str:
    """``"robot.py:42 in Rogue.loop"``: the nearest caller outside SNR's runtime.

    Example::

        raise ThreadSafetyError(f"... called from {caller_location()} ...")
    """
    frame = outside_runtime(sys._getframe(skip))
    return "<unknown place>" if frame is None else frame_location(frame)


def source_block(filename: str, line: int, name: str, context: str = "") -> str:
    """One line of code as a traceback shows it: where, then the code itself.

    Editors and terminals make the ``File "...", line N`` part clickable, so
    it takes the student straight to the line to fix. ``context`` follows the
    name, e.g. ``" (defined at line 11)"``.

    Example::

        source_block("/home/student/rov/robot.py", 12, "Doubler.double", " (defined at line 11)")
        #   File "/home/student/rov/robot.py", line 12, in Doubler.double (defined at line 11)
        #     return task.val_list[0].data * 2
    """
    code = linecache.getline(filename, line).strip()
    where = f'  File "{filename}", line {line}, in {name}{context}'
    return f"{where}\n    {code}" if code else where


def def_block(func: Any) -> str:
    """The ``def`` line of ``func`` as a `source_block`, or "" when it has no code.

    For mistakes in how a function is written (its parameters, a missing
    ``super().__init__``): the ``def`` is the line to change.

    Example::

        def_block(DepthPrinter.on_depth)
        #   File "/home/student/rov/robot.py", line 8, in DepthPrinter.on_depth
        #     def on_depth(self, task: Task) -> SomeTasks:
    """
    target = getattr(func, "__func__", func)
    code = getattr(target, "__code__", None)
    if code is None:
        return ""
    name = code_name(code, getattr(target, "__qualname__", code.co_name))
    return source_block(code.co_filename, code.co_firstlineno, name)


def caller_block(skip: int = 1) -> str:
    """The nearest caller outside SNR's runtime as a `source_block`, or "".

    For errors found inside SNR on behalf of the line that called it, such
    as a ``self.task_handlers = ...`` that runs before ``super().__init__``.

    Example::

        raise ComponentError(f"... set too early.\n{caller_block()}")
    """
    frame = outside_runtime(sys._getframe(skip))
    if frame is None:
        return ""
    return source_block(frame.f_code.co_filename, frame.f_lineno, _frame_name(frame))


def running_line(thread_id: Optional[int]) -> str:
    """``sensor.py:12 in Sonar.loop: `reading = port.read()```: where a thread is now.

    The innermost frame outside SNR and the standard library is shown (a
    loop blocked in ``socket.recv`` is shown at the student's line that
    called it); "" when the thread is not running.

    Example::

        running_line(loop.thread_id)   # "sensor.py:12 in Sonar.loop: `reading = port.read()`"
    """
    if thread_id is None:
        return ""
    frame: Optional[FrameType] = sys._current_frames().get(thread_id)
    innermost = frame
    while frame is not None and (
        is_runtime_file(frame.f_code.co_filename) or _is_stdlib(frame.f_code.co_filename)
    ):
        frame = frame.f_back
    frame = frame or innermost
    return "" if frame is None else line_with_code(frame)


def line_with_code(frame: FrameType, line: Optional[int] = None) -> str:
    """``sensor.py:12 in Sonar.loop: `reading = port.read()```: a frame's place and code.

    At ``line``, or where the frame is now; the code is left out when the
    source cannot be read.

    Example::

        line_with_code(sys._getframe())   # "robot.py:30 in Depth.loop: `x = line_with_code(...)`"
    """
    at = frame.f_lineno if line is None else line
    code = linecache.getline(frame.f_code.co_filename, at).strip()
    return frame_location(frame, at) + (f": `{code}`" if code else "")


def _is_stdlib(filename: str) -> bool:
    prefixes = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}
    return filename.startswith("<") or any(
        filename.startswith(f"{prefix}/lib/python") for prefix in prefixes
    )


_PARSE_LOCK = threading.Lock()


def parse_source(text: str) -> ast.Module:
    """``ast.parse(text)``, one thread at a time.

    SNR reads a student's source to explain a mistake (a class's checks, a
    failure, the watchdog, the graph), and two nodes in one process may do it
    at the same moment. On CPython 3.11.7 two parses at once can fail with
    ``SystemError: AST constructor recursion depth mismatch`` (the AST
    constructor's recursion count is not kept per thread there).

    Example::

        parse_source("x = 1").body[0]   # an ast.Assign
    """
    with _PARSE_LOCK:
        return ast.parse(text)
