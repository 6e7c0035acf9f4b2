"""Input and output: console, recorder, replayer.

The controller, the live view and MCAP files are extras: ``snr.extras.controller``
and ``snr.extras.viz``.

Example::

    from snr.std_mods.io import RecorderEndpointFactory, ReplayerLoopFactory
"""

from snr.std_mods.io.command_processor import (
    CommandProcessorEndpoint,
)
from snr.std_mods.io.command_receiver import (
    CommandReceiverFactory,
    CommandReceiverLoop,
)
from snr.std_mods.io.console_protocol import (
    DEFAULT_CONSOLE_PORT,
)
from snr.std_mods.io.recorder import (
    RecorderEndpoint,
    RecorderEndpointFactory,
)
from snr.std_mods.io.remote_console import (
    RemoteConsole,
)
from snr.std_mods.io.replayer import (
    PageReader,
    ReplayerLoop,
    ReplayerLoopFactory,
    TextReader,
    TextReplayerFactory,
    TextReplayerLoop,
)

__all__ = [
    "CommandProcessorEndpoint",
    "CommandReceiverFactory",
    "CommandReceiverLoop",
    "DEFAULT_CONSOLE_PORT",
    "PageReader",
    "RecorderEndpoint",
    "RecorderEndpointFactory",
    "RemoteConsole",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
]
