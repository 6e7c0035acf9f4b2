"""The node core endpoint's old home: it is in `snr.core.node` now, beside its node.

Kept so that ``from snr.core.node_core import NODE_CORE_NAME`` goes on working.

Example::

    from snr.core.node_core import NODE_CORE_NAME   # "node_core"
"""

from snr.core.node import NODE_CORE_NAME, NodeCoreEndpoint, NodeCoreFactory

__all__ = ["NODE_CORE_NAME", "NodeCoreEndpoint", "NodeCoreFactory"]
