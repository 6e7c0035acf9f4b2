"""Input and output: console, recorder, replayer, controller, live view.

Example::

    from snr.std_mods.io import ControllerLoopFactory, SimulatedJoystick
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
from snr.std_mods.io.keyboard import (
    KeyboardJoystick,
)
from snr.std_mods.io.live_view import (
    FoxgloveBridge,
    FoxgloveBridgeFactory,
)
from snr.std_mods.io.local_console import (
    LocalConsole,
    LocalConsoleFactory,
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
    "ControlProcessorEndpoint",
    "ControlProcessorFactory",
    "ControllerLoop",
    "ControllerLoopFactory",
    "DEFAULT_CONSOLE_PORT",
    "DEFAULT_JOYSTICK_SCRIPT",
    "FoxgloveBridge",
    "FoxgloveBridgeFactory",
    "InputMappingEndpoint",
    "InputMappingFactory",
    "Joystick",
    "JoystickStep",
    "KeyboardJoystick",
    "LocalConsole",
    "LocalConsoleFactory",
    "PageReader",
    "RecorderEndpoint",
    "RecorderEndpointFactory",
    "RemoteConsole",
    "ReplayerLoop",
    "ReplayerLoopFactory",
    "STEAM_CONTROLLER_BUTTONS",
    "STEAM_CONTROLLER_MAPPING",
    "SimulatedJoystick",
    "TextReader",
    "TextReplayerFactory",
    "TextReplayerLoop",
]
