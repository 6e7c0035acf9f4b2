"""``python -m snr plot``: draw keys of a recording over time, to a PNG file.

The kernel never imports this package: ``python -m snr plot`` loads it
through the ``snr.commands`` entry point ``plot`` (``pyproject.toml``).
matplotlib is imported only to draw, and drawn with its Agg backend (no
window, no screen needed), without pyplot, so a notebook's own plots are
left alone.

Example::

    python -m snr plot dive.jsonl depth_m heading_deg -o dive.png
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import IO, Any, Optional, Sequence

from snr.extras.plot.columns import read_recording
from snr.prelude import ConfigError, SNRError
from snr.prelude.install import install_hint
from snr.std_mods.codec import PathLike

__all__ = ["add_arguments", "plot_recording", "run"]


def _matplotlib_figure() -> Any:
    """matplotlib's ``Figure`` class, or a ConfigError that says how to install it."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise ConfigError(
            f"drawing a recording needs matplotlib, which is not installed: {install_hint('plot')}"
        ) from None
    return Figure


def plot_recording(
    recording: PathLike, keys: Sequence[str], output: Optional[PathLike] = None
) -> str:
    """Draw ``keys`` of ``recording`` over time into a PNG file; the file's name.

    One subplot per key, one above the other with a shared time axis, each
    numeric field of the key's data a line (with a legend when there are
    several).

    Args:
        recording: a recording, JSON lines or MCAP.
        keys: the keys to draw; their data must be numbers, or dicts or
            lists of numbers (see `snr.std_mods.io.Column`).
        output: the PNG file to write (default: the recording's name with
            ``.png``, in the current folder). An existing file is replaced.

    Raises:
        ConfigError: matplotlib is missing, the recording cannot be read, a
            key is not in it, or a key's data is not numbers.

    Example::

        plot_recording("dive.jsonl", ["depth_m"])   # 'dive.png'
    """
    if not keys:
        raise ConfigError("Name at least one key to draw, e.g. depth_m.")
    figure_class = _matplotlib_figure()
    run = read_recording(recording, keys)
    for key in keys:
        if run[key].not_numeric:
            raise ConfigError(
                f"Cannot draw {key!r}: only numbers, or dicts or lists of numbers, are drawn, "
                f"and in {run.filename!r} {run[key].not_numeric}. Draw another key, or read "
                "it with snr.read_recording and plot it your way."
            )
    if output is None:
        stem = os.path.splitext(os.path.basename(run.filename))[0]
        output = stem + ".png"
    target = os.fspath(output)
    height = 1.0 + 2.2 * len(keys)
    figure = figure_class(figsize=(8.0, height), layout="constrained")
    axes = figure.subplots(len(keys), 1, sharex=True, squeeze=False)[:, 0]
    for ax, key in zip(axes, keys):
        column = run[key]
        for name, values in column.fields.items():
            ax.plot(column.t_s, values, label=name, marker="." if len(values) < 50 else None)
        ax.set_title(key, loc="left")
        ax.grid(True, alpha=0.3)
        if len(column.fields) > 1:
            ax.legend(loc="best", fontsize="small")
    axes[-1].set_xlabel("time since the first page (s)")
    figure.suptitle(os.path.basename(run.filename))
    figure.savefig(target, format="png", dpi=100)
    return target


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``python -m snr plot`` to ``parser``.

    Example::

        add_arguments(sub.add_parser("plot"))
    """
    parser.description = (
        "Draw the pages of each KEY in a recording (JSON lines or MCAP) "
        "over time: one subplot per key, each number in its data a line. Writes a PNG "
        f"file, no screen needed (needs {install_hint('plot')})."
    )
    parser.add_argument("recording", help="a recording: JSON lines or MCAP")
    parser.add_argument("keys", metavar="KEY", nargs="+", help="a key to draw (one subplot each)")
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        default=None,
        help="the PNG file to write (default: the recording's name with .png, here)",
    )


def run(args: argparse.Namespace, out: Optional[IO[str]] = None) -> int:
    """Run ``python -m snr plot`` with parsed ``args``; the exit status.

    A problem is one line on stderr and status 1.

    Example::

        run(parser.parse_args(["plot", "dive.jsonl", "depth_m"]))
    """
    out = sys.stdout if out is None else out
    try:
        written = plot_recording(args.recording, args.keys, args.output)
    except (SNRError, OSError) as error:
        print(f"snr plot: {error}", file=sys.stderr)
        return 1
    drawn = ", ".join(args.keys)
    print(f"Drew {drawn} from {args.recording} in {os.path.abspath(written)}", file=out)
    return 0
