"""Communication between nodes: pipes and TCP sockets.

Serial links and Zenoh are extras: ``snr.extras.serial`` and ``snr.extras.zenoh``.
Every link that writes to a peer queues in the one `Outbox` (``comms_loop.py``).

Example::

    from snr.std_mods.comms import SocketsServerFactory
"""

from snr.std_mods.comms.comms_loop import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    CommsLoop,
    Outbox,
)
from snr.std_mods.comms.pipe import (
    PipeLoop,
    PipeLoopFactory,
)
from snr.std_mods.comms.sockets import (
    SocketsClientFactory,
    SocketsClientLoop,
    SocketsPair,
    SocketsServerFactory,
    SocketsServerLoop,
)

__all__ = [
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "CommsLoop",
    "Outbox",
    "PipeLoop",
    "PipeLoopFactory",
    "SocketsClientFactory",
    "SocketsClientLoop",
    "SocketsPair",
    "SocketsServerFactory",
    "SocketsServerLoop",
]
