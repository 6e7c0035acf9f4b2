"""Input and output: console, recorder, replayer, controller.

Example::

    from snr.std_mods.io import RecorderEndpointFactory, ReplayerLoopFactory
"""

from snr.std_mods.io.recorder import RecorderEndpoint, RecorderEndpointFactory
from snr.std_mods.io.replayer import (
    PageReader,
    ReplayerLoop,
    ReplayerLoopFactory,
    TextReader,
    TextReplayerFactory,
    TextReplayerLoop,
)

__all__ = [
    "PageReader",
    "RecorderEndpoint",
    "RecorderEndpointFactory",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
]
