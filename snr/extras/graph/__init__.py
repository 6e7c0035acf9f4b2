"""The data-flow graph of an SNR system: ``python -m snr graph main.py``.

Nodes, their components, the data keys each component produces and handles,
and the links between nodes, drawn as Mermaid (which GitHub renders) or
Graphviz DOT, with the keys read but never produced (or produced but never
read) in red. `graph_of_config` draws a `Config` without running it;
`graph_of_node` a running node (the console's ``graph`` command).

Example::

    from snr.extras.graph import config_from_script, graph_of_config, to_mermaid

    print(to_mermaid(graph_of_config(config_from_script("examples/urov/main.py"))))
"""

from snr.extras.graph.model import (
    UNKNOWN_PEER,
    ComponentInfo,
    KeyProblem,
    LinkInfo,
    NodeInfo,
    SystemGraph,
    describe_component,
    graph_of_config,
    graph_of_node,
)
from snr.extras.graph.render import FORMATS, render, to_dot, to_mermaid, to_text
from snr.extras.graph.script import config_from_script

__all__ = [
    "FORMATS",
    "UNKNOWN_PEER",
    "ComponentInfo",
    "KeyProblem",
    "LinkInfo",
    "NodeInfo",
    "SystemGraph",
    "config_from_script",
    "describe_component",
    "graph_of_config",
    "graph_of_node",
    "render",
    "to_dot",
    "to_mermaid",
    "to_text",
]
