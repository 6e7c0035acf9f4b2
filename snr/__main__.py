"""``python -m snr``: the SNR command line.

``python -m snr --help`` lists its commands (demo, console, graph, docs, convert,
lesson, plot, router, secret, version); ``python -m snr COMMAND --help`` tells one.

Example::

    python -m snr demo --seconds 10
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Dict, List, Optional, Sequence

import snr
import snr.console
from snr.core import plugins
from snr.prelude.install import DISTRIBUTION

__all__ = ["main"]


_COMMANDS: Dict[str, str] = {  # name: what `snr --help` says of it
    "demo": "run a demo, no hardware needed: the UROV of the thesis (two nodes over "
    "TCP), or with --sim a simulated rover that follows walls",
    "console": "type commands into a running node, by HOST:PORT or, with --zenoh, by its "
    "role (the same as snr-console)",
    "docs": "build (if needed) and open SNR's docs, the guide and the API reference, offline",
    "graph": "draw the data-flow graph of the system a program runs, without running it",
    "convert": "convert a recording between JSON lines and MCAP (*.mcap)",
    "lesson": "the course's lessons: list them, start one, grade your file in the simulator",
    "plot": "draw keys of a recording over time, to a PNG file (pictures of a run)",
    "router": "run a Zenoh router for a classroom, set up from the secret (docs/comms.md)",
    "secret": "make the secret that only your team's nodes know (docs/comms.md)",
    "version": "print the installed SNR version",
}
"""Every command but console, secret and version lives in an extra, which describes it."""


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
    parsers = {name: sub.add_parser(name, help=words) for name, words in _COMMANDS.items()}
    parsers["secret"].description = (
        "new: write a fresh random secret to the secret file, which every "
        "node on this computer then uses to prove it belongs to your system; copy the "
        "file to each computer of your team. SNR_SECRET in the environment wins over it."
    )
    parsers["secret"].add_argument("action", choices=["new"], help="new: make a fresh secret")
    parsers["secret"].add_argument(
        "--force", action="store_true", help="replace the secret file if it exists"
    )
    parsers["version"].description = "Print the version of the SNR that 'import snr' finds."
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["console"]:  # its own options, e.g. --token, go to snr-console
        return snr.console.main(words[1:], prog="snr console")
    file_args: List[str] = []
    if words[:1] == ["graph"] and "--" in words:  # what follows `--` is FILE's own
        file_args = words[words.index("--") + 1 :]
        words = words[: words.index("--")]
    command: Any = None
    if words[:1] and words[0] in _COMMANDS and words[0] not in ("secret", "version"):
        # These commands live in extras, found by their entry points (docs/design.md,
        # "Extras and extension points"), loaded only when asked for.
        try:
            command = plugins.load("snr.commands", words[0], f"python -m snr {words[0]}")
        except snr.SNRError as error:
            print(f"snr {words[0]}: {error}", file=sys.stderr)
            return 1
        if hasattr(command, "add_arguments"):  # its description and options
            command.add_arguments(parsers[words[0]])
    args = parser.parse_args(words)
    args.file_args = file_args
    if command is not None:
        try:
            return int(command.run(args))
        except argparse.ArgumentError as error:  # options that do not go together
            parsers[words[0]].error(str(error))  # prints the usage, exits with status 2
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
    """``snr --version``: prints e.g. ``snr-robotics 0.1.0`` and exits with 0.

    An action, so it answers while parsing, whatever follows it.

    Example::

        parser.add_argument("--version", action=_PrintVersion, help="print the version")
    """

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
