"""Pointing at the student's code, not SNR's: where a class or a call is; a value cut short.

What the prelude's own messages need; the rest is `snr.core.checks.student_code`
and `snr.core.checks.error_text`, read second. Frames of SNR's runtime
(``snr/core``, ``snr/prelude``) are skipped.

Example::

    describe_class(DepthSensor)      # 'DepthSensor (robot.py:3)'
    caller_location()                # 'robot.py:42 in Rogue.loop'
"""

from __future__ import annotations

import inspect
import os
import sys
from types import FrameType
from typing import Any, Optional

__all__ = ["caller_location", "describe_class", "frame_location", "frame_name", "is_runtime_file"]
__all__ += ["outside_runtime", "short_path", "short_repr"]

_SNR_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_RUNTIME_DIRS = tuple(os.path.join(_SNR_DIR, sub) + os.sep for sub in ("core", "prelude"))
# The runners built on the core's (CliRunner, MultiProcRunner) are the runtime too.
_RUNTIME_DIRS += (os.path.join(_SNR_DIR, "std_mods", "runners.py"),)


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


def is_runtime_file(filename: str) -> bool:
    """True for SNR's runtime files (``snr/core``, ``snr/prelude``, the runners): reports skip them.

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


def frame_location(frame: FrameType, line: Optional[int] = None) -> str:
    """``"robot.py:12 in MyFactory.get"``: where a frame is (at ``line``, or now).

    Example::

        frame_location(sys._getframe())
    """
    at = frame.f_lineno if line is None else line
    return f"{short_path(frame.f_code.co_filename)}:{at} in {frame_name(frame)}"


def frame_name(frame: FrameType) -> str:
    """``"MyFactory.get"``: the qualified name of the function a frame runs.

    Example::

        frame_name(sys._getframe())   # 'MyFactory.get' inside MyFactory.get
    """
    code = frame.f_code
    name: Optional[str] = getattr(code, "co_qualname", None)  # Python 3.11+
    if name is None:
        # Before 3.11: add the class of `self` (or `cls`), as co_qualname would.
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


def short_repr(value: Any, limit: int = 120, end: str = "…") -> str:
    """``repr(value)``, cut to ``limit`` characters (ending in ``end``) so messages stay readable.

    Example::

        short_repr(list(range(1000)), 20)   # '[0, 1, 2, 3, 4, 5, …'
    """
    try:
        text = repr(value)
    except Exception as error:  # a broken __repr__ must not hide the real error
        return f"<{type(value).__name__} whose repr() raised {type(error).__name__}>"
    return text if len(text) <= limit else text[: limit - len(end)] + end
