"""``python -m snr``: the SNR command line.

Commands::

    python -m snr demo [--seconds N] [--verbose] [--view [--view-port P]]
                                       run the UROV demo system (no hardware needed);
                                       --view: watch it live in Foxglove or Lichtblick
    python -m snr demo --sim [--seconds N] [--frames DIR]
                                       a simulated rover follows the walls of a room
    python -m snr console HOST:PORT    type commands into a running node (snr-console)
    python -m snr graph FILE [--role R] [--format mermaid|dot|text] [-- ARGS...]
                                       draw the system FILE runs, without running it
    python -m snr docs [--serve]       build (if needed) and open the docs, offline
    python -m snr convert IN OUT       convert a recording: JSON lines <-> MCAP (by OUT's name)
    python -m snr version              print the installed version (also: --version)
"""

from __future__ import annotations

import argparse
import sys
from typing import List, Optional, Sequence

import snr
import snr.console
from snr.prelude.install import DISTRIBUTION, install_hint

__all__ = ["main"]


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of ``python -m snr`` and the ``snr`` command."""
    parser = argparse.ArgumentParser(prog="snr", description="SNR is Not ROS")
    parser.add_argument(
        "--version", action=_PrintVersion, help="print the installed version and exit"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo_parser = sub.add_parser(
        "demo",
        help="run the demo system of nodes",
        description="By default: the UROV of the thesis, two nodes in two processes "
        "talking over TCP, which is what SNR is for. --sim: one node, a simulated rover "
        "driven by the wall follower of the first lesson (docs/lessons.md).",
    )
    demo_parser.add_argument("--seconds", type=float, default=15.0, help="how long to run")
    demo_parser.add_argument(
        "--verbose", action="store_true", help="show the nodes' whole log, not only warnings"
    )
    demo_parser.add_argument(
        "--view",
        action="store_true",
        help="serve a live view for Foxglove or Lichtblick and print the URL to open "
        f"(needs {install_hint('viz')})",
    )
    demo_parser.add_argument(
        "--view-port", type=int, default=8765, help="the live view's port (default 8765)"
    )
    demo_parser.add_argument(
        "--sim",
        action="store_true",
        help="a simulated rover follows walls, in a window or as PNG frames "
        f"(needs {install_hint('controller')} to draw)",
    )
    demo_parser.add_argument(
        "--frames",
        metavar="DIR",
        default=None,
        help="with --sim: write PNG frames to DIR instead of opening a window",
    )
    sub.add_parser("console", help="type commands into a running node (same as snr-console)")
    docs_parser = sub.add_parser("docs", help="build (if needed) and open the docs offline")
    graph_parser = sub.add_parser(
        "graph",
        usage="snr graph FILE [--role ROLE] [--format {mermaid,dot,text}] [-- ARGS...]",
        help="draw the data-flow graph of the system a program runs, without running it",
        description="Draw the nodes, components, data keys and links of the system FILE "
        "would run. FILE runs until it starts an SNR runner; the runner hands over its "
        "config instead of starting nodes. Keys read but never stored, or stored but "
        "never read, are marked (!).",
    )
    graph_parser.add_argument("file", metavar="FILE", help="the program, e.g. main.py")
    graph_parser.add_argument(
        "--role", action="append", default=None, help="draw only this role (repeatable)"
    )
    graph_parser.add_argument(
        "--format", choices=["mermaid", "dot", "text"], default="mermaid", help="default mermaid"
    )
    convert_parser = sub.add_parser(
        "convert", help="convert a recording between JSON lines and MCAP (*.mcap)"
    )
    sub.add_parser("version", help="print the SNR version")
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["console"]:  # its own options, e.g. --token, go to snr-console
        return snr.console.main(words[1:])
    file_args: List[str] = []
    if words[:1] == ["graph"] and "--" in words:  # what follows `--` is FILE's own
        file_args = words[words.index("--") + 1 :]
        words = words[: words.index("--")]
    if words[:1] == ["convert"]:  # its options, built only when asked for
        from snr.std_mods.io import convert

        convert.add_arguments(convert_parser)
    if words[:1] == ["docs"]:  # the docs builder is loaded only to build docs
        from snr.tools import docsite

        docsite.add_arguments(docs_parser)
    args = parser.parse_args(words)
    if args.command == "demo":
        from snr.demo import run_demo, run_sim_demo  # only the demo needs it

        if args.sim:
            if args.view:
                demo_parser.error("--view watches the UROV demo; it does not go with --sim")
            return run_sim_demo(args.seconds, verbose=args.verbose, frames_dir=args.frames)
        if args.frames is not None:
            demo_parser.error("--frames goes with --sim")
        view_port = args.view_port if args.view else None
        return run_demo(args.seconds, verbose=args.verbose, view_port=view_port)
    if args.command == "graph":
        return _graph(args.file, file_args, args.role, args.format)
    if args.command == "docs":
        return docsite.run(args)
    if args.command == "convert":
        return convert.run(args)
    if args.command == "version":
        print(snr.__version__)
        return 0
    parser.print_help()
    return 2


class _PrintVersion(argparse.Action):
    """``snr --version``: prints e.g. ``snr-robotics 0.1.0`` and exits with 0."""

    def __init__(self, option_strings: Sequence[str], dest: str, help: str) -> None:
        super().__init__(option_strings, dest, nargs=0, help=help)

    def __call__(self, parser: argparse.ArgumentParser, *args: object) -> None:
        print(f"{DISTRIBUTION} {_installed_version()}")
        parser.exit()


def _installed_version() -> str:
    """The version pip installed (the distribution's metadata), e.g. ``"0.1.0"``.

    It is ``snr.__version__``, which the build reads; a checkout put on
    ``sys.path`` without installing it has no metadata, and gives its own.
    """
    # Loaded only when asked: importlib.metadata costs more than all of `import snr`.
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(DISTRIBUTION)
    except PackageNotFoundError:
        return snr.__version__


def _graph(file: str, file_args: Sequence[str], roles: Optional[Sequence[str]], form: str) -> int:
    """``python -m snr graph``: print the graph of the system ``file`` runs."""
    from snr.std_mods.graph import config_from_script, graph_of_config, render

    try:
        config = config_from_script(file, file_args)
        for role in roles or ():
            config.get(role)  # an unknown role: the error lists the known ones
        print(render(graph_of_config(config, roles), form))
    except snr.SNRError as error:
        print(f"snr graph: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
