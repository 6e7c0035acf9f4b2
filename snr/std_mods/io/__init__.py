"""Input and output: console, recorder, replayer, controller.

Example::

    from snr.std_mods.io import ControllerLoopFactory, SimulatedJoystick
"""

from snr.std_mods.io.control_processor import (
    STEAM_CONTROLLER_BUTTONS,
    ControlProcessorEndpoint,
    ControlProcessorFactory,
)
from snr.std_mods.io.controller import ControllerLoop, ControllerLoopFactory
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

__all__ = [
    "DEFAULT_JOYSTICK_SCRIPT",
    "STEAM_CONTROLLER_BUTTONS",
    "STEAM_CONTROLLER_MAPPING",
    "ControlProcessorEndpoint",
    "ControlProcessorFactory",
    "ControllerLoop",
    "ControllerLoopFactory",
    "InputMappingEndpoint",
    "InputMappingFactory",
    "Joystick",
    "JoystickStep",
    "SimulatedJoystick",
]
