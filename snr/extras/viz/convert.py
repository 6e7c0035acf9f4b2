"""Convert recordings between JSON lines and MCAP: ``python -m snr convert IN OUT``.

The source's format is known from its first bytes, the target's from its
name (``.mcap``: MCAP, anything else: JSON lines). Every page is carried over
whole: key, data, origin, ``created_at_s`` and ``process``. A recording SNR
wrote converts to MCAP and back to the very same bytes; bad lines (or
messages) in the source are skipped and counted, as a replay would.

Example::

    convert_recording("dive.jsonl", "dive.mcap")
    # Conversion(pages=1200, skipped=0, source_format='jsonl', target_format='mcap')
"""

from __future__ import annotations

import os
import sys
from typing import IO, TYPE_CHECKING, NamedTuple, Optional

from snr.extras.viz.mcap_files import (
    COMPRESSIONS,
    McapPageWriter,
    format_of_name,
    require_mcap,
)
from snr.prelude import ConfigError, SNRError
from snr.std_mods.codec import PathLike, header_line, page_to_line
from snr.std_mods.io.replayer import PageReader

if TYPE_CHECKING:  # for annotations only: the command line imports argparse itself
    import argparse

__all__ = ["Conversion", "add_arguments", "convert_recording", "run"]

_FORMAT_NAMES = {"jsonl": "JSON lines", "mcap": "MCAP"}


class Conversion(NamedTuple):
    """What `convert_recording` did: pages written, bad lines or messages skipped, formats.

    Example::

        done = convert_recording("dive.mcap", "dive.jsonl")
        print(done.pages, done.skipped, done.source_format)   # 1200 0 mcap
    """

    pages: int
    skipped: int
    source_format: str
    target_format: str


def convert_recording(
    source: PathLike, target: PathLike, compression: str = "none", overwrite: bool = False
) -> Conversion:
    """Write the pages of ``source`` to ``target`` in the format its name says.

    Args:
        source: a recording, JSON lines or MCAP.
        target: the file to write: MCAP if it ends in ``.mcap``, else JSON lines.
        compression: for an MCAP target: ``"none"``, ``"zstd"`` or ``"lz4"``.
        overwrite: replace ``target`` if it exists (otherwise an error).

    The target is written under a temporary name beside it and renamed when
    complete, so a failed conversion leaves no half-written file.

    Raises:
        ConfigError: ``source`` does not exist, ``target`` exists (and not
            ``overwrite``) or is ``source``, or MCAP needs the mcap package.
        WireFormatError: ``source`` is a JSON-lines file of a newer format.
        OSError: ``target`` cannot be written.

    Example::

        convert_recording("dive.jsonl", "dive.mcap", compression="zstd")
    """
    source_name, target_name = os.fspath(source), os.fspath(target)
    reader = PageReader(source_name)
    if os.path.exists(target_name):
        if os.path.samefile(source_name, target_name):
            raise ConfigError(f"Cannot convert {source_name!r} into itself: name another file.")
        if not overwrite:
            raise ConfigError(
                f"{target_name!r} exists: choose another name, or pass --overwrite to replace it."
            )
    target_format = format_of_name(target_name)
    to_mcap = target_format == "mcap"
    if to_mcap:
        require_mcap(f"Writing {target_name!r}")
    elif compression != "none":
        raise ConfigError(f"compression={compression!r} is for MCAP targets (*.mcap) only.")
    partial = target_name + ".partial"
    pages = 0
    with open(partial, "wb") as file:
        try:
            pages = (
                _write_mcap(reader, file, compression) if to_mcap else _write_lines(reader, file)
            )
        except BaseException:
            file.close()
            os.remove(partial)
            raise
    os.replace(partial, target_name)
    source_format = "mcap" if reader.is_mcap else "jsonl"
    return Conversion(pages, reader.bad_lines, source_format, target_format)


def _write_mcap(reader: PageReader, file: IO[bytes], compression: str) -> int:
    writer = McapPageWriter(file, compression, flush=False)
    pages = 0
    for page in reader:
        writer.write(page)
        pages += 1
    writer.close()
    return pages


def _write_lines(reader: PageReader, file: IO[bytes]) -> int:
    file.write(header_line().encode("ascii") + b"\n")
    pages = 0
    for page in reader:
        file.write(page_to_line(page).encode("ascii") + b"\n")
        pages += 1
    return pages


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``python -m snr convert`` to ``parser``.

    Example::

        add_arguments(sub.add_parser("convert"))
    """
    parser.description = (
        "Convert a recording of pages: JSON lines to MCAP, or MCAP to JSON "
        "lines. The source's format is read from its first bytes, the target's from its "
        "name (*.mcap: MCAP, anything else: JSON lines)."
    )
    parser.add_argument("source", help="a recording: JSON lines or MCAP")
    parser.add_argument("target", help="the file to write: *.mcap for MCAP, else JSON lines")
    parser.add_argument(
        "--compression",
        choices=COMPRESSIONS,
        default="none",
        help="compress an MCAP target (zstd and lz4 need their packages)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace the target if it exists")


def run(args: argparse.Namespace, out: Optional[IO[str]] = None) -> int:
    """Run ``python -m snr convert`` with parsed ``args``; the exit status.

    A problem is one line on stderr and status 1.

    Example::

        run(parser.parse_args(["convert", "dive.jsonl", "dive.mcap"]))
    """
    out = sys.stdout if out is None else out
    try:
        done = convert_recording(args.source, args.target, args.compression, args.overwrite)
    except (SNRError, OSError) as error:
        print(f"snr convert: {error}", file=sys.stderr)
        return 1
    print(
        f"Converted {done.pages} pages from {args.source} ({_FORMAT_NAMES[done.source_format]}) "
        f"to {args.target} ({_FORMAT_NAMES[done.target_format]})"
        + (f"; skipped {done.skipped} bad lines or messages (see above)" if done.skipped else ""),
        file=out,
    )
    return 0
