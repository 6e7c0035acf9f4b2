"""Input and output: console, recorder, replayer, controller.

Example::

    from snr.std_mods.io import ControllerLoopFactory, SimulatedJoystick
"""

from snr.std_mods.io.control_processor import (
    STEAM_CONTROLLER_BUTTONS,
    ControlProcessorEndpoint,
    ControlProcessorFactory,
)
from snr.std_mods.io.controller import (
    ControllerLoop,
    ControllerLoopFactory,
)
from snr.std_mods.io.input_mapping import (
    STEAM_CONTROLLER_MAPPING,
    InputMappingEndpoint,
    InputMappingFactory,
)
from snr.std_mods.io.joystick import (
    DEFAULT_JOYSTICK_SCRIPT,
    Joystick,
    JoystickStep,
    SimulatedJoystick,
)
from snr.std_mods.io.recorder import (
    RecorderEndpoint,
    RecorderEndpointFactory,
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
    "ControlProcessorEndpoint",
    "ControlProcessorFactory",
    "ControllerLoop",
    "ControllerLoopFactory",
    "DEFAULT_JOYSTICK_SCRIPT",
    "InputMappingEndpoint",
    "InputMappingFactory",
    "Joystick",
    "JoystickStep",
    "PageReader",
    "RecorderEndpoint",
    "RecorderEndpointFactory",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "STEAM_CONTROLLER_BUTTONS",
    "STEAM_CONTROLLER_MAPPING",
    "SimulatedJoystick",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
]
