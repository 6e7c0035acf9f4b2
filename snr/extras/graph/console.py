"""The console's ``graph`` command, registered when a console starts.

The kernel's console loads this module through the entry point group
``snr.console_commands``; the command draws the running node with
`snr.extras.graph.command.console_graph`.

Example::

    $ snr-console -c "graph mermaid"
"""

from __future__ import annotations

from typing import List

from snr.std_mods.io.command_processor import (
    Answer,
    CommandProcessorEndpoint,
    command,
    one_choice,
)

__all__: List[str] = []


@command(
    "graph [text|mermaid|dot]",
    "Show the node's components, the data keys each stores and handles, and its links.",
    "`text` (the default) is for reading here; `mermaid` can be pasted into a\n"
    "Markdown file (GitHub draws it), `dot` into Graphviz. Keys read but never\n"
    "stored, or stored but never read, are marked (!). `python -m snr graph main.py`\n"
    "draws the whole system without running it.",
)
def _graph(p: CommandProcessorEndpoint, args: str) -> Answer:
    """``graph [text|mermaid|dot]``: this node's data-flow graph, as it runs now."""
    choice = one_choice("graph", args or "text", ["text", "mermaid", "dot"])
    # Here, not at the top: the graph loads ast, which only `graph` needs.
    from snr.extras.graph.command import console_graph

    return console_graph(p.full_node("graph"), choice)
