"""Logging set-up: readable lines on stderr unless the program set its own.

Every node logs to ``snr.<role>`` and every component to
``snr.<role>.<component>``, so one call quiets a whole node::

    node.log.setLevel(logging.WARNING)
"""

from __future__ import annotations

import logging
import sys

from snr.prelude import Mode

__all__ = ["LOG_FORMAT", "ensure_log_handler", "level_for_mode"]

LOG_FORMAT = "%(asctime)s %(name)s %(levelname)s: %(message)s"
"""How SNR's own handler formats a line."""

_ROOT = "snr"


def level_for_mode(mode: Mode) -> int:
    """INFO while developing or deployed, WARNING in tests (quiet output)."""
    return logging.WARNING if mode is Mode.TEST else logging.INFO


def ensure_log_handler() -> None:
    """Add a stderr handler to the ``snr`` logger if nobody configured logging.

    A program that calls ``logging.basicConfig`` (or a test runner that
    captures logs) keeps full control: SNR adds nothing then.
    """
    snr_log = logging.getLogger(_ROOT)
    if snr_log.handlers or logging.getLogger().handlers:
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter(LOG_FORMAT, datefmt="%H:%M:%S"))
    snr_log.addHandler(handler)
