"""``python -m snr graph`` and the console's ``graph``, as the kernel finds them.

The kernel never imports this package: ``python -m snr graph`` loads `run`
through the ``snr.commands`` entry point ``graph``, and the console's
``graph`` command (``snr.extras.graph.console``, found through
``snr.console_commands``) calls `console_graph` (``pyproject.toml``).

Example::

    python -m snr graph examples/urov/main.py --format text
"""

from __future__ import annotations

import argparse
import sys

from snr.core import Node
from snr.extras.graph.model import graph_of_config, graph_of_node
from snr.extras.graph.render import render
from snr.extras.graph.script import config_from_script
from snr.prelude import SNRError

__all__ = ["add_arguments", "console_graph", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``python -m snr graph`` to ``parser``.

    Example::

        add_arguments(argparse.ArgumentParser(prog="snr graph"))
    """
    parser.description = (
        "Draw the nodes, components, data keys and links of the system FILE "
        "would run. FILE runs until it starts an SNR runner; the runner hands over its "
        "config instead of starting nodes. Keys read but never stored, or stored but "
        "never read, are marked (!)."
    )
    parser.usage = "snr graph FILE [--role ROLE] [--format {mermaid,dot,text}] [-- ARGS...]"
    parser.add_argument("file", metavar="FILE", help="the program, e.g. main.py")
    parser.add_argument(
        "--role", action="append", default=None, help="draw only this role (repeatable)"
    )
    parser.add_argument(
        "--format", choices=["mermaid", "dot", "text"], default="mermaid", help="default mermaid"
    )


def run(args: argparse.Namespace) -> int:
    """``python -m snr graph``: print the graph of the system ``args.file`` runs.

    ``args`` holds ``file``, ``file_args`` (what followed ``--``), ``role``
    (a list or None) and ``format``.

    Example::

        run(argparse.Namespace(file="main.py", file_args=[], role=None, format="text"))
    """
    try:
        config = config_from_script(args.file, args.file_args)
        for role in args.role or ():
            config.get(role)  # an unknown role: the error lists the known ones
        print(render(graph_of_config(config, args.role), args.format))
    except SNRError as error:
        print(f"snr graph: {error}", file=sys.stderr)
        return 1
    return 0


def console_graph(node: Node, form: str) -> str:
    """The console's ``graph [text|mermaid|dot]``: ``node``'s graph as it runs now.

    Example::

        print(console_graph(node, "text"))
    """
    return render(graph_of_node(node), form)
