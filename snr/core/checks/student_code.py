"""Source lines and tracebacks for messages: the rest of `snr.prelude.student_code`.

The prelude's helpers (`describe_class`, `caller_location`...) are named here too,
so a check imports all of them from one place.

Example::

    print(def_block(Doubler.double))
    #   File "/home/student/rov/robot.py", line 11, in Doubler.double
    #     def double(self, task: Task, key: TaskId) -> SomeTasks:
"""

from __future__ import annotations

import ast
import functools
import inspect
import linecache
import sys
import threading
import traceback
from types import CodeType, FrameType
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

__all__ = ["caller_block", "caller_location", "code_name", "code_of", "def_block"]
__all__ += ["describe_callable", "describe_class", "failure_frames", "frame_location"]
__all__ += ["innermost_frame", "is_runtime_file", "is_snr", "line_with_code", "outside_runtime"]
__all__ += ["parse_source", "running_line", "short_path", "source_block", "source_node"]
__all__ += ["walk_own"]


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


def _qualname(func: Any) -> Optional[str]:
    return getattr(getattr(func, "__func__", func), "__qualname__", None)


def describe_callable(func: Any) -> str:
    """``"MyEndpoint.on_depth (robot.py:30)"``: a function with where it is.

    Example::

        describe_callable(endpoint.update_filter)
    """
    name, code = _qualname(func) or repr(func), code_of(func)
    return (
        name if code is None else f"{name} ({short_path(code.co_filename)}:{code.co_firstlineno})"
    )


def innermost_frame(error: BaseException) -> Optional[FrameType]:
    """The frame where ``error`` was raised (the last of its traceback), or None.

    Example::

        innermost_frame(error).f_locals   # the names where it went wrong
    """
    tb = error.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return None if tb is None else tb.tb_frame


def failure_frames(error: BaseException) -> str:
    """The student's frames of ``error`` under a heading; its traceback is then trimmed to them.

    SNR's own frames are left out of both (all of them are shown if only SNR's: a bug in SNR).

    Example::

        raise HandlerError(f"... raised {what}{failure_frames(error)}") from error
        # Where it happened (most recent call last):
        #   File "robot.py", line 30, in on_depth
        #     return 1 / 0
    """
    frames = traceback.extract_tb(error.__traceback__)
    theirs = traceback.StackSummary.from_list(
        [f for f in frames if not is_runtime_file(f.filename)]
    )
    tb = error.__traceback__
    while tb is not None and is_runtime_file(tb.tb_frame.f_code.co_filename):
        tb = tb.tb_next
    if tb is not None:  # Python's own report of it then starts at the student's code
        error.__traceback__ = tb
    shown = "".join((theirs or frames).format()).rstrip()
    return f"\nWhere it happened (most recent call last):\n{shown}"


def source_block(filename: str, line: int, name: str, context: str = "") -> str:
    """One line of code as a traceback shows it (editors open it with a click).

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

    Example::

        def_block(DepthPrinter.on_depth)
        #   File "/home/student/rov/robot.py", line 8, in DepthPrinter.on_depth
        #     def on_depth(self, task: Task) -> SomeTasks:
    """
    code = code_of(func)
    if code is None:
        return ""
    name = code_name(code, _qualname(func) or code.co_name)
    return source_block(code.co_filename, code.co_firstlineno, name)


def caller_block(text: str = "") -> str:
    """``text`` and the nearest caller outside SNR's runtime as a `source_block` under it.

    Example::

        raise ComponentError(caller_block("... set too early."))
    """
    frame = outside_runtime(sys._getframe(1))
    if frame is None:
        return text
    block = source_block(frame.f_code.co_filename, frame.f_lineno, frame_name(frame))
    return f"{text}\n{block}" if text else block


def running_line(thread_id: Optional[int]) -> str:
    """Where a thread is now, outside SNR and the standard library; "" when not running.

    Example::

        running_line(loop.thread_id)   # "sensor.py:12 in Sonar.loop: `reading = port.read()`"
    """
    frame = sys._current_frames().get(thread_id) if thread_id is not None else None
    innermost = frame
    prefixes = (sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix)
    stdlib = ("<", *(f"{p}/lib/python" for p in prefixes))  # "<frozen ...>" too
    while frame is not None and (
        is_runtime_file(frame.f_code.co_filename) or frame.f_code.co_filename.startswith(stdlib)
    ):
        frame = frame.f_back
    frame = frame or innermost
    return "" if frame is None else line_with_code(frame)


def line_with_code(frame: FrameType, line: Optional[int] = None) -> str:
    """A frame's place and code, at ``line`` or where it is now (no code if unreadable).

    Example::

        line_with_code(sys._getframe())   # "robot.py:30 in Depth.loop: `x = line_with_code(...)`"
    """
    at = frame.f_lineno if line is None else line
    code = linecache.getline(frame.f_code.co_filename, at).strip()
    return frame_location(frame, at) + (f": `{code}`" if code else "")


_PARSE_LOCK = threading.Lock()


def parse_source(text: str) -> ast.Module:
    """``ast.parse(text)``, one thread at a time.

    Two nodes in one process may read a student's source at once, and on
    CPython 3.11.7 two parses at once can fail with ``SystemError: AST
    constructor recursion depth mismatch``.

    Example::

        parse_source("x = 1").body[0]   # an ast.Assign
    """
    with _PARSE_LOCK:
        return ast.parse(text)


@functools.lru_cache(maxsize=64)  # DEPLOYED nodes may explain one mistake many times
def source_node(obj: Any) -> Optional[ast.stmt]:
    """The ``def`` or ``class`` statement of a function, code object or class, or None.

    Its line numbers are the file's; None when the source cannot be read.

    Example::

        source_node(Doubler.double.__code__).lineno   # 11, the line of the def
    """
    import textwrap  # here, not at the top: only needed once something is wrong

    try:
        lines, first = inspect.getsourcelines(obj)
        tree = parse_source(textwrap.dedent("".join(lines)))
    except (OSError, TypeError, SyntaxError, ValueError):
        return None
    ast.increment_lineno(tree, first - 1)
    return tree.body[0] if tree.body else None


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
