"""Communication between nodes: pipes, TCP sockets, serial links, Zenoh.

Example::

    from snr.std_mods.comms import SerialLinkFactory
"""

from snr.std_mods.comms.comms_loop import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    CommsLoop,
)
from snr.std_mods.comms.pipe import (
    PipeLoop,
    PipeLoopFactory,
)
from snr.std_mods.comms.serial_link_loop import (
    SerialLinkFactory,
    SerialLinkLoop,
)
from snr.std_mods.comms.sockets import (
    SocketsClientFactory,
    SocketsClientLoop,
    SocketsPair,
    SocketsServerFactory,
    SocketsServerLoop,
)
from snr.std_mods.comms.zenoh_comms import (
    ZenohComms,
    ZenohCommsFactory,
)

__all__ = [
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "CommsLoop",
    "PipeLoop",
    "PipeLoopFactory",
    "SerialLinkFactory",
    "SerialLinkLoop",
    "SocketsClientFactory",
    "SocketsClientLoop",
    "SocketsPair",
    "SocketsServerFactory",
    "SocketsServerLoop",
    "ZenohComms",
    "ZenohCommsFactory",
]
