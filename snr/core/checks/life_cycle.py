"""A node or loop used out of turn, in words: run twice, started twice, a task without its page.

Example::

    raise ran_twice_error("robot", "terminated")
    # Cannot run node 'robot': it is terminated. A node runs once; build a new
    # Node to run again.
"""

from __future__ import annotations

from snr.prelude.errors import NodeStateError

__all__ = ["NOT_A_PAGE", "ran_twice_error", "started_twice_error"]

NOT_A_PAGE = (
    "A store_page task for %r carries %r instead of a Page; dropped it. "
    "Make these tasks with tasks.store_page(page) or self.store_data_task()."
)
"""What the node core logs for a ``store_page`` task without a page (its name, its values)."""


def ran_twice_error(role: str, state: str) -> NodeStateError:
    """The error for ``Node.loop()`` called on a node that is not new (``state``: where it is).

    Example::

        raise ran_twice_error("robot", "running")
    """
    return NodeStateError(
        f"Cannot run node {role!r}: it is {state}. A node runs once; build a new Node to run again."
    )


def started_twice_error(name: str, state: str) -> NodeStateError:
    """The error for a loop whose thread is started while it runs (``state``: "running").

    Example::

        raise started_twice_error("sonar", "running")
    """
    return NodeStateError(
        f"Cannot start loop {name!r} twice: it is {state}. "
        "Reloading builds a new loop from its factory instead."
    )
