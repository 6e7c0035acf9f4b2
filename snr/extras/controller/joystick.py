"""What a game controller looks like to SNR, and a simulated one to test with.

`ControllerLoop` reads any object with the `Joystick` methods: a pygame
joystick (a real pad) or a `SimulatedJoystick`, which plays a script of
button presses and stick moves so that a program runs without hardware.

Example::

    pad = SimulatedJoystick([(0.5, "button_2", 1), (0.7, "button_2", 0)])
    ControllerLoopFactory("raw_controller_input", joystick=pad)
"""

import re
import time
from typing import (
    Any,
    Callable,
    Dict,
    List,
    NamedTuple,
    Optional,
    Protocol,
    Sequence,
    Tuple,
    runtime_checkable,
)

from snr.prelude import ComponentError

__all__ = [
    "DEFAULT_JOYSTICK_SCRIPT",
    "Joystick",
    "JoystickStep",
    "SimulatedJoystick",
    "read_joystick",
]

HatPosition = Tuple[int, int]


@runtime_checkable
class Joystick(Protocol):
    """The methods of a joystick that `ControllerLoop` reads.

    A pygame joystick (``pygame.joystick.Joystick(0)``) has them, and so
    does `SimulatedJoystick`. Write your own to read another device.

    Example::

        class StuckButton:
            def get_name(self) -> str: return "stuck"
            def get_numaxes(self) -> int: return 0
            def get_numbuttons(self) -> int: return 1
            def get_numhats(self) -> int: return 0
            def get_axis(self, axis: int, /) -> float: return 0.0
            def get_button(self, button: int, /) -> int: return 1
            def get_hat(self, hat: int, /) -> Tuple[float, float]: return (0, 0)
    """

    def get_name(self) -> str:
        """The controller's name, e.g. ``"Steam Controller"``."""
        ...

    def get_numaxes(self) -> int:
        """How many axes (stick directions, analog triggers) it has."""
        ...

    def get_numbuttons(self) -> int:
        """How many buttons it has."""
        ...

    def get_numhats(self) -> int:
        """How many hats (d-pads) it has."""
        ...

    def get_axis(self, axis: int, /) -> float:
        """The position of an axis, from -1.0 to 1.0."""
        ...

    def get_button(self, button: int, /) -> int:
        """1 (or True) while the button is held down, else 0."""
        ...

    def get_hat(self, hat: int, /) -> Tuple[float, float]:
        """The (x, y) position of a hat, each -1, 0 or 1."""
        ...


def read_joystick(joystick: Joystick) -> Dict[str, Any]:
    """Every axis, button and hat of ``joystick`` as one dict (listing A.8).

    Keys are ``axis_<n>`` (float), ``button_<n>`` (0 or 1) and ``dhat_<n>``
    (``[x, y]``: a list, not a tuple, so the page looks the same after it
    crossed a socket as JSON).

    Example::

        read_joystick(SimulatedJoystick())
        # {'axis_0': 0.0, ..., 'button_0': 0, ..., 'dhat_0': [0, 0], ...}
    """
    state: Dict[str, Any] = {}
    for axis in range(joystick.get_numaxes()):
        state[f"axis_{axis}"] = float(joystick.get_axis(axis))
    for button in range(joystick.get_numbuttons()):
        state[f"button_{button}"] = int(joystick.get_button(button))
    for hat in range(joystick.get_numhats()):
        x, y = joystick.get_hat(hat)
        state[f"dhat_{hat}"] = [int(x), int(y)]
    return state


class JoystickStep(NamedTuple):
    """One scripted change of a `SimulatedJoystick`.

    Attributes:
        at_s: when, in seconds from the first time the joystick is read.
        control: ``"axis_<n>"``, ``"button_<n>"`` or ``"dhat_<n>"``.
        value: a float in [-1, 1] for an axis, 0 or 1 for a button, an
            ``(x, y)`` pair of -1/0/1 for a hat.

    Example::

        JoystickStep(1.0, "button_2", 1)     # press A on a Steam controller
    """

    at_s: float
    control: str
    value: Any


def _press(at_s: float, button: int, hold_s: float = 0.2) -> List[JoystickStep]:
    control = f"button_{button}"
    return [JoystickStep(at_s, control, 1), JoystickStep(at_s + hold_s, control, 0)]


DEFAULT_JOYSTICK_SCRIPT: Tuple[JoystickStep, ...] = (
    # A, B, X and Y (buttons 2-5 on a Steam controller), as in thesis figure 5.4
    *_press(0.2, 2),
    *_press(0.6, 3),
    *_press(1.0, 4),
    *_press(1.4, 5),
    # left and right trigger clicks
    *_press(1.8, 8),
    *_press(2.2, 9),
    # d-pad up, then back to the middle
    JoystickStep(2.6, "dhat_0", (0, 1)),
    JoystickStep(2.8, "dhat_0", (0, 0)),
    # left stick right, then forward, then let go
    JoystickStep(3.0, "axis_0", 0.5),
    JoystickStep(3.2, "axis_0", 1.0),
    JoystickStep(3.4, "axis_0", 0.0),
    JoystickStep(3.6, "axis_1", -1.0),
    JoystickStep(3.8, "axis_1", 0.0),
)
"""What `SimulatedJoystick` plays when given no script: about 4 s of presses."""

_CONTROL = re.compile(r"(axis|button|dhat)_(\d+)\Z")


class SimulatedJoystick:
    """A pretend game controller that plays a script; no pygame needed.

    It has the `Joystick` methods, so `ControllerLoop` reads it like a real
    pad. The script's clock starts the first time a control is read.
    Its default shape matches the thesis's Steam controller: 4 axes,
    21 buttons and 2 hats.

    Args:
        script: the changes to play, as `JoystickStep` objects or plain
            ``(at_s, control, value)`` tuples; default `DEFAULT_JOYSTICK_SCRIPT`.
        repeat_after_s: start the script again (all controls at rest) this
            many seconds after it started; None plays it once.
        num_axes, num_buttons, num_hats: the controller's shape.
        name: what ``get_name()`` returns.
        clock: seconds as a float; pass your own to control time in tests.

    Example::

        pad = SimulatedJoystick([(0.5, "button_2", 1), (0.7, "button_2", 0)],
                                repeat_after_s=1.0)
        ControllerLoopFactory("raw_controller_input", joystick=pad)
    """

    def __init__(
        self,
        script: Optional[Sequence[Tuple[float, str, Any]]] = None,
        repeat_after_s: Optional[float] = None,
        num_axes: int = 4,
        num_buttons: int = 21,
        num_hats: int = 2,
        name: str = "Simulated Steam Controller",
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.num_axes = num_axes
        self.num_buttons = num_buttons
        self.num_hats = num_hats
        self.name = name
        self.clock = clock
        steps = DEFAULT_JOYSTICK_SCRIPT if script is None else script
        self._script_name = "default script" if script is None else "script"
        self.script = sorted(
            (self._checked_step(i, step) for i, step in enumerate(steps)),
            key=lambda step: step.at_s,
        )
        self.repeat_after_s = self._checked_repeat(repeat_after_s)
        self._cycle_started_at: Optional[float] = None
        self._next_step = 0
        self._axes: List[float] = []
        self._buttons: List[int] = []
        self._hats: List[HatPosition] = []
        self._rest()

    # -- checking the script --------------------------------------------------
    def _checked_step(self, index: int, step: Tuple[float, str, Any]) -> JoystickStep:
        shown = tuple(step) if isinstance(step, tuple) else step  # JoystickStep's repr is long
        where = f"SimulatedJoystick {self._script_name}, step {index} {shown!r}"
        try:
            at_s, control, value = step
        except (TypeError, ValueError):
            raise ComponentError(
                f"{where} is not an (at_s, control, value) triple. Write steps like "
                '(0.5, "button_2", 1).'
            ) from None
        if not isinstance(at_s, (int, float)) or at_s < 0:
            raise ComponentError(f"{where}: at_s must be a time in seconds, 0 or more.")
        kind, _ = self._parse_control(where, control)
        return JoystickStep(float(at_s), control, self._checked_value(where, kind, value))

    def _parse_control(self, where: str, control: Any) -> Tuple[str, int]:
        match = _CONTROL.match(control) if isinstance(control, str) else None
        if match is None:
            raise ComponentError(
                f"{where}: {control!r} names no control. Use 'axis_<n>', 'button_<n>' "
                "or 'dhat_<n>', e.g. 'button_2'."
            )
        kind, number = match.group(1), int(match.group(2))
        count = {"axis": self.num_axes, "button": self.num_buttons, "dhat": self.num_hats}[kind]
        if number >= count:
            plural = {"axis": "axes", "button": "buttons", "dhat": "hats"}[kind]
            fix = (
                "Pass script=[...] with steps for this joystick's controls"
                if self._script_name == "default script"
                else f"Fix the number, or pass num_{plural}=... to give the joystick more"
            )
            raise ComponentError(
                f"{where}: this joystick has {count} {plural}"
                + (f" (numbered 0 to {count - 1})" if count else "")
                + f", so {control!r} does not exist. {fix}."
            )
        return kind, number

    @staticmethod
    def _checked_value(where: str, kind: str, value: Any) -> Any:
        if kind == "axis" and _is_number(value) and -1.0 <= value <= 1.0:
            return float(value)
        if kind == "button" and isinstance(value, (bool, int, float)) and value in (0, 1):
            return int(value)
        if (
            kind == "dhat"
            and isinstance(value, (tuple, list))
            and len(value) == 2
            and all(v in (-1, 0, 1) and _is_number(v) for v in value)
        ):
            return (int(value[0]), int(value[1]))
        expected = {
            "axis": "a number from -1.0 to 1.0",
            "button": "0 (released) or 1 (pressed)",
            "dhat": "an (x, y) pair, each -1, 0 or 1",
        }[kind]
        raise ComponentError(f"{where}: the value for an {kind} must be {expected}.")

    def _checked_repeat(self, repeat_after_s: Optional[float]) -> Optional[float]:
        if repeat_after_s is None:
            return None
        last = self.script[-1].at_s if self.script else 0.0
        if repeat_after_s <= 0 or repeat_after_s <= last:
            raise ComponentError(
                f"SimulatedJoystick(repeat_after_s={repeat_after_s}): the script's last "
                f"step is at {last} s, so repeat_after_s must be later than that (or None "
                "to play the script once)."
            )
        return float(repeat_after_s)

    # -- playing the script ---------------------------------------------------
    def _rest(self) -> None:
        self._axes = [0.0] * self.num_axes
        self._buttons = [0] * self.num_buttons
        self._hats = [(0, 0)] * self.num_hats

    def _apply(self, step: JoystickStep) -> None:
        kind, number = step.control.rsplit("_", 1)
        if kind == "axis":
            self._axes[int(number)] = step.value
        elif kind == "button":
            self._buttons[int(number)] = step.value
        else:
            self._hats[int(number)] = step.value

    def _advance(self) -> None:
        """Apply every step that is due by now."""
        now = self.clock()
        if self._cycle_started_at is None:
            self._cycle_started_at = now
        elapsed = now - self._cycle_started_at
        period = self.repeat_after_s
        if period is not None and elapsed >= period:
            cycles = int(elapsed // period)
            self._cycle_started_at += cycles * period
            elapsed -= cycles * period
            self._next_step = 0
            self._rest()
        while self._next_step < len(self.script) and self.script[self._next_step].at_s <= elapsed:
            self._apply(self.script[self._next_step])
            self._next_step += 1

    def restart(self) -> None:
        """Play the script from the start again, all controls at rest."""
        self._cycle_started_at = None
        self._next_step = 0
        self._rest()

    @property
    def finished(self) -> bool:
        """True once a script that does not repeat has played every step."""
        if self.repeat_after_s is None and self._cycle_started_at is not None:
            self._advance()
        return self.repeat_after_s is None and self._next_step >= len(self.script)

    # -- the Joystick methods -------------------------------------------------
    def get_name(self) -> str:
        """The name given to the constructor."""
        return self.name

    def get_numaxes(self) -> int:
        """How many axes it has."""
        return self.num_axes

    def get_numbuttons(self) -> int:
        """How many buttons it has."""
        return self.num_buttons

    def get_numhats(self) -> int:
        """How many hats it has."""
        return self.num_hats

    def get_axis(self, axis: int, /) -> float:
        """The scripted position of ``axis`` now."""
        self._advance()
        return self._axes[axis]

    def get_button(self, button: int, /) -> int:
        """1 while the script holds ``button`` down, else 0."""
        self._advance()
        return self._buttons[button]

    def get_hat(self, hat: int, /) -> Tuple[float, float]:
        """The scripted (x, y) position of ``hat`` now."""
        self._advance()
        return self._hats[hat]

    def __repr__(self) -> str:
        return (
            f"SimulatedJoystick({len(self.script)} steps, {self.num_axes} axes, "
            f"{self.num_buttons} buttons, {self.num_hats} hats)"
        )


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
