"""In DEBUG mode: keys that should cross a link to another node but do not.

The robot forwards ``"sensr_data"`` and the topside handles ``"sensor_data"``:
nothing is shown and nothing is said (thesis listing 5.1). So
``node.key_hints.link_s`` after a link's hello, the comms component compares
the keys with what was stored and received (``MissingKeyHints.check_link``).

Example (what `CommsLoop` does for you)::

    watch_link(comms_loop, link)   # on the I/O thread, when the hello arrives
"""

from __future__ import annotations

import functools
import time
from typing import TYPE_CHECKING, List, Set, Tuple

from snr.core import Node, tasks
from snr.prelude import DataKey, TaskHandler, TaskType

if TYPE_CHECKING:
    from snr.std_mods.comms.comms_loop import CommsLoop, Link

__all__ = ["check_link", "watch_link"]

_PAGE_TASKS = (TaskType.store_page, TaskType.process_data)


def watch_link(comms: CommsLoop, link: Link) -> None:
    """In DEBUG mode, check ``link``'s keys ``link_s`` from now (I/O thread, on hello).

    Example::

        watch_link(self, link)   # in CommsLoop, when the peer's hello arrives
    """
    node, io = comms.parent, comms.io_loop
    if not isinstance(node, Node) or node.key_hints is None or io is None:
        return
    if link.keys_received is None:
        link.keys_received = set()  # from now on the link notes what arrives

    def ask() -> None:  # on the I/O thread: hand the check to the node's thread
        if not link.is_closed() and not comms.is_terminated():
            check = functools.partial(check_link, comms, link)
            comms.schedule(tasks.event(tasks.CHECK_WIRING, [check]))

    io.call_later(node.key_hints.link_s, ask)


def check_link(comms: CommsLoop, link: Link) -> None:
    """On the node's thread: report keys that should have crossed ``link`` by now.

    The keys received over every link to the same peer count together (listing
    5.1 has two); while one is younger than the delay, its own check comes later.

    Example::

        check_link(comms_loop, link)   # see MissingKeyHints.check_link for the messages
    """
    from snr.std_mods.comms.comms_loop import CommsLoop  # here: comms_loop.py imports this module

    node = comms.parent
    if not isinstance(node, Node) or node.key_hints is None or link.is_closed():
        return
    if node.components.get(comms.name) is not comms:
        return  # removed or reloaded since
    hints = node.key_hints
    handled: List[Tuple[DataKey, TaskHandler]] = []
    peer_links: List[Link] = []
    for component in list(node.components.values()):
        if isinstance(component, CommsLoop):  # its keys are checked as sent, not wanted
            peer_links += [other for other in component.links if other.peer_role == link.peer_role]
            continue
        for task_id, handler in list(component.task_handlers.items()):
            if isinstance(task_id, tuple) and task_id[0] in _PAGE_TASKS:
                handled.append((task_id[1], handler))
    now = time.monotonic()
    received: Set[DataKey] = set()
    for other in peer_links:
        if not other.is_closed() and now - other.opened_at < hints.link_s:
            handled = []  # a newer link to the same node: its own check comes later
        received.update(other.keys_received or ())
    places = sorted({other.transport.peer for other in peer_links} | {link.transport.peer})
    peer = f"node {link.peer_name} at {' and '.join(places)}"
    hints.check_link(repr(comms.name), peer, comms.keys, handled, node.datastore, received)
