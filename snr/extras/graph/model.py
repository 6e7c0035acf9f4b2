"""The data-flow graph of a system: nodes, components, keys and links.

`graph_of_config` builds it from a `Config` without running anything: each
role's node is built (``Node(role, config)``, which builds the components
but starts none: sockets, threads and files open in ``begin()``), and
dropped. `graph_of_node` builds it from a running node, for the console's
``graph`` command. For every component the graph knows

* the keys it **handles**: its ``task_handlers`` for ``(store_page, KEY)``
  and ``(process_data, KEY)`` (exact);
* the keys it **produces** and **reads**: its ``produces``/``reads``
  attributes, and the keys found in its code (`source_keys`);
* for a comms component, the keys it **forwards** to its peers.

Links join comms components: a sockets server and the clients with the
same ``(host, port)``; from a running node, every open link and the role at
its other end. Pages that came over a link are stored by that link's
component on the receiving node.

`SystemGraph.problems` lists the keys a node reads but nothing on it stores
(nor brings over a link), and the keys stored but read by nobody (nor sent
on): the commonest wiring mistake is a key spelt two ways.

Example::

    graph = graph_of_config(Config(make_components()))
    for problem in graph.problems():
        print(problem.text)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Sequence, Set, Tuple

from snr.core import Config, Node, ThreadLoop
from snr.core.component import Component
from snr.core.node import NODE_CORE_NAME
from snr.extras.graph.source_keys import key_uses, resolve
from snr.prelude import AbstractComponent, AbstractConfig, DataKey, Role, TaskType
from snr.std_mods.comms.comms_loop import CommsLoop, LinkState
from snr.std_mods.comms.sockets import SocketsClientLoop, SocketsServerLoop

__all__ = [
    "ComponentInfo",
    "KeyProblem",
    "LinkInfo",
    "NodeInfo",
    "SystemGraph",
    "describe_component",
    "graph_of_config",
    "graph_of_node",
]

_PAGE_TASKS = (TaskType.store_page, TaskType.process_data)
UNKNOWN_PEER = "?"
"""The role drawn at the far end of a link whose peer the graph cannot know."""


@dataclass
class ComponentInfo:
    """One component, and the data keys it handles, produces and reads.

    Example::

        ComponentInfo("telemetry", "Telemetry", "endpoint", handles=["depth"],
                      produces=["sensor_data"], reads=["heading", "speed"])
    """

    name: str
    class_name: str
    kind: str  # "endpoint", "loop" or "link"
    handles: List[DataKey] = field(default_factory=list)
    produces: List[DataKey] = field(default_factory=list)
    reads: List[DataKey] = field(default_factory=list)
    handles_every_key: bool = False  # a type-level store_page handler, e.g. a recorder
    unresolved: List[str] = field(default_factory=list)  # stores whose key is computed


@dataclass
class NodeInfo:
    """One node (role): its components, in start order.

    ``stored_here`` (from a running node only) holds the keys in the
    datastore that this node stored but no component is known to produce.

    Example::

        NodeInfo("urov", [ComponentInfo("telemetry", "Telemetry", "endpoint")])
    """

    role: Role
    components: List[ComponentInfo] = field(default_factory=list)
    stored_here: List[DataKey] = field(default_factory=list)

    def component(self, name: str) -> Optional[ComponentInfo]:
        """The component called ``name``, or None."""
        return next((c for c in self.components if c.name == name), None)


@dataclass
class LinkInfo:
    """A link between a comms component and its peer, and the keys each way.

    ``b_role`` is `UNKNOWN_PEER` when the other end is not in the graph
    (a pipe, or a server whose clients are elsewhere).

    Example::

        LinkInfo("topside", "sockets_client_9000", "urov", "sockets_server_9000",
                 "TCP 127.0.0.1:9000", a_to_b=["controller_input"])
    """

    a_role: Role
    a_component: str
    b_role: Role
    b_component: str
    label: str
    a_to_b: List[DataKey] = field(default_factory=list)
    b_to_a: List[DataKey] = field(default_factory=list)


@dataclass(frozen=True)
class KeyProblem:
    """A key read but never produced on a node, or produced but never read.

    Example::

        KeyProblem("urov", "depht", "never_produced", ("telemetry",))
    """

    role: Role
    key: DataKey
    kind: str  # "never_produced" or "never_read"
    components: Tuple[str, ...]  # who reads it / who produces it

    @property
    def text(self) -> str:
        """The problem in words, with the likely fix."""
        who = ", ".join(self.components)
        if self.kind == "never_produced":
            return (
                f"Node {self.role!r}: {self.key!r} is read by {who}, but nothing on the node "
                "stores it and no link brings it. Is it spelt the same where it is stored? "
                "Is the node that stores it linked, with the key in the link's keys?"
            )
        return (
            f"Node {self.role!r}: {self.key!r} is stored by {who}, but nothing on the node "
            "reads it and no link sends it on. Is it spelt the same where it is read? "
            "Should a comms component forward it to another node?"
        )


@dataclass
class SystemGraph:
    """Nodes and links of a system, with its keys; render it with `snr.extras.graph`.

    Example::

        graph = graph_of_config(config)
        print(to_mermaid(graph))
    """

    nodes: List[NodeInfo] = field(default_factory=list)
    links: List[LinkInfo] = field(default_factory=list)

    def node(self, role: Role) -> Optional[NodeInfo]:
        """The node of ``role``, or None."""
        return next((n for n in self.nodes if n.role == role), None)

    def arriving(self, role: Role) -> Dict[DataKey, List[str]]:
        """Keys that links bring to ``role``: key -> the comms components that store them."""
        found: Dict[DataKey, List[str]] = {}
        for link in self.links:
            if link.b_role == role:
                for key in link.a_to_b:
                    _add(found, key, link.b_component)
            if link.a_role == role:
                for key in link.b_to_a:
                    _add(found, key, link.a_component)
        return found

    def producers(self, role: Role) -> Dict[DataKey, List[str]]:
        """Every key stored on ``role``: key -> who stores it (components, links)."""
        found = self.arriving(role)
        node = self.node(role)
        if node is not None:
            for component in node.components:
                for key in component.produces:
                    _add(found, key, component.name)
            for key in node.stored_here:
                found.setdefault(key, [])
        return found

    def consumers(self, role: Role) -> Dict[DataKey, List[str]]:
        """Every key used on ``role``: key -> who handles, reads or forwards it."""
        found: Dict[DataKey, List[str]] = {}
        node = self.node(role)
        if node is not None:
            for component in node.components:
                for key in [*component.handles, *component.reads]:
                    _add(found, key, component.name)
        return found

    def problems(self) -> List[KeyProblem]:
        """Keys read but never produced, and produced but never read, node by node.

        A node with a link to an unknown peer (`UNKNOWN_PEER`) may get any key
        over it, so its keys are not called "never produced"; a node with a
        component that handles every key (a recorder of everything) reads all.
        """
        problems: List[KeyProblem] = []
        for node in self.nodes:
            producers, consumers = self.producers(node.role), self.consumers(node.role)
            open_inputs = any(
                UNKNOWN_PEER in (link.a_role, link.b_role)
                and node.role in (link.a_role, link.b_role)
                for link in self.links
            )
            if not open_inputs:
                for key in sorted(set(consumers) - set(producers), key=str):
                    problems.append(
                        KeyProblem(node.role, key, "never_produced", tuple(consumers[key]))
                    )
            if not any(c.handles_every_key for c in node.components):
                for key in sorted(set(producers) - set(consumers), key=str):
                    who = tuple(producers[key]) or (f"node {node.role!r}",)
                    problems.append(KeyProblem(node.role, key, "never_read", who))
        return problems


def _add(table: Dict[DataKey, List[str]], key: DataKey, name: str) -> None:
    names = table.setdefault(key, [])
    if name not in names:
        names.append(name)


def _keys(keys: object) -> List[DataKey]:
    """A ``produces``/``reads`` value as a list: one key (a str) is fine too."""
    if isinstance(keys, str):
        return [keys]
    if isinstance(keys, Iterable):
        return [key for key in keys if isinstance(key, str) and key]
    return []


def _declared(component: AbstractComponent, name: str) -> Optional[List[DataKey]]:
    """The component's own ``produces``/``reads``, or None when it keeps the default.

    Set on the instance or on its class (even to ``()``), it is the whole
    answer: the code is not read for those keys.
    """
    if name in vars(component):
        return _keys(vars(component)[name])
    for klass in type(component).__mro__:
        if klass is Component:
            return None
        if name in vars(klass):
            return _keys(vars(klass)[name])
    return None


def describe_component(component: AbstractComponent) -> ComponentInfo:
    """What ``component`` handles, produces and reads (see the module docstring).

    Example::

        describe_component(node.components["telemetry"]).produces   # ['sensor_data']
    """
    handles: List[DataKey] = []
    every_key = False
    for task_id in component.task_handlers:
        if isinstance(task_id, tuple) and task_id[0] in _PAGE_TASKS:
            if task_id[1] not in handles:
                handles.append(task_id[1])
        elif task_id in _PAGE_TASKS:
            every_key = True
    produces, reads = _declared(component, "produces"), _declared(component, "reads")
    unresolved: List[str] = []
    if isinstance(component, CommsLoop):
        kind = "link"  # what a link stores comes from its peer: see SystemGraph.arriving
    else:
        kind = "loop" if isinstance(component, ThreadLoop) else "endpoint"
        if produces is None or reads is None:
            found = resolve(key_uses(type(component)), component)
            if produces is None:
                produces, unresolved = sorted(found.stores, key=str), found.unresolved
            if reads is None:
                reads = sorted(found.reads, key=str)
    return ComponentInfo(
        name=component.name,
        class_name=type(component).__name__,
        kind=kind,
        handles=handles,
        produces=produces or [],
        reads=[key for key in reads or [] if key not in handles],
        handles_every_key=every_key,
        unresolved=unresolved,
    )


def _describe_node(role: Role, components: Iterable[AbstractComponent]) -> NodeInfo:
    return NodeInfo(role, [describe_component(c) for c in components if c.name != NODE_CORE_NAME])


def graph_of_config(config: AbstractConfig, roles: Optional[Sequence[Role]] = None) -> SystemGraph:
    """The graph of ``config`` (every role, or ``roles``), built without running a node.

    Each role's node is built and dropped: its components' constructors run,
    so they must not open hardware (that belongs in ``begin()``).

    Raises:
        ConfigError / ComponentError: a role is unknown, or a component cannot
            be built (the message names the factory).
    """
    chosen = list(config.roles()) if roles is None else list(roles)
    # No profiler: these nodes never run, and a profiler would only cost time.
    quiet = (
        Config(config.factories, mode=config.mode, profile=False)
        if isinstance(config, Config)
        else config
    )
    graph = SystemGraph()
    comms: List[Tuple[Role, CommsLoop]] = []
    for role in list(config.roles()):
        node = Node(role, quiet)
        if role in chosen:
            graph.nodes.append(_describe_node(role, node.components.values()))
        comms.extend((role, c) for c in node.components.values() if isinstance(c, CommsLoop))
    graph.links = _static_links(comms, chosen)
    return graph


def _static_links(comms: List[Tuple[Role, CommsLoop]], chosen: Sequence[Role]) -> List[LinkInfo]:
    """Sockets servers and clients paired by address; other comms to an unknown peer."""
    servers = {c.address: (role, c) for role, c in comms if isinstance(c, SocketsServerLoop)}
    links: List[LinkInfo] = []
    served: Set[Tuple[Role, str]] = set()
    for role, component in comms:
        if isinstance(component, SocketsServerLoop):
            continue
        if isinstance(component, SocketsClientLoop) and component.address in servers:
            server_role, server = servers[component.address]
            served.add((server_role, server.name))
            host, port = component.address
            link = LinkInfo(
                role,
                component.name,
                server_role,
                server.name,
                f"TCP {host}:{port}",
                list(component.keys),
                list(server.keys),
            )
        else:
            link = LinkInfo(
                role, component.name, UNKNOWN_PEER, "", _label(component), list(component.keys)
            )
        links.append(link)
    for role, server in servers.values():
        if (role, server.name) not in served:
            links.append(
                LinkInfo(role, server.name, UNKNOWN_PEER, "", _label(server), list(server.keys))
            )
    return [link for link in links if link.a_role in chosen or link.b_role in chosen]


def _label(component: CommsLoop) -> str:
    address = getattr(component, "address", None)
    if isinstance(address, tuple) and len(address) == 2:
        return f"TCP {address[0]}:{address[1]}"
    return type(component).__name__.replace("Loop", "").lower() or "link"


def graph_of_node(node: Node) -> SystemGraph:
    """The graph of a running node, as it is now (run it on the node's thread).

    Its components as built (consoles and components added while running
    included); its comms components' open links and the roles at their other
    end; and from the datastore, the keys that came from each peer and the
    keys this node stored that no component is known to produce.
    """
    info = _describe_node(node.role, list(node.components.values()))
    graph = SystemGraph([info])
    origins: Dict[Role, List[DataKey]] = {}
    for key, page in list(node.datastore.items()):
        origins.setdefault(page.origin, []).append(key)
    linked_roles: Set[Role] = set()
    for component in list(node.components.values()):
        if not isinstance(component, CommsLoop):
            continue
        peers = [
            link.peer_role or UNKNOWN_PEER
            for link in component.links
            if link.state is LinkState.OPEN
        ] or [UNKNOWN_PEER]
        for peer in dict.fromkeys(peers):
            arrived = [] if peer in linked_roles else sorted(origins.get(peer, []), key=str)
            linked_roles.add(peer)
            graph.links.append(
                LinkInfo(
                    node.role,
                    component.name,
                    peer,
                    "",
                    _label(component),
                    list(component.keys),
                    arrived,
                )
            )
    known = set(graph.producers(node.role))
    info.stored_here = sorted(
        (key for key in origins.get(node.role, []) if key not in known), key=str
    )
    for role, keys in origins.items():
        if role != node.role and role not in linked_roles:
            info.stored_here.extend(k for k in sorted(keys, key=str) if k not in known)
    return graph
