"""``python -m snr demo``: the command, found by the kernel's ``snr.commands`` entry point.

``snr/__main__.py`` names the command; this declares its options (``--seconds``,
``--sim``...), checks how they combine and runs the demo they ask for.

Example::

    python -m snr demo --seconds 5
"""

from __future__ import annotations

import argparse

from snr.extras.demo.run import run_demo, run_sim_demo
from snr.prelude.install import install_hint

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``python -m snr demo`` to ``parser``.

    Example::

        add_arguments(argparse.ArgumentParser(prog="snr demo"))
    """
    parser.description = (
        "By default: the UROV of the thesis, two nodes in two processes "
        "talking over TCP, which is what SNR is for. --sim: one node, a simulated rover "
        "driven by the wall follower of the first lesson (docs/lessons.md)."
    )
    parser.add_argument("--seconds", type=float, default=15.0, help="how long to run")
    parser.add_argument(
        "--verbose", action="store_true", help="show the nodes' whole log, not only warnings"
    )
    parser.add_argument(
        "--view",
        action="store_true",
        help="serve a live view for Foxglove or Lichtblick and print the URL to open "
        f"(needs {install_hint('view')})",
    )
    parser.add_argument(
        "--view-port", type=int, default=8765, help="the live view's port (default 8765)"
    )
    parser.add_argument(
        "--sim",
        action="store_true",
        help="a simulated rover follows walls, in a window or as PNG frames "
        f"(needs {install_hint('controller')} to draw)",
    )
    parser.add_argument(
        "--frames",
        metavar="DIR",
        default=None,
        help="with --sim: write PNG frames to DIR instead of opening a window",
    )


def run(args: argparse.Namespace) -> int:
    """Run the demo ``python -m snr demo`` was asked for; the exit status.

    Example::

        run(argparse.Namespace(seconds=2.0, verbose=False, sim=True, frames=None, view=False))
    """
    # A wrong pair of options is a usage error: `python -m snr` prints it with
    # the usage and exits with status 2, as argparse does for its own.
    if args.sim and args.view:
        raise argparse.ArgumentError(
            None, "--view watches the UROV demo; it does not go with --sim"
        )
    if not args.sim and args.frames is not None:
        raise argparse.ArgumentError(None, "--frames goes with --sim")
    if args.sim:
        return run_sim_demo(args.seconds, verbose=args.verbose, frames_dir=args.frames)
    view_port = args.view_port if args.view else None
    return run_demo(args.seconds, verbose=args.verbose, view_port=view_port)
