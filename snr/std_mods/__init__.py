"""Layer 2 of SNR: ready-made components (thesis 6.4).

Sub-packages: ``comms`` (talk between nodes), ``filters``, ``io`` (console,
recorder, replayer, serial, controller) and ``utils`` (timeout, stopwatch,
printer). Students import them from ``snr`` directly.

Example::

    from snr.std_mods import TimeoutLoopFactory
"""

from snr.std_mods.comms import (
    SerialLinkFactory,
    SerialLinkLoop,
)
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
    DEFAULT_JOYSTICK_SCRIPT,
    STEAM_CONTROLLER_BUTTONS,
    STEAM_CONTROLLER_MAPPING,
    ControllerLoop,
    ControllerLoopFactory,
    ControlProcessorEndpoint,
    ControlProcessorFactory,
    InputMappingEndpoint,
    InputMappingFactory,
    Joystick,
    JoystickStep,
    PageReader,
    RecorderEndpoint,
    RecorderEndpointFactory,
    ReplayerLoop,
    ReplayerLoopFactory,
    SimulatedJoystick,
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
    "ControlProcessorEndpoint",
    "ControlProcessorFactory",
    "ControllerLoop",
    "ControllerLoopFactory",
    "DEFAULT_FILTER_LENGTH",
    "DEFAULT_JOYSTICK_SCRIPT",
    "InputMappingEndpoint",
    "InputMappingFactory",
    "Joystick",
    "JoystickStep",
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
    "STEAM_CONTROLLER_BUTTONS",
    "STEAM_CONTROLLER_MAPPING",
    "SerialLinkFactory",
    "SerialLinkLoop",
    "SimulatedJoystick",
    "StopwatchEndpoint",
    "StopwatchEndpointFactory",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
    "TimeoutLoop",
    "TimeoutLoopFactory",
    "format_task",
]
