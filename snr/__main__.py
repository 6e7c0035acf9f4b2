"""``python -m snr``: the SNR command line.

``python -m snr --help`` lists its commands (demo, console, graph, docs, convert,
lesson, plot, router, secret, version); ``python -m snr COMMAND --help`` tells one.

Example::

    python -m snr demo --seconds 10
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Dict, List, Optional, Sequence, Tuple

import snr
import snr.console
from snr.core import plugins
from snr.prelude.install import DISTRIBUTION, install_hint

__all__ = ["main"]


_COMMANDS: Dict[str, Tuple[str, Optional[str]]] = {  # name: (help, description)
    "demo": (
        "run a demo, no hardware needed: the UROV of the thesis (two nodes over "
        "TCP), or with --sim a simulated rover that follows walls",
        "By default: the UROV of the thesis, two nodes in two processes "
        "talking over TCP, which is what SNR is for. --sim: one node, a simulated rover "
        "driven by the wall follower of the first lesson (docs/lessons.md).",
    ),
    # Never parsed here: `snr console ...` goes to snr.console.main, whose help is its own.
    "console": (
        "type commands into a running node, by HOST:PORT or, with --zenoh, by its "
        "role (the same as snr-console)",
        None,
    ),
    "docs": (
        "build (if needed) and open SNR's docs, the guide and the API reference, offline",
        "Build SNR's documentation, the guide and the API reference, as HTML "
        "(only if a page or the code changed since the last build), then open it in a "
        "browser, to read offline; --serve serves it on http://127.0.0.1 instead.",
    ),
    "graph": (
        "draw the data-flow graph of the system a program runs, without running it",
        "Draw the nodes, components, data keys and links of the system FILE "
        "would run. FILE runs until it starts an SNR runner; the runner hands over its "
        "config instead of starting nodes. Keys read but never stored, or stored but "
        "never read, are marked (!).",
    ),
    "convert": (
        "convert a recording between JSON lines and MCAP (*.mcap)",
        "Convert a recording of pages: JSON lines to MCAP, or MCAP to JSON "
        "lines. The source's format is read from its first bytes, the target's from its "
        "name (*.mcap: MCAP, anything else: JSON lines).",
    ),
    "lesson": (
        "the course's lessons: list them, start one, grade your file in the simulator",
        None,
    ),
    "plot": (
        "draw keys of a recording over time, to a PNG file (pictures of a run)",
        "Draw the pages of each KEY in a recording (JSON lines or MCAP) "
        "over time: one subplot per key, each number in its data a line. Writes a PNG "
        f"file, no screen needed (needs {install_hint('plot')}).",
    ),
    "router": (
        "run a Zenoh router for a classroom, set up from the secret (docs/comms.md)",
        "A Zenoh router that nodes in mode='client' connect to where multicast "
        "is blocked; with a secret, only nodes with the same secret link to it. --zenohd "
        f"prints what zenohd needs instead (needs {install_hint('zenoh')}).",
    ),
    "secret": (
        "make the secret that only your team's nodes know (docs/comms.md)",
        "new: write a fresh random secret to the secret file, which every "
        "node on this computer then uses to prove it belongs to your system; copy the "
        "file to each computer of your team. SNR_SECRET in the environment wins over it.",
    ),
    "version": (
        "print the installed SNR version",
        "Print the version of the SNR that 'import snr' finds.",
    ),
}


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of ``python -m snr`` and the ``snr`` command."""
    parser = argparse.ArgumentParser(
        prog="snr",
        description="SNR is Not ROS: a pure-Python robotics framework for teaching.",
        epilog="Run 'snr COMMAND --help' for a command's options.",
    )
    parser.add_argument(
        "--version", action=_PrintVersion, help="print the installed version and exit"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    parsers = {
        name: sub.add_parser(name, help=h, description=d) for name, (h, d) in _COMMANDS.items()
    }
    demo_parser = parsers["demo"]
    demo_parser.add_argument("--seconds", type=float, default=15.0, help="how long to run")
    demo_parser.add_argument(
        "--verbose", action="store_true", help="show the nodes' whole log, not only warnings"
    )
    demo_parser.add_argument(
        "--view",
        action="store_true",
        help="serve a live view for Foxglove or Lichtblick and print the URL to open "
        f"(needs {install_hint('view')})",
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
    graph_parser = parsers["graph"]
    graph_parser.usage = "snr graph FILE [--role ROLE] [--format {mermaid,dot,text}] [-- ARGS...]"
    graph_parser.add_argument("file", metavar="FILE", help="the program, e.g. main.py")
    graph_parser.add_argument(
        "--role", action="append", default=None, help="draw only this role (repeatable)"
    )
    graph_parser.add_argument(
        "--format", choices=["mermaid", "dot", "text"], default="mermaid", help="default mermaid"
    )
    parsers["secret"].add_argument("action", choices=["new"], help="new: make a fresh secret")
    parsers["secret"].add_argument(
        "--force", action="store_true", help="replace the secret file if it exists"
    )
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["console"]:  # its own options, e.g. --token, go to snr-console
        return snr.console.main(words[1:], prog="snr console")
    file_args: List[str] = []
    if words[:1] == ["graph"] and "--" in words:  # what follows `--` is FILE's own
        file_args = words[words.index("--") + 1 :]
        words = words[: words.index("--")]
    command: Any = None
    if words[:1] in (["demo"], ["graph"], ["docs"], ["convert"], ["lesson"], ["plot"], ["router"]):
        # These commands live in extras, found by their entry points (docs/design.md,
        # "Extras and extension points"), loaded only when asked for.
        try:
            command = plugins.load("snr.commands", words[0], f"python -m snr {words[0]}")
        except snr.SNRError as error:
            print(f"snr {words[0]}: {error}", file=sys.stderr)
            return 1
        if hasattr(command, "add_arguments"):  # its own options, e.g. convert's
            command.add_arguments(parsers[words[0]])
    args = parser.parse_args(words)
    if args.command == "demo":
        if args.sim and args.view:
            demo_parser.error("--view watches the UROV demo; it does not go with --sim")
        if not args.sim and args.frames is not None:
            demo_parser.error("--frames goes with --sim")
    if args.command == "graph":
        args.file_args = file_args
    if command is not None:
        return int(command.run(args))
    if args.command == "version":
        print(snr.__version__)
        return 0
    if args.command == "secret":
        return _new_secret(bool(args.force))
    parser.print_help()
    return 2


def _new_secret(force: bool) -> int:
    """``snr secret new``: write a fresh secret to the secret file (owner-only), say where."""
    import os

    from snr.std_mods.comms.handshake import new_secret, secret_file

    path = secret_file()
    if path.exists() and not force:
        print(
            f"snr secret: {path} exists already; nodes on this computer use it. Copy it to "
            "your team's other computers, or replace it with `snr secret new --force` "
            "(then copy the new one to every computer of the team).",
            file=sys.stderr,
        )
        return 1
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as file:
        file.write(new_secret() + "\n")
    print(
        f"Wrote a new secret to {path} (readable by you only). Copy this file to the same "
        "place on every computer of your team: nodes with it link only to each other."
    )
    return 0


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


if __name__ == "__main__":
    sys.exit(main())
