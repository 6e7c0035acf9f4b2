"""``python -m snr``: the SNR command line.

Commands::

    python -m snr demo [--seconds N]   run the UROV demo system (no hardware needed)
    python -m snr console HOST:PORT    type commands into a running node (snr-console)
    python -m snr docs [--serve]       build (if needed) and open the docs, offline
    python -m snr version              print the installed version
"""

from __future__ import annotations

import argparse
import importlib.util
import socket
import sys
from pathlib import Path
from typing import Optional, Sequence

import snr
import snr.console
import snr.docsite

__all__ = ["main"]


def _urov_example() -> Optional[Path]:
    """``examples/urov/main.py`` of the source checkout SNR runs from, if any."""
    path = Path(snr.__file__).resolve().parent.parent / "examples" / "urov" / "main.py"
    return path if path.is_file() else None


def _free_port_pair(host: str = "127.0.0.1") -> int:
    """A port P such that P and P+1 are both free on ``host`` right now."""
    for _ in range(50):
        with socket.socket() as probe:
            probe.bind((host, 0))
            port = int(probe.getsockname()[1])
        if port >= 65535:
            continue
        with socket.socket() as second:
            try:
                second.bind((host, port + 1))
            except OSError:
                continue
        return port
    raise snr.CommsError(f"Could not find two free neighbouring ports on {host}.")


def demo(seconds: float) -> int:
    """Run the UROV system, both roles on this machine, for ``seconds``.

    Each role runs in its own process, talking over TCP on 127.0.0.1 (ports
    chosen now, so the demo never collides with anything). The topside
    process shows the vehicle's live telemetry. Ctrl-C stops it early.
    """
    script = _urov_example()
    if script is None:
        print(
            "The demo runs examples/urov from an SNR source checkout, which this "
            "installation does not have. Clone the SNR repository and run "
            "`pip install -e . && python -m snr demo` in it.",
            file=sys.stderr,
        )
        return 2
    sys.path.insert(0, str(script.parent))
    spec = importlib.util.spec_from_file_location("urov_main", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    components = module.make_components("127.0.0.1", _free_port_pair(), seconds)
    config = snr.Config(components, mode=snr.Mode.DEPLOYED)
    print(
        f"SNR demo: the UROV system of thesis listing 5.1 for {seconds:g} s "
        "(topside and urov nodes, one process each; Ctrl-C stops it).",
        flush=True,
    )
    runner = snr.MultiProcRunner(["urov", "topside"], config)
    runner.run()
    failed = [code for code in runner.exitcodes if code not in (0, None)]
    return 1 if failed else 0


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
