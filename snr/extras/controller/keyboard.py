"""`KeyboardJoystick`: the arrow keys (or WASD) of a pygame window as a game controller.

It has the `Joystick` methods, so `ControllerLoopFactory(joystick=keys)`
reads it like a pad and stores the same ``raw_controller_input`` pages; the
rest of the teleop path (`InputMappingFactory`, then whatever drives the
wheels) cannot tell the difference. The keys act as the left stick:

=================  ==========  =================================
key                control     value while held
=================  ==========  =================================
Up / W             ``axis_1``  -1.0 (a stick pushed forward reads -1)
Down / S           ``axis_1``  +1.0
Left / A           ``axis_0``  -1.0
Right / D          ``axis_0``  +1.0
Space              ``button_2`` 1 (``"A"`` in `STEAM_CONTROLLER_MAPPING`)
=================  ==========  =================================

Only the window's own thread may read its events, so the window's code
passes them on with `KeyboardJoystick.handle`; ``SimViewLoop`` does that for
its window (``SimViewFactory(...).keyboard``). Losing the window's focus
lets go of every key, so a robot never drives on after the key-up was missed.

Example::

    keys = KeyboardJoystick()
    ControllerLoopFactory("raw_controller_input", joystick=keys)
    ...
    for event in pygame.event.get():      # in the code that owns the window
        keys.handle(event)
"""

from __future__ import annotations

import sys
import threading
from typing import Any, Dict, Optional, Set, Tuple

__all__ = ["KEYBOARD_BUTTON", "KeyboardJoystick"]

KEYBOARD_BUTTON = 2
"""The button Space presses: ``button_2``, which the Steam mapping names ``"A"``."""

# What each key does, by pygame's name for its key code.
_KEY_CONTROLS: Dict[str, Tuple[str, float]] = {
    "K_UP": ("axis_1", -1.0),
    "K_w": ("axis_1", -1.0),
    "K_DOWN": ("axis_1", 1.0),
    "K_s": ("axis_1", 1.0),
    "K_LEFT": ("axis_0", -1.0),
    "K_a": ("axis_0", -1.0),
    "K_RIGHT": ("axis_0", 1.0),
    "K_d": ("axis_0", 1.0),
    "K_SPACE": ("button", 1.0),
}


class KeyboardJoystick:
    """A two-axis, one-button "controller" whose stick is the arrow keys or WASD.

    Safe to share between threads: the window's thread calls `handle`, the
    controller loop's thread reads the axes.

    Example::

        keys = KeyboardJoystick()
        keys.press("K_UP")
        keys.get_axis(1)            # -1.0: forward, as a pad's stick
        keys.release_all()
        keys.get_axis(1)            # 0.0
    """

    def __init__(self, name: str = "Keyboard (arrow keys / WASD)") -> None:
        self.name = name
        self._held: Set[str] = set()
        self._lock = threading.Lock()
        self._codes: Optional[Dict[int, str]] = None  # pygame key code -> name, on first use

    # -- fed by the window's thread -----------------------------------------------
    def handle(self, event: Any) -> bool:
        """Take a pygame event; True if it was one of the teleop keys (or a focus loss).

        Other events are left to the window's code.
        """
        pygame = sys.modules.get("pygame")  # an event means pygame is loaded
        if pygame is None:
            return False
        if event.type == pygame.WINDOWFOCUSLOST:  # its key-ups would go elsewhere
            self.release_all()
            return True
        if event.type not in (pygame.KEYDOWN, pygame.KEYUP):
            return False
        name = self._key_names(pygame).get(getattr(event, "key", None) or 0)
        if name is None:
            return False
        if event.type == pygame.KEYDOWN:
            self.press(name)
        else:
            self.release(name)
        return True

    def press(self, key: str) -> None:
        """Hold ``key`` (pygame's name, e.g. ``"K_UP"``) down."""
        if key not in _KEY_CONTROLS:
            raise ValueError(f"{key!r} is not a teleop key; they are {', '.join(_KEY_CONTROLS)}.")
        with self._lock:
            self._held.add(key)

    def release(self, key: str) -> None:
        """Let go of ``key``."""
        with self._lock:
            self._held.discard(key)

    def release_all(self) -> None:
        """Let go of every key (the window lost the focus, or closed)."""
        with self._lock:
            self._held.clear()

    def _key_names(self, pygame: Any) -> Dict[int, str]:
        if self._codes is None:
            self._codes = {getattr(pygame, name): name for name in _KEY_CONTROLS}
        return self._codes

    # -- the Joystick methods, read by the controller loop's thread ---------------
    def get_name(self) -> str:
        """The name `ControllerLoop` logs."""
        return self.name

    def get_numaxes(self) -> int:
        """Two: ``axis_0`` (left/right) and ``axis_1`` (forward/back)."""
        return 2

    def get_numbuttons(self) -> int:
        """Three, so that Space can be ``button_2`` ("A"); 0 and 1 are never pressed."""
        return KEYBOARD_BUTTON + 1

    def get_numhats(self) -> int:
        """None."""
        return 0

    def get_axis(self, axis: int, /) -> float:
        """-1.0, 0.0 or 1.0; opposite keys held together cancel out."""
        control = f"axis_{axis}"
        with self._lock:
            held = list(self._held)
        return sum(value for c, value in (_KEY_CONTROLS[k] for k in held) if c == control)

    def get_button(self, button: int, /) -> int:
        """1 while Space is held, for ``button_2``; else 0."""
        with self._lock:
            return int(button == KEYBOARD_BUTTON and "K_SPACE" in self._held)

    def get_hat(self, hat: int, /) -> Tuple[float, float]:
        """Never called: there are no hats."""
        raise IndexError(f"KeyboardJoystick has no hat {hat}")
