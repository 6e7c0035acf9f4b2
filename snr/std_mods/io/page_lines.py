"""The JSON-lines page format of recordings and serial links (moved).

The format now lives in the page codec, `snr.std_mods.codec`, beside the
comms frames, so both share one strict JSON reader and writer. This module
keeps the old import path working.

Example::

    from snr.std_mods.io.page_lines import page_from_line, page_to_line
    page_from_line(page_to_line(Page("depth_m", 3.2, "urov", 1700000000.25)))
"""

from __future__ import annotations

from snr.std_mods.codec import (
    FORMAT_NAME,
    FORMAT_VERSION,
    PathLike,
    check_header,
    decode_line,
    header_line,
    is_header,
    page_from_fields,
    page_from_line,
    page_to_line,
)

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "PathLike",
    "check_header",
    "decode_line",
    "header_line",
    "is_header",
    "page_from_fields",
    "page_from_line",
    "page_to_line",
]
