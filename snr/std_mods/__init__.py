"""Layer 2 of SNR: ready-made components (thesis 6.4).

Sub-packages: ``comms`` (talk between nodes), ``filters``, ``io`` (console,
recorder, replayer, serial, controller) and ``utils`` (timeout, stopwatch,
printer). Students import them from ``snr`` directly.

Example::

    from snr.std_mods import TimeoutLoopFactory
"""

from snr.std_mods.comms import SerialLinkFactory, SerialLinkLoop
from snr.std_mods.filters import (
    DEFAULT_FILTER_LENGTH,
    KalmanFilter,
    KalmanFilterEndpoint,
    KalmanFilterFactory,
    MovingAvgEndpoint,
    MovingAvgFilter,
    MovingAvgFilterFactory,
)
from snr.std_mods.io import (
    PageReader,
    RecorderEndpoint,
    RecorderEndpointFactory,
    ReplayerLoop,
    ReplayerLoopFactory,
    TextReader,
    TextReplayerFactory,
    TextReplayerLoop,
)
from snr.std_mods.utils import (
    PrinterEndpoint,
    PrinterEndpointFactory,
    StopwatchEndpoint,
    StopwatchEndpointFactory,
    TimeoutLoop,
    TimeoutLoopFactory,
    format_task,
)

__all__ = [
    "DEFAULT_FILTER_LENGTH",
    "KalmanFilter",
    "KalmanFilterEndpoint",
    "KalmanFilterFactory",
    "MovingAvgEndpoint",
    "MovingAvgFilter",
    "MovingAvgFilterFactory",
    "PageReader",
    "PrinterEndpoint",
    "PrinterEndpointFactory",
    "RecorderEndpoint",
    "RecorderEndpointFactory",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "SerialLinkFactory",
    "SerialLinkLoop",
    "StopwatchEndpoint",
    "StopwatchEndpointFactory",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
    "TimeoutLoop",
    "TimeoutLoopFactory",
    "format_task",
]
