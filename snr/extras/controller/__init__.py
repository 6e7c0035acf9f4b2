"""Game controllers and the keyboard as input (thesis listings A.6 to A.11).

pygame reads a real controller: ``pip install 'snr-robotics[controller]'``. A
`SimulatedJoystick` needs nothing. ``controller`` reads it
(`ControllerLoopFactory`), ``joystick`` is what a controller looks like,
``keyboard`` the arrow keys of a pygame window, ``input_mapping`` names its
controls, ``control_processor`` turns button changes into events.

Example::

    from snr.extras.controller import ControllerLoopFactory, SimulatedJoystick

    components = {"topside": [ControllerLoopFactory(joystick=SimulatedJoystick())]}
"""

from snr.extras.controller.control_processor import (
    STEAM_CONTROLLER_BUTTONS,
    ControlProcessorEndpoint,
    ControlProcessorFactory,
)
from snr.extras.controller.controller import ControllerLoop, ControllerLoopFactory
from snr.extras.controller.input_mapping import (
    STEAM_CONTROLLER_MAPPING,
    InputMappingEndpoint,
    InputMappingFactory,
)
from snr.extras.controller.joystick import (
    DEFAULT_JOYSTICK_SCRIPT,
    Joystick,
    JoystickStep,
    SimulatedJoystick,
)
from snr.extras.controller.keyboard import KeyboardJoystick

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
    "KeyboardJoystick",
    "STEAM_CONTROLLER_BUTTONS",
    "STEAM_CONTROLLER_MAPPING",
    "SimulatedJoystick",
]
