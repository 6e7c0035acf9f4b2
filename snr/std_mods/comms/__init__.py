"""Communication between nodes: pipes, TCP sockets, serial links.

Example::

    from snr.std_mods.comms import SerialLinkFactory
"""

from snr.std_mods.comms.serial_link import SerialLinkFactory, SerialLinkLoop

__all__ = [
    "SerialLinkFactory",
    "SerialLinkLoop",
]
