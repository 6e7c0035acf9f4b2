"""A value cut to fit a message: what the prelude's own messages need.

What Python said about an error (``exception_text``) and "did you mean"
(``closest_match``, ``did_you_mean``) are in `snr.core.checks.error_text`,
read second.

Example::

    short_repr(list(range(1000)), 20)   # '[0, 1, 2, 3, 4, 5, …'
"""

from __future__ import annotations

from typing import Any

__all__ = ["short_repr"]


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
