"""The program around its runner: a runner never run, no role given, an error nobody caught.

`runner_built` and `runner_ran`: a runner the program's own ``__main__`` code
built and never ran is said at exit (not in a test, in DEPLOYED mode, or after
an uncaught error: docs/errors.md, 15q). `no_role_given`: ``python robot.py``
without a role, answered with the roles. `snr_excepthook`, set by ``import snr``
unless a tool set its own: an `SNRError` nobody caught is printed with the
student's frames only, unless ``--verbose`` or ``SNR_VERBOSE=1`` (16p).

Example::

    runner = CliRunner({"robot": [...]})   # runner_built(runner, config) in __init__
    runner.run()                            # runner_ran(runner) as run() starts
"""

from __future__ import annotations

import atexit
import os
import sys
import traceback
from types import TracebackType
from typing import Any, Dict, List, NoReturn, Optional, Sequence, Tuple, Type

from snr.core.checks.student_code import frame_location, outside_runtime, source_block
from snr.prelude import AbstractConfig, Mode, SNRError

__all__ = [
    "VERBOSE_ENV",
    "install_excepthook",
    "no_role_given",
    "runner_built",
    "runner_ran",
    "snr_excepthook",
]

# id(runner) -> (runner, kept so its id is not reused; "robot.py:4 in <module>"; its line).
_not_run: Dict[int, Tuple[object, str, str]] = {}
_registered: List[bool] = []


def runner_built(runner: object, config: AbstractConfig) -> None:
    """Remember ``runner`` until it runs, if the program's own code built it.

    Example::

        runner_built(self, self.config)   # last line of a runner's __init__
    """
    frame = outside_runtime(sys._getframe(1))
    if frame is None or frame.f_globals.get("__name__") != "__main__":
        return
    if config.mode is Mode.DEPLOYED or "pytest" in sys.modules:
        return
    unittest = sys.modules.get("unittest")
    if unittest is not None and isinstance(frame.f_locals.get("self"), unittest.TestCase):
        return
    block = source_block(frame.f_code.co_filename, frame.f_lineno, frame.f_code.co_name)
    _not_run[id(runner)] = (runner, frame_location(frame), block)
    if not _registered:
        _registered.append(True)
        atexit.register(_say_not_run)


def runner_ran(runner: object) -> None:
    """``runner.run()`` was called: nothing to say about it at exit.

    Example::

        runner_ran(self)   # first line of a runner's run()
    """
    _not_run.pop(id(runner), None)


def _say_not_run() -> None:
    if getattr(sys, "last_value", None) is not None:
        return
    for runner, place, block in _not_run.values():
        name = type(runner).__name__
        print(
            f"{name} built at {place} never ran: the program ended without starting a "
            f"node. Call its run(): `{name}(...).run()`, or `runner.run()` on the name "
            f"you gave it.\n{block}",
            file=sys.stderr,
            flush=True,
        )
    _not_run.clear()


def no_role_given(parser: Any, prog: str, roles: Sequence[str]) -> NoReturn:
    """Exit (status 2) with ``parser``'s usage, the roles to choose from and an example.

    Example::

        no_role_given(parser, "robot.py", ["urov", "topside"])
        # robot.py: error: no role given. Choose one of: urov, topside. For example: ...
    """
    parser.print_usage(sys.stderr)
    print(
        f"{prog}: error: no role given. Choose one of: {', '.join(roles)}. "
        f"For example: python {prog} {roles[0] if roles else 'ROLE'}",
        file=sys.stderr,
    )
    raise SystemExit(2)


VERBOSE_ENV = "SNR_VERBOSE"
"""The environment variable that asks for SNR's frames in tracebacks."""

_SNR_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))) + os.sep
_LEFT_OUT = (
    f"(SNR's own frames are left out: run with --verbose, or set {VERBOSE_ENV}=1, to see them.)"
)


def install_excepthook() -> None:
    """Make `snr_excepthook` Python's, unless someone else already replaced Python's own.

    Example::

        install_excepthook()
    """
    if sys.excepthook is sys.__excepthook__:
        sys.excepthook = snr_excepthook


def snr_excepthook(
    kind: Type[BaseException], error: BaseException, tb: Optional[TracebackType]
) -> None:
    """Print an uncaught `SNRError` as the student's frames and its message; others as Python.

    Example::

        sys.excepthook = snr_excepthook   # Traceback ... robot.py ... ConfigError: ...
    """
    frames = [f for f in traceback.extract_tb(tb) if not f.filename.startswith(_SNR_DIR)]
    verbose = os.environ.get(VERBOSE_ENV, "0") not in ("", "0") or "--verbose" in sys.argv
    if not isinstance(error, SNRError) or not frames or verbose:
        sys.__excepthook__(kind, error, tb)
        return
    print("Traceback (most recent call last):", file=sys.stderr)
    print("".join(traceback.format_list(frames)), end="", file=sys.stderr)
    print(f"{kind.__name__}: {error}", file=sys.stderr)
    print(_LEFT_OUT, file=sys.stderr, flush=True)
