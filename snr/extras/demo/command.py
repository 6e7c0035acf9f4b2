"""``python -m snr demo``: the command, found by the kernel's ``snr.commands`` entry point.

``snr/__main__.py`` declares the command's options (``--seconds``, ``--sim``...)
and checks how they combine; this runs the demo they ask for.

Example::

    python -m snr demo --seconds 5
"""

from __future__ import annotations

import argparse

from snr.extras.demo.run import run_demo, run_sim_demo

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    """Run the demo ``python -m snr demo`` was asked for; the exit status.

    Example::

        run(argparse.Namespace(seconds=2.0, verbose=False, sim=True, frames=None, view=False))
    """
    if args.sim:
        return run_sim_demo(args.seconds, verbose=args.verbose, frames_dir=args.frames)
    view_port = args.view_port if args.view else None
    return run_demo(args.seconds, verbose=args.verbose, view_port=view_port)
