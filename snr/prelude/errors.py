"""The exceptions SNR raises, and helpers that point at the student's code.

Every SNR error is an :class:`SNRError`, so one ``except SNRError`` catches them
all. Messages follow one shape: *what* went wrong (naming your class, handler,
file and line), *why* it probably happened, and *what to do*.

Example::

    try:
        snr.CliRunner(components, ["main.py", "rover"]).run()
    except snr.SNRError as e:
        print(e)

The tree::

    SNRError
     +-- ConfigError          a config, role or factory list is wrong
     +-- ComponentError       an endpoint, loop or factory is written wrongly
     |    +-- MissingSuperInitError  __init__ did not call super().__init__(...)
     +-- HandlerError         a task handler raised or returned a wrong value
     +-- LoopError            a loop's setup() or loop() raised
     +-- NodeStateError       a node was used in the wrong life-cycle state
     +-- ThreadSafetyError    node state was touched from the wrong thread
     +-- CommsError           talking to another node failed
          +-- WireFormatError  a frame on the wire is malformed
          +-- NotSerializableError  data cannot be sent between nodes
"""

from __future__ import annotations

import dataclasses
import enum
import inspect
import math
import os
import sys
import traceback
from types import FrameType, TracebackType
from typing import Any, Iterable, List, Optional, Set, Tuple

__all__ = [
    "CommsError",
    "ComponentError",
    "ConfigError",
    "HandlerError",
    "LoopError",
    "MissingSuperInitError",
    "NodeStateError",
    "NotSerializableError",
    "SNRError",
    "ThreadSafetyError",
    "WireFormatError",
    "caller_block",
    "caller_location",
    "check_serializable",
    "closest_match",
    "describe_callable",
    "describe_class",
    "frame_location",
    "is_runtime_file",
    "not_serializable_error",
    "short_path",
    "short_repr",
    "source_block",
    "student_frames",
    "trim_runtime_frames",
]


class SNRError(Exception):
    """Root of every error SNR raises on purpose.

    Example::

        except snr.SNRError as e: print("SNR says:", e)
    """


class ConfigError(SNRError):
    """A config is wrong: unknown role, empty role, duplicate names.

    Example::

        Config({"robot": []}).get("robot")   # raises ConfigError
    """


class ComponentError(SNRError):
    """An endpoint, loop or factory is written in a way SNR cannot use.

    Example: a handler registered under a bare string key instead of a TaskType.
    """


class MissingSuperInitError(ComponentError, AttributeError):
    """A component's ``__init__`` used the component before ``super().__init__``.

    It is also an ``AttributeError``, so ``hasattr`` and ``getattr(obj, name,
    default)`` keep working on a half-built component.

    Example::

        class Beeper(Endpoint):
            def __init__(self, factory, parent):
                self.task_handlers = {}          # MissingSuperInitError: too early
                super().__init__(factory, parent, "beeper")
    """


class HandlerError(SNRError):
    """A task handler raised an exception or returned something not a Task.

    Example: ``return 5`` from a handler; the message names the handler.
    """


class LoopError(SNRError):
    """A loop's ``setup()`` or ``loop()`` raised; the loop has stopped.

    Example: ``raise Exception("High velocity impact")`` inside ``loop()``.
    """


class NodeStateError(SNRError):
    """A node (or loop) was asked to do something its life-cycle state forbids.

    Example: calling ``node.loop()`` twice.
    """


class ThreadSafetyError(SNRError):
    """Node state was changed from a thread that does not own it.

    Example: a loop thread calling ``node.execute_task(...)`` directly instead of
    ``self.schedule(...)``.
    """


class CommsError(SNRError):
    """Talking to another node failed: port in use, peer refused, bad data.

    Example: two nodes both trying to serve on port 9000.
    """


class WireFormatError(CommsError):
    """A frame read from another node is malformed; it is dropped.

    Example: a length header larger than the maximum frame size.
    """


class NotSerializableError(CommsError):
    """A page's data cannot be turned into JSON to send to another node.

    Example: storing a ``set`` or a custom object under a forwarded key.
    """


def _short_path(path: Optional[str]) -> str:
    if not path:
        return "<unknown file>"
    try:
        rel = os.path.relpath(path)
    except ValueError:  # different drive on Windows
        return path
    return rel if not rel.startswith(".." + os.sep + "..") else path


def short_path(path: Optional[str]) -> str:
    """``path`` as messages show it: relative to the current folder when that is shorter.

    Example::

        short_path("/home/student/rov/robot.py")   # 'robot.py' when run in /home/student/rov
    """
    return _short_path(path)


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
        return f"{cls.__qualname__} ({_short_path(path)}:{line})"
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
    return f"{name} ({_short_path(code.co_filename)}:{code.co_firstlineno})"


def closest_match(word: str, choices: Iterable[str]) -> Optional[str]:
    """The choice most like ``word``, or None: used for "did you mean" hints.

    Example::

        closest_match("urv", ["urov", "topside"])  # 'urov'
    """
    import difflib  # here, not at the top: hints are only made when something is wrong

    found: List[str] = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return found[0] if found else None


# ---------------------------------------------------------------------------
# Pointing at the student's code, not SNR's
# ---------------------------------------------------------------------------
_SNR_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_RUNTIME_DIRS = tuple(os.path.join(_SNR_DIR, sub) + os.sep for sub in ("core", "prelude"))


def is_runtime_file(filename: str) -> bool:
    """True for files of SNR's runtime (``snr/core``, ``snr/prelude``).

    Frames from these files are framework plumbing: the student did not write
    them, so reports skip them. ``snr/std_mods`` is component code and stays.

    Example::

        is_runtime_file(snr.core.node.__file__)   # True
    """
    return filename.startswith(_RUNTIME_DIRS)


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


def caller_location(skip: int = 1) -> str:
    """``"robot.py:42 in Rogue.loop"``: the nearest caller outside SNR's runtime.

    Example::

        raise ThreadSafetyError(f"... called from {caller_location()} ...")
    """
    frame: Optional[FrameType] = sys._getframe(skip)
    while frame is not None and is_runtime_file(frame.f_code.co_filename):
        frame = frame.f_back
    if frame is None:
        return "<unknown place>"
    return frame_location(frame)


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
    import linecache  # here: only used while an error is being explained

    code = linecache.getline(filename, line).strip()
    where = f'  File "{filename}", line {line}, in {name}{context}'
    return f"{where}\n    {code}" if code else where


def caller_block(skip: int = 1) -> str:
    """The nearest caller outside SNR's runtime as a `source_block`, or "".

    For errors found inside SNR on behalf of the line that called it, such
    as a ``self.task_handlers = ...`` that runs before ``super().__init__``.

    Example::

        raise ComponentError(f"... set too early.\n{caller_block()}")
    """
    frame: Optional[FrameType] = sys._getframe(skip)
    while frame is not None and is_runtime_file(frame.f_code.co_filename):
        frame = frame.f_back
    if frame is None:
        return ""
    code = frame.f_code
    name = getattr(code, "co_qualname", None) or frame_location(frame).rsplit(" in ", 1)[-1]
    return source_block(code.co_filename, frame.f_lineno, name)


def frame_location(frame: FrameType, line: Optional[int] = None) -> str:
    """``"robot.py:12 in MyFactory.get"``: where a frame is (at ``line``, or now).

    Example::

        frame_location(sys._getframe())
    """
    code = frame.f_code
    name = getattr(code, "co_qualname", None)  # Python 3.11+
    if name is None:
        # Older Pythons know only the function's name: add the class of
        # `self` (or `cls`) when the frame has one, as co_qualname would.
        owner = frame.f_locals.get("self", frame.f_locals.get("cls"))
        owner_class = owner if isinstance(owner, type) else type(owner)
        name = code.co_name
        if owner is not None and code.co_name in vars(owner_class):
            name = f"{owner_class.__qualname__}.{code.co_name}"
    return f"{_short_path(code.co_filename)}:{frame.f_lineno if line is None else line} in {name}"


def short_repr(value: Any, limit: int = 120) -> str:
    """``repr(value)``, cut to ``limit`` characters so messages stay readable.

    Example::

        short_repr(list(range(1000)), 20)   # '[0, 1, 2, 3, 4, 5, …'
    """
    try:
        text = repr(value)
    except Exception as error:  # a broken __repr__ must not hide the real error
        return f"<{type(value).__name__} whose repr() raised {type(error).__name__}>"
    return text if len(text) <= limit else text[: limit - 1] + "…"


# ---------------------------------------------------------------------------
# Data that cannot cross between nodes
# ---------------------------------------------------------------------------
_JSON_SCALARS = (str, int, float, bool, type(None))
_MAX_DEPTH = 100
_KEY_PROBLEM = "key"
_LOOP_PROBLEM = "loop"
_TYPE_PROBLEM = "type"
_NUMBER_PROBLEM = "number"  # NaN or infinity: JSON has no such numbers
_TEXT_PROBLEM = "text"  # a lone surrogate: not Unicode text, UTF-8 cannot hold it
_Found = Tuple[str, Any, str]  # (path, offending value, which problem)


def _scalar_problem(value: Any) -> Optional[str]:
    if isinstance(value, float) and not math.isfinite(value):
        return _NUMBER_PROBLEM
    if isinstance(value, str) and not value.isascii():
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            return _TEXT_PROBLEM
    return None


def _find(value: Any, path: str, open_containers: Set[int], depth: int) -> Optional[_Found]:
    if isinstance(value, _JSON_SCALARS):
        problem = _scalar_problem(value)
        return None if problem is None else (path, value, problem)
    if not isinstance(value, (list, tuple, dict)):
        return path, value, _TYPE_PROBLEM
    if id(value) in open_containers or depth > _MAX_DEPTH:
        return path, value, _LOOP_PROBLEM
    open_containers.add(id(value))
    try:
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, _JSON_SCALARS):
                    return path, key, _KEY_PROBLEM
                key_problem = _scalar_problem(key)
                if key_problem is not None:
                    return (
                        path,
                        key,
                        _KEY_PROBLEM if key_problem == _NUMBER_PROBLEM else key_problem,
                    )
                found = _find(item, f"{path}[{key!r}]", open_containers, depth + 1)
                if found is not None:
                    return found
        else:
            for index, item in enumerate(value):
                found = _find(item, f"{path}[{index}]", open_containers, depth + 1)
                if found is not None:
                    return found
        return None
    finally:
        open_containers.discard(id(value))


def _serializable_hint(value: Any, problem: str) -> str:
    if problem == _LOOP_PROBLEM:
        return "It contains itself (or nests too deep); send a copy without the loop."
    if problem == _KEY_PROBLEM:
        return "Dict keys sent between nodes must be str (or numbers): use str(key)."
    if problem == _NUMBER_PROBLEM:
        return (
            "JSON has no NaN or infinity: send None (or leave the page out) when there is "
            "no valid number, e.g. None if math.isnan(x) else x."
        )
    if problem == _TEXT_PROBLEM:
        return (
            "It holds a lone surrogate, which is not text: decode bytes with "
            "errors='replace', or send them as value.hex()."
        )
    if isinstance(value, (set, frozenset)):
        return "Send a list instead: list(value), or sorted(value) for a stable order."
    if isinstance(value, (bytes, bytearray)):
        return "Send text or numbers instead: value.hex(), or list(value)."
    if isinstance(value, enum.Enum):
        return "Send value.name or value.value instead."
    if isinstance(value, complex):
        return "Send [value.real, value.imag] instead."
    if hasattr(value, "tolist"):
        return "Convert it with value.tolist() (numpy arrays and numbers)."
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return "Convert it with dataclasses.asdict(value)."
    return "Send a dict or list of plain values instead, e.g. built from the object's fields."


def not_serializable_error(
    key: str, data: Any, where: str = "", to: str = "to another node", reason: str = ""
) -> NotSerializableError:
    """A NotSerializableError naming the key, the path inside the data and the type.

    Args:
        key: the data key of the page.
        data: the page's data.
        where: extra context, e.g. ``" by component 'sockets_client'"``.
        to: where the page was going, e.g. ``"to a recording"``.
        reason: what went wrong when no single part of the data is to blame
            (e.g. it nests too deep or is too big).

    Example::

        not_serializable_error("pose", {"pose": [1, 2, {3}]})
        # "Cannot send the page stored under 'pose' to another node: data['pose'][2]
        #  is a set ({3}), which JSON cannot hold. Send a list instead: ..."
    """
    found = _find(data, "data", set(), 0)
    head = f"Cannot send the page stored under {key!r}{where} {to}"
    allowed = (
        "Data sent between nodes may only hold dicts, lists, tuples, str, int, "
        "float, bool and None."
    )
    if found is None:
        why = reason or "it cannot be written as JSON"
        return NotSerializableError(f"{head}: {why}. {allowed}")
    path, bad, problem = found
    if problem == _KEY_PROBLEM:
        what = f"{path} has a key that is a {type(bad).__name__} ({short_repr(bad, 60)})"
    else:
        what = f"{path} is a {type(bad).__name__} ({short_repr(bad, 60)})"
    return NotSerializableError(
        f"{head}: {what}, which JSON cannot hold. {_serializable_hint(bad, problem)} {allowed}"
    )


def check_serializable(key: str, data: Any, to: str = "to another node") -> None:
    """Raise `not_serializable_error`'s error unless ``data`` is plain JSON.

    For writers that would otherwise quietly change the data (a set written
    as a list, NaN written as ``NaN``), such as `Page.serialize`.

    Example::

        check_serializable("pose", {"x": 1.0})     # fine
        check_serializable("pose", {"x": {1.0}})   # NotSerializableError: data['x'] is a set
    """
    if _find(data, "data", set(), 0) is not None:
        raise not_serializable_error(key, data, to=to)
