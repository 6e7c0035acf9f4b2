"""Zenoh: comms between many nodes on one network, and the console over Zenoh.

Needs ``pip install 'snr-robotics[zenoh]'`` (eclipse-zenoh). ``comms`` publishes
pages by key (`ZenohCommsFactory`), ``inbox`` hands samples to the node's
thread, ``console`` reaches any node by its role (``snr-console --zenoh``,
found by the kernel through the entry point ``snr.console_transports``).

Example::

    from snr.extras.zenoh import ZenohCommsFactory

    components = {"urov": [ZenohCommsFactory("team7", publish=["depth_m"])]}
"""

from snr.extras.zenoh.comms import ZenohComms, ZenohCommsFactory

__all__ = ["ZenohComms", "ZenohCommsFactory"]
