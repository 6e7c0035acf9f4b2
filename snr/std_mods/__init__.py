"""Layer 2 of SNR: ready-made components (thesis 6.4).

Sub-packages: ``comms`` (talk between nodes), ``filters``, ``io`` (console,
recorder, replayer, serial, controller) and ``utils`` (timeout, stopwatch,
printer). Students import them from ``snr`` directly.

Example::

    from snr.std_mods import TimeoutLoopFactory
"""

from snr.std_mods.comms import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    CommsLoop,
    PipeLoop,
    PipeLoopFactory,
    SocketsClientFactory,
    SocketsClientLoop,
    SocketsPair,
    SocketsServerFactory,
    SocketsServerLoop,
)
from snr.std_mods.filters import (
    DEFAULT_FILTER_LENGTH,
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
    SimulatedJoystick,
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
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "CommsLoop",
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
    "MovingAvgEndpoint",
    "MovingAvgFilter",
    "MovingAvgFilterFactory",
    "PipeLoop",
    "PipeLoopFactory",
    "PrinterEndpoint",
    "PrinterEndpointFactory",
    "STEAM_CONTROLLER_BUTTONS",
    "STEAM_CONTROLLER_MAPPING",
    "SimulatedJoystick",
    "SocketsClientFactory",
    "SocketsClientLoop",
    "SocketsPair",
    "SocketsServerFactory",
    "SocketsServerLoop",
    "StopwatchEndpoint",
    "StopwatchEndpointFactory",
    "TimeoutLoop",
    "TimeoutLoopFactory",
    "format_task",
]
