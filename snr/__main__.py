"""``python -m snr``: the SNR command line.

Commands::

    python -m snr demo [--seconds N]   run the demo system (no hardware needed)
    python -m snr console HOST:PORT    type commands into a running node (snr-console)
    python -m snr docs [--serve]       build (if needed) and open the docs, offline
    python -m snr version              print the installed version
"""

from __future__ import annotations

import argparse
import math
import random
import sys
from typing import List, Optional, Sequence

import snr
import snr.console
import snr.docsite

__all__ = ["main"]


def _demo_config(seconds: float) -> snr.Config:
    """A small system: a noisy depth sensor, a filter, a display, a timeout."""
    rng = random.Random(7)
    readings: List[float] = [
        round(5 + 2 * math.sin(i / 10) + rng.gauss(0, 0.3), 3) for i in range(int(seconds * 20))
    ]
    return snr.Config(
        {
            "demo": [
                snr.ListReplayerFactory(readings, "depth_raw", period_s=0.05),
                snr.MovingAvgFilterFactory("depth_raw", "depth", length=5),
                snr.PrinterEndpointFactory([(snr.TaskType.store_page, "depth")]),
                snr.TimeoutLoopFactory(seconds=seconds),
            ]
        },
        mode=snr.Mode.DEPLOYED,
    )


def demo(seconds: float) -> int:
    """Run the demo system for ``seconds``; Ctrl-C stops it early."""
    snr.SynchronousRunner("demo", _demo_config(seconds)).run()
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of ``python -m snr`` and the ``snr`` command."""
    parser = argparse.ArgumentParser(prog="snr", description="SNR is Not ROS")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo_parser = sub.add_parser("demo", help="run the demo system of nodes")
    demo_parser.add_argument("--seconds", type=float, default=15.0, help="how long to run")
    sub.add_parser("console", help="type commands into a running node (same as snr-console)")
    docs_parser = sub.add_parser("docs", help="build (if needed) and open the docs offline")
    snr.docsite.add_arguments(docs_parser)
    sub.add_parser("version", help="print the SNR version")
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["console"]:  # its own options, e.g. --token, go to snr-console
        return snr.console.main(words[1:])
    args = parser.parse_args(words)
    if args.command == "demo":
        return demo(args.seconds)
    if args.command == "docs":
        return snr.docsite.run(args)
    if args.command == "version":
        print(snr.__version__)
        return 0
    parser.print_help()
    return 2


if __name__ == "__main__":
    sys.exit(main())
