"""Communication between nodes: TCP sockets and pipes (thesis 6.4.1).

Pages stored under chosen keys are forwarded to other nodes, in order, as
length-prefixed JSON frames (``docs/wire-format.md``; the codec is in
``snr.std_mods.comms.wire``).

Example (thesis listing 5.3)::

    sockets = snr.SocketsPair(server_tuple=("localhost", 9000))
    components = {
        "input_device": [..., sockets.client(["controller_data"])],
        "receiver": [sockets.server(), ...],
    }
"""

from snr.std_mods.comms.link import COMMS_CONNECTED, COMMS_DISCONNECTED, CommsLoop
from snr.std_mods.comms.pipe import PipeLoop, PipeLoopFactory
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
    "PipeLoop",
    "PipeLoopFactory",
    "SocketsClientFactory",
    "SocketsClientLoop",
    "SocketsPair",
    "SocketsServerFactory",
    "SocketsServerLoop",
]
