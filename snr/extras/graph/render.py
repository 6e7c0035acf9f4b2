"""Draw a `SystemGraph` as Mermaid, Graphviz DOT, or plain text.

Both drawings show one box per component, grouped by node; an arrow per
data key from the component that stores it to each component that handles
it (solid) or reads it with ``get_data`` (dashed); a thick arrow per link
between nodes, labelled with the keys it carries; and, in red, the keys
read but never produced or produced but never read.

Mermaid is text that GitHub, GitLab and most Markdown viewers draw when it
sits in a fenced ```` ```mermaid ```` block; DOT is for Graphviz
(``dot -Tsvg graph.dot -o graph.svg``). The output depends only on the
graph, so a drawing kept in the docs can be compared with a fresh one.

Example::

    print(to_mermaid(graph_of_config(config)))
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

from snr.extras.graph.model import UNKNOWN_PEER, SystemGraph
from snr.prelude import Role

__all__ = ["FORMATS", "render", "to_dot", "to_mermaid", "to_text"]

FORMATS = ("mermaid", "dot", "text")
"""The formats `render` knows, the first the default."""

_OTHER_CODE = "other code"  # who stored a key, when no component is known to


@dataclass
class _Box:
    id: str
    lines: List[str]
    role: Optional[Role]  # the node it sits in; None: outside every node
    style: str = ""  # "", "problem" or "peer"


@dataclass
class _Edge:
    source: str
    target: str
    keys: List[str]
    style: str  # "handles", "reads", "link", "problem"


@dataclass
class _Drawing:
    boxes: List[_Box] = field(default_factory=list)
    edges: List[_Edge] = field(default_factory=list)
    _ids: Dict[Tuple[str, ...], str] = field(default_factory=dict)

    def box(
        self, key: Tuple[str, ...], lines: List[str], role: Optional[Role], style: str = ""
    ) -> str:
        found = self._ids.get(key)
        if found is None:
            found = self._ids[key] = f"n{len(self._ids)}"
            self.boxes.append(_Box(found, lines, role, style))
        return found

    def edge(self, source: str, target: str, key: str, style: str) -> None:
        for edge in self.edges:
            if (edge.source, edge.target, edge.style) == (source, target, style):
                if key not in edge.keys:
                    edge.keys.append(key)
                return
        self.edges.append(_Edge(source, target, [key], style))


def _draw(graph: SystemGraph) -> _Drawing:
    drawing = _Drawing()
    drawn = {node.role for node in graph.nodes}
    for node in graph.nodes:
        for component in node.components:
            drawing.box(
                (node.role, component.name), [component.name, component.class_name], node.role
            )
    problems = graph.problems()
    flagged = {(p.role, p.key, p.kind) for p in problems}
    for node in graph.nodes:
        role = node.role
        info = {c.name: c for c in node.components}
        for key, producers in graph.producers(role).items():
            sources = [drawing.box((role, name), [name], role) for name in producers] or [
                drawing.box((role, "", _OTHER_CODE), [_OTHER_CODE], role)
            ]
            if (role, key, "never_read") in flagged:
                sink = drawing.box(
                    (role, "unread", key), [f"(!) {key}", "never read"], role, "problem"
                )
                for source in sources:
                    drawing.edge(source, sink, key, "problem")
                continue
            for name, component in info.items():
                style = "handles" if key in component.handles else ""
                if key in component.reads:
                    style = "reads"
                if style:
                    target = drawing.box((role, name), [name], role)
                    for source in sources:
                        if source != target:
                            drawing.edge(source, target, key, style)
        for problem in problems:
            if problem.role == role and problem.kind == "never_produced":
                source = drawing.box(
                    (role, "missing", problem.key),
                    [f"(!) {problem.key}", "never produced"],
                    role,
                    "problem",
                )
                for name in problem.components:
                    drawing.edge(
                        source, drawing.box((role, name), [name], role), problem.key, "problem"
                    )

    def end(role: Role, component: str) -> str:
        """A link's end: its component's box, or a box for a node not drawn."""
        if role in drawn and component:
            return drawing.box((role, component), [component], role)
        peer = "unknown peer" if role == UNKNOWN_PEER else f"node {role}"
        return drawing.box(("peer", role), [peer], None, "peer")

    for link in graph.links:
        a, b = end(link.a_role, link.a_component), end(link.b_role, link.b_component)
        for key in link.a_to_b:
            drawing.edge(a, b, key, "link")
        for key in link.b_to_a:
            drawing.edge(b, a, key, "link")
        if not link.a_to_b and not link.b_to_a:
            drawing.edge(a, b, "", "link")
        for edge in drawing.edges:
            if edge.style == "link" and {edge.source, edge.target} == {a, b}:
                tag = f"[{link.label}]"
                if tag not in edge.keys:
                    edge.keys.append(tag)
    return drawing


def _edge_label(edge: _Edge) -> str:
    keys = ", ".join(k for k in edge.keys if k and not k.startswith("["))
    tags = " ".join(k for k in edge.keys if k.startswith("["))
    return f"{keys} {tags}".strip()


def _mermaid_text(text: str) -> str:
    return text.replace('"', "#quot;").replace("<", "#lt;").replace(">", "#gt;")


def to_mermaid(graph: SystemGraph) -> str:
    """The graph as a Mermaid flowchart (put it in a ```` ```mermaid ```` block)."""
    drawing = _draw(graph)
    lines = ["flowchart LR"]

    def box_line(box: _Box, indent: str) -> str:
        label = "<br/>".join(_mermaid_text(line) for line in box.lines)
        return f'{indent}{box.id}["{label}"]'

    for index, node in enumerate(graph.nodes):
        lines.append(f'  subgraph s{index}["node {_mermaid_text(node.role)}"]')
        lines.extend(box_line(b, "    ") for b in drawing.boxes if b.role == node.role)
        lines.append("  end")
    lines.extend(box_line(b, "  ") for b in drawing.boxes if b.role is None)
    arrows = {"handles": "-->", "reads": "-.->", "link": "==>", "problem": "-.->"}
    for edge in drawing.edges:
        label = _mermaid_text(_edge_label(edge))
        arrow = "===" if edge.style == "link" and not any(edge.keys[:1]) else arrows[edge.style]
        lines.append(f'  {edge.source} {arrow}|"{label}"| {edge.target}')
    problem_ids = [b.id for b in drawing.boxes if b.style == "problem"]
    peer_ids = [b.id for b in drawing.boxes if b.style == "peer"]
    lines.append("  classDef problem fill:#fee,stroke:#c00,color:#900")
    lines.append("  classDef peer fill:#fff,stroke:#888,stroke-dasharray:4")
    if problem_ids:
        lines.append(f"  class {','.join(problem_ids)} problem")
    if peer_ids:
        lines.append(f"  class {','.join(peer_ids)} peer")
    return "\n".join(lines)


def _dot_text(*lines: str) -> str:
    """A quoted DOT string; lines are joined with DOT's own line break, ``\\n``."""
    escaped = (line.replace("\\", "\\\\").replace('"', '\\"') for line in lines)
    return '"' + "\\n".join(escaped) + '"'


def to_dot(graph: SystemGraph) -> str:
    """The graph in Graphviz DOT: ``dot -Tsvg graph.dot -o graph.svg`` draws it."""
    drawing = _draw(graph)
    lines = [
        "digraph snr {",
        "  rankdir=LR;",
        '  node [shape=box, fontname="Helvetica"];',
        '  edge [fontname="Helvetica", fontsize=10];',
    ]
    styles = {"problem": ", color=red, fontcolor=red", "peer": ", style=dashed"}

    def box_line(box: _Box, indent: str) -> str:
        label = _dot_text(*box.lines)
        return f"{indent}{box.id} [label={label}{styles.get(box.style, '')}];"

    for index, node in enumerate(graph.nodes):
        lines.append(f"  subgraph cluster_{index} {{")
        lines.append(f"    label={_dot_text('node ' + node.role)};")
        lines.extend(box_line(b, "    ") for b in drawing.boxes if b.role == node.role)
        lines.append("  }")
    lines.extend(box_line(b, "  ") for b in drawing.boxes if b.role is None)
    edge_styles = {
        "handles": "",
        "reads": ", style=dashed",
        "link": ", penwidth=2.5",
        "problem": ", style=dashed, color=red, fontcolor=red",
    }
    for edge in drawing.edges:
        label = _dot_text(_edge_label(edge))
        lines.append(f"  {edge.source} -> {edge.target} [label={label}{edge_styles[edge.style]}];")
    lines.append("}")
    return "\n".join(lines)


def to_text(graph: SystemGraph) -> str:
    """The graph in words: each node's components and keys, the links, the problems."""
    lines: List[str] = []
    for node in graph.nodes:
        lines.append(f"Node {node.role!r} ({len(node.components)} components):")
        for c in node.components:
            parts = []
            if c.handles_every_key:
                parts.append("handles every key")
            for word, keys in (("handles", c.handles), ("stores", c.produces), ("reads", c.reads)):
                if keys:
                    parts.append(f"{word} {', '.join(map(str, keys))}")
            lines.append(f"  {c.name} ({c.class_name}): {'; '.join(parts) or 'no data keys'}")
            for where in c.unresolved:
                lines.append(
                    f"    stores a key computed at run time ({where}); "
                    "name it in `produces` to draw it"
                )
        if node.stored_here:
            stored = ", ".join(map(str, node.stored_here))
            lines.append(f"  stored by code the graph cannot attribute: {stored}")
    if graph.links:
        lines.append("Links:")
    for link in graph.links:
        peer = "an unknown peer" if link.b_role == UNKNOWN_PEER else f"{link.b_role}"
        if link.b_component:
            peer += f".{link.b_component}"
        sends = ", ".join(map(str, link.a_to_b)) or "nothing"
        gets = ", ".join(map(str, link.b_to_a)) or "nothing"
        lines.append(
            f"  {link.a_role}.{link.a_component} <-> {peer} ({link.label}): "
            f"sends {sends}; receives {gets}"
        )
    problems = graph.problems()
    lines.append("Problems:" if problems else "No key is read without a producer or stored unread.")
    lines.extend(f"  (!) {problem.text}" for problem in problems)
    return "\n".join(lines)


def render(graph: SystemGraph, format: str = "mermaid") -> str:
    """``graph`` in one of `FORMATS`.

    Raises:
        ValueError: an unknown format (the message lists them).
    """
    renderers = {"mermaid": to_mermaid, "dot": to_dot, "text": to_text}
    if format not in renderers:
        raise ValueError(f"Unknown graph format {format!r}; use one of {', '.join(FORMATS)}.")
    return renderers[format](graph)
