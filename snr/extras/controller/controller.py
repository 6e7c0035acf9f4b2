"""`ControllerLoop`: read a game controller with pygame (listings A.8, A.9).

The loop publishes the controller's raw state, a dict such as
``{"axis_0": 0.5, ..., "button_3": 1, ..., "dhat_0": [0, 1]}``, each time
something changes. `InputMappingFactory` turns the numbered controls into
names, `ControlProcessorFactory` turns button changes into events.

pygame is optional (``pip install 'snr-robotics[controller]'``) and only imported when
a loop opens a real controller; a `SimulatedJoystick` needs no pygame. pygame-ce,
which is imported as ``pygame`` too, works the same.

Example::

    components = {"input_device": [
        ControllerLoopFactory("raw_controller_input"),                   # a real pad
        # ControllerLoopFactory("raw_controller_input",
        #                       joystick=SimulatedJoystick()),          # or a pretend one
        InputMappingFactory("raw_controller_input", "controller_input"),
    ]}
"""

from __future__ import annotations

import importlib
import os
import sys
from types import ModuleType
from typing import Any, Dict, List, Optional, Tuple

from snr.core import LoopFactory, ThreadLoop
from snr.extras.controller.joystick import Joystick, read_joystick
from snr.prelude import AbstractNode, ComponentError, DataKey
from snr.prelude.install import install_hint

__all__ = ["ControllerLoop", "ControllerLoopFactory"]

_INSTALL_HINT = (
    f"Install it with `{install_hint('controller')}`, or with `pip install pygame` or "
    "`pip install pygame-ce`: either works, both are imported as pygame, and pygame-ce "
    "has wheels for Python 3.14 (on Raspberry Pi OS: `sudo apt install python3-pygame`)"
)
_SIMULATE_HINT = (
    "To run without a controller, give the loop a pretend one: "
    "ControllerLoopFactory(..., joystick=SimulatedJoystick())"
)


def _import_pygame() -> ModuleType:
    """pygame, imported only now; a clear ComponentError when it is missing."""
    # pygame prints a two-line banner on import unless told not to.
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        return importlib.import_module("pygame")
    except ImportError as error:
        raise ComponentError(
            "ControllerLoop needs pygame to read a game controller, but pygame is not "
            f"installed. {_INSTALL_HINT}. {_SIMULATE_HINT}."
        ) from error


def _start_pygame(pygame: Any) -> List[Any]:
    """Start the pygame parts a controller needs; returns those this call started.

    Joystick events only flow once pygame's display module is up, but no
    window is opened. With no screen at all, SDL's "dummy" video driver
    stands in.
    """
    started: List[Any] = []
    if not pygame.display.get_init():
        if sys.platform.startswith("linux") and not (
            os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
        ):
            # A robot reached over ssh has no screen: skip SDL's search for one.
            os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        try:
            pygame.display.init()
        except pygame.error as error:
            raise ComponentError(
                f"pygame could not start its display module, which it needs to deliver "
                f"controller events: {error}. With no screen, run with the environment "
                "variable SDL_VIDEODRIVER=dummy (no window is opened either way)."
            ) from error
        started.append(pygame.display)
    if not pygame.joystick.get_init():
        pygame.joystick.init()
        started.append(pygame.joystick)
    return started


def _open_pygame_joystick(pygame: Any, index: int, log: Any) -> Any:
    """Open joystick ``index``; "No controller found" is a clear ComponentError."""
    started = _start_pygame(pygame)
    count = pygame.joystick.get_count()
    if index >= count or index < 0:
        for module in reversed(started):  # leave pygame as we found it
            module.quit()
        found = (
            "No game controller found"
            if count == 0
            else (
                f"Controller number {index} not found: only {count} controller(s) are "
                f"connected, numbered 0 to {count - 1}"
            )
        )
        raise ComponentError(
            f"{found}. Plug one in (or pair it and switch it on), then check that "
            "`ls /dev/input/js*` lists it and that your user may read it: add yourself "
            "to the 'input' group (`sudo usermod -aG input $USER`, then log in again) "
            f"rather than running as root. {_SIMULATE_HINT}."
        )
    joysticks = [pygame.joystick.Joystick(i) for i in range(count)]
    log.info("Found joysticks: %s", [j.get_name() for j in joysticks])
    joystick = joysticks[index]
    joystick.init()
    return joystick


def _is_pygame_joystick(joystick: Joystick) -> bool:
    pygame = sys.modules.get("pygame")
    joystick_type = getattr(getattr(pygame, "joystick", None), "JoystickType", None)
    return isinstance(joystick_type, type) and isinstance(joystick, joystick_type)


class ControllerLoop(ThreadLoop):
    """Stores a game controller's axes, buttons and hats whenever they change.

    The first pass stores the state at rest, so whoever reads the data has
    something to compare the next change against. Build it with
    `ControllerLoopFactory`.

    Example (a page it stores)::

        Page("raw_controller_input",
             {"axis_0": 0.0, ..., "button_2": 1, ..., "dhat_0": [0, 0], ...}, ...)
    """

    def __init__(
        self,
        factory: ControllerLoopFactory,
        parent: AbstractNode,
        output_data: DataKey,
        joystick: Optional[Joystick],
        joystick_index: int,
        max_tick_rate_hz: float,
    ) -> None:
        super().__init__(factory, parent, factory.name, max_tick_rate_hz=max_tick_rate_hz)
        self.output_data = output_data
        self.last_state: Optional[Dict[str, Any]] = None
        # pygame only updates a joystick while its events are being read, so
        # the loop reads them when (and only when) the joystick is pygame's.
        self.pygame: Optional[Any] = None
        self.opened_here = joystick is None
        if joystick is None:
            self.pygame = _import_pygame()
            joystick = _open_pygame_joystick(self.pygame, joystick_index, self.log)
        elif _is_pygame_joystick(joystick):
            self.pygame = sys.modules["pygame"]
        self.joystick: Joystick = joystick

    def setup(self) -> None:
        """Say which controller is used and what it has."""
        self.info(
            "Using joystick: %s with %d axes and %d buttons and %d d pads",
            self.joystick.get_name(),
            self.joystick.get_numaxes(),
            self.joystick.get_numbuttons(),
            self.joystick.get_numhats(),
        )

    def loop(self) -> None:
        """Store the controller's state if it changed since the last pass."""
        if self.pygame is not None and not self.pygame_events_ok():
            return
        state = read_joystick(self.joystick)
        if state != self.last_state:
            self.last_state = state
            self.store_data(self.output_data, state)

    def pygame_events_ok(self) -> bool:
        """Read pygame's joystick events; False (and stop) on unplug or quit."""
        pygame = self.pygame
        assert pygame is not None
        # Take only joystick events: a window's events belong to its own code.
        events = pygame.event.get([
            pygame.JOYAXISMOTION, pygame.JOYBALLMOTION, pygame.JOYHATMOTION,
            pygame.JOYBUTTONUP, pygame.JOYBUTTONDOWN,
            pygame.JOYDEVICEADDED, pygame.JOYDEVICEREMOVED,
        ])  # fmt: skip
        my_id = getattr(self.joystick, "get_instance_id", lambda: None)()
        for event in events:
            if event.type == pygame.JOYDEVICEREMOVED and event.instance_id == my_id:
                self.err(
                    "Controller %r was unplugged, so loop %r stops. Plug it back in "
                    "and restart the node.",
                    self.joystick.get_name(),
                    self.name,
                )
                self.set_terminate_flag("controller unplugged")
                return False
        if pygame.event.peek(pygame.QUIT):  # peek: leave it for the window's code
            self.set_terminate_flag("pygame quit")
            return False
        return True

    def terminate(self) -> None:
        """Let go of a controller this loop opened.

        pygame itself stays up: a window, or the loop a hot reload builds,
        may still use it, and pygame shuts itself down when Python exits.
        """
        if self.opened_here:
            quit_joystick = getattr(self.joystick, "quit", None)
            if quit_joystick is not None:
                quit_joystick()


class ControllerLoopFactory(LoopFactory):
    """Builds a `ControllerLoop` (thesis listing A.9).

    Args:
        output_data: the data key to store the raw state under.
        joystick: what to read; None (default) opens a real controller with
            pygame, or pass a `SimulatedJoystick` (or any `Joystick`).
        joystick_index: which connected controller to open (0: the first).
        max_tick_rate_hz: how often to read the controller (listing A.8: 20).
        name: the loop's name (default ``"controller_loop"``).

    Raises:
        ComponentError: when the node is built, if pygame is missing or no
            controller is connected; the message says what to do.

    Example::

        ControllerLoopFactory("raw_controller_input")
        ControllerLoopFactory("raw_controller_input", joystick=SimulatedJoystick())
    """

    def __init__(
        self,
        output_data: DataKey = "raw_controller_input",
        joystick: Optional[Joystick] = None,
        joystick_index: int = 0,
        max_tick_rate_hz: float = 20.0,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        missing = _missing_joystick_methods(joystick) if joystick is not None else ()
        if missing:
            raise ComponentError(
                f"ControllerLoopFactory(joystick={joystick!r}): that object lacks the "
                f"joystick method(s) {', '.join(missing)}. Pass a SimulatedJoystick, a "
                "pygame joystick, or an object with every method of snr.Joystick."
            )
        self.output_data = output_data
        self.joystick = joystick
        self.joystick_index = joystick_index
        self.max_tick_rate_hz = max_tick_rate_hz
        self.name = name or "controller_loop"

    def get(self, parent: AbstractNode) -> ControllerLoop:
        return ControllerLoop(
            self,
            parent,
            self.output_data,
            self.joystick,
            self.joystick_index,
            self.max_tick_rate_hz,
        )


def _missing_joystick_methods(obj: object) -> Tuple[str, ...]:
    wanted = ("get_name", "get_numaxes", "get_numbuttons", "get_numhats",
              "get_axis", "get_button", "get_hat")  # fmt: skip
    return tuple(name for name in wanted if not callable(getattr(obj, name, None)))
