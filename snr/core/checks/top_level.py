"""`snr_excepthook`: an SNR error nobody caught, printed as the runners print one.

An error raised before any runner (``Config(mode="deployed")``) would reach
Python's report, a traceback through SNR's internals. ``import snr`` sets
`snr_excepthook` as ``sys.excepthook`` (unless a tool set its own): an
`SNRError` is printed with the student's frames only, unless ``--verbose`` or
``SNR_VERBOSE=1`` asks for SNR's (docs/errors.md, 16p).

Example::

    $ python robot.py robot
    Traceback (most recent call last):
      File "/home/student/rov/robot.py", line 4, in <module>
        config = Config({"robot": [...]}, mode="deployed")
    ConfigError: Config(mode=...) got 'deployed'; use Mode.DEBUG, Mode.TEST or Mode.DEPLOYED.
    (SNR's own frames are left out: run with --verbose, or set SNR_VERBOSE=1, to see them.)
"""

from __future__ import annotations

import os
import sys
import traceback
from types import TracebackType
from typing import Optional, Type

from snr.prelude import SNRError

__all__ = ["VERBOSE_ENV", "install_excepthook", "snr_excepthook"]

VERBOSE_ENV = "SNR_VERBOSE"
"""The environment variable that asks for SNR's frames in tracebacks."""

_SNR_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))) + os.sep
_LEFT_OUT = (
    f"(SNR's own frames are left out: run with --verbose, or set {VERBOSE_ENV}=1, to see them.)"
)


def install_excepthook() -> None:
    """Make `snr_excepthook` Python's, unless someone else already replaced Python's own.

    Example::

        install_excepthook()   # what `import snr` does
    """
    if sys.excepthook is sys.__excepthook__:
        sys.excepthook = snr_excepthook


def verbose() -> bool:
    """True when SNR's own frames were asked for: ``--verbose`` or ``SNR_VERBOSE=1``.

    Example::

        verbose()   # False for `python robot.py robot`
    """
    return os.environ.get(VERBOSE_ENV, "0") not in ("", "0") or "--verbose" in sys.argv


def snr_excepthook(
    kind: Type[BaseException], error: BaseException, tb: Optional[TracebackType]
) -> None:
    """Print an uncaught `SNRError` as the student's frames and its message; others as Python.

    Example::

        sys.excepthook = snr_excepthook
    """
    frames = [f for f in traceback.extract_tb(tb) if not f.filename.startswith(_SNR_DIR)]
    if not isinstance(error, SNRError) or not frames or verbose():
        sys.__excepthook__(kind, error, tb)
        return
    print("Traceback (most recent call last):", file=sys.stderr)
    print("".join(traceback.format_list(frames)), end="", file=sys.stderr)
    print(f"{kind.__name__}: {error}", file=sys.stderr)
    print(_LEFT_OUT, file=sys.stderr, flush=True)
