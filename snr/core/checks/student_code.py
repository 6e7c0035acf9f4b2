"""Source lines and tracebacks for messages: the rest of `snr.prelude.student_code`.

Where a function is (`describe_callable`, `def_block`), a traceback without
SNR's runtime (`student_frames`, `trim_runtime_frames`), the call in progress
as a traceback shows it (`caller_block`) and where another thread is
(`running_line`). The helpers the prelude needs itself (`describe_class`,
`caller_location`, `frame_location`...) are in `snr.prelude.student_code` and
named here too, so a check imports all of them from one place.

Example::

    print(def_block(Doubler.double))
    #   File "/home/student/rov/robot.py", line 11, in Doubler.double
    #     def double(self, task: Task, key: TaskId) -> SomeTasks:
"""

from __future__ import annotations

import ast
import linecache
import sys
import threading
import traceback
from types import CodeType, FrameType, TracebackType
from typing import Any, Iterator, Optional

from snr.prelude.student_code import (
    caller_location,
    describe_class,
    frame_location,
    frame_name,
    is_runtime_file,
    outside_runtime,
    short_path,
)

__all__ = [
    "caller_block",
    "caller_location",
    "code_name",
    "code_of",
    "def_block",
    "describe_callable",
    "describe_class",
    "frame_location",
    "is_runtime_file",
    "is_snr",
    "line_with_code",
    "outside_runtime",
    "parse_source",
    "running_line",
    "short_path",
    "source_block",
    "student_frames",
    "trim_runtime_frames",
    "walk_own",
]


def is_snr(cls: type) -> bool:
    """True for a class of SNR's own (any module under ``snr``), which checks skip.

    Example::

        is_snr(snr.Endpoint)   # True; is_snr(MyEndpoint) is False
    """
    return cls.__module__.split(".", 1)[0] == "snr"


def code_of(func: Any) -> Optional[CodeType]:
    """The code of a function or bound method, or None (a builtin, a callable object).

    Example::

        code_of(endpoint.on_depth).co_firstlineno   # the line of its def
    """
    return getattr(getattr(func, "__func__", func), "__code__", None)


def code_name(code: CodeType, fallback: str) -> str:
    """``"Doubler.double"``: the qualified name of ``code``, or ``fallback`` before Python 3.11.

    Example::

        code_name(Doubler.double.__code__, Doubler.double.__qualname__)   # 'Doubler.double'
    """
    return getattr(code, "co_qualname", None) or fallback


def describe_callable(func: Any) -> str:
    """``"MyEndpoint.on_depth (robot.py:30)"``: a function with where it is.

    Example::

        describe_callable(endpoint.update_filter)
    """
    name = getattr(getattr(func, "__func__", func), "__qualname__", None) or repr(func)
    code = code_of(func)
    return (
        str(name)
        if code is None
        else f"{name} ({short_path(code.co_filename)}:{code.co_firstlineno})"
    )


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
    code = code_of(func)
    if code is None:
        return ""
    name = code_name(code, getattr(getattr(func, "__func__", func), "__qualname__", code.co_name))
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
    return source_block(frame.f_code.co_filename, frame.f_lineno, frame_name(frame))


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


def walk_own(function: ast.AST) -> Iterator[ast.AST]:
    """The nodes of ``function``'s body, not of the functions or classes defined inside it.

    Example::

        [n for n in walk_own(def_node) if isinstance(n, ast.Return)]   # its own returns
    """
    stack = list(ast.iter_child_nodes(function))
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            stack.extend(ast.iter_child_nodes(node))
