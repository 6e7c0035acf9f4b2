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
     +-- HandlerError         a task handler raised or returned a wrong value
     +-- LoopError            a loop's setup() or loop() raised
     +-- NodeStateError       a node was used in the wrong life-cycle state
     +-- ThreadSafetyError    node state was touched from the wrong thread
     +-- CommsError           talking to another node failed
          +-- WireFormatError  a frame on the wire is malformed
          +-- NotSerializableError  data cannot be sent between nodes
"""

from __future__ import annotations

import difflib
import inspect
import os
from typing import Any, Iterable, List, Optional

__all__ = [
    "CommsError",
    "ComponentError",
    "ConfigError",
    "HandlerError",
    "LoopError",
    "NodeStateError",
    "NotSerializableError",
    "SNRError",
    "ThreadSafetyError",
    "WireFormatError",
    "closest_match",
    "describe_callable",
    "describe_class",
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


def describe_class(cls: type) -> str:
    """``"MyEndpoint (robot.py:12)"``: a class with where it is defined.

    Example::

        describe_class(MovingAvgEndpoint)  # 'MovingAvgEndpoint (filters.py:40)'
    """
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
    found: List[str] = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return found[0] if found else None
