"""ControllerLoop on real pygame, headless (SDL's dummy drivers, no screen or sound).

The no-controller test runs wherever pygame is installed. The end-to-end test
plugs in a virtual pad through SDL's own virtual-joystick API (the SDL library
pygame has loaded, reached with ctypes), so pygame sees a real device whose
buttons the test presses; it skips where that library cannot be found.
"""

from __future__ import annotations

import ctypes
import importlib
import os
import sys
import unittest
from typing import Any, Dict, Optional

os.environ["SDL_VIDEODRIVER"] = "dummy"  # before pygame is imported
os.environ["SDL_AUDIODRIVER"] = "dummy"
os.environ["PYGAME_HIDE_SUPPORT_PROMPT"] = "1"

from snr import (
    AbstractNode,
    ControllerLoopFactory,
    ControlProcessorFactory,
    ExpectorEndpointFactory,
    InputMappingFactory,
    LoopFactory,
    Node,
    SNRTestCase,
    TaskType,
    ThreadLoop,
)
from snr.prelude import ComponentError
from tests.optional import reason

try:
    pygame: Any = importlib.import_module("pygame")
except ImportError:
    pygame = None

SDL_JOYSTICK_TYPE_GAMECONTROLLER = 1


def loaded_sdl_library() -> Optional[ctypes.CDLL]:
    """The SDL2 library this process has loaded for pygame, or None."""
    if pygame is None or not sys.platform.startswith("linux"):
        return None
    with open("/proc/self/maps", encoding="utf-8") as maps:
        paths = {line.split()[-1] for line in maps if "libSDL2-2" in line or "libSDL2.so" in line}
    paths = {p for p in paths if "SDL2_" not in os.path.basename(p)}  # not SDL2_image etc.
    if len(paths) != 1:
        return None
    sdl = ctypes.CDLL(paths.pop())
    if not hasattr(sdl, "SDL_JoystickAttachVirtual"):  # SDL older than 2.0.14
        return None
    sdl.SDL_JoystickAttachVirtual.restype = ctypes.c_int
    sdl.SDL_JoystickAttachVirtual.argtypes = [ctypes.c_int] * 4
    sdl.SDL_JoystickDetachVirtual.argtypes = [ctypes.c_int]
    sdl.SDL_JoystickOpen.restype = ctypes.c_void_p
    sdl.SDL_JoystickOpen.argtypes = [ctypes.c_int]
    sdl.SDL_JoystickClose.argtypes = [ctypes.c_void_p]
    sdl.SDL_JoystickSetVirtualButton.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint8]
    sdl.SDL_JoystickSetVirtualAxis.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int16]
    return sdl


class VirtualPad:
    """A Steam-controller-shaped pad plugged into SDL for the length of a test."""

    def __init__(self, sdl: ctypes.CDLL) -> None:
        self.sdl = sdl
        self.index = sdl.SDL_JoystickAttachVirtual(SDL_JOYSTICK_TYPE_GAMECONTROLLER, 4, 21, 2)
        if self.index < 0:
            raise unittest.SkipTest("SDL refused to attach a virtual joystick")
        self.handle = sdl.SDL_JoystickOpen(self.index)

    def set_button(self, button: int, pressed: bool) -> None:
        self.sdl.SDL_JoystickSetVirtualButton(self.handle, button, int(pressed))

    def set_axis(self, axis: int, value: int) -> None:
        self.sdl.SDL_JoystickSetVirtualAxis(self.handle, axis, value)

    def unplug(self) -> None:
        if self.handle:
            self.sdl.SDL_JoystickClose(self.handle)
            self.handle = None
            self.sdl.SDL_JoystickDetachVirtual(self.index)


class PadPresserLoop(ThreadLoop):
    """Presses and releases A on the virtual pad once the node has seen each step."""

    def __init__(self, factory: PadPresserFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pad_presser", max_tick_rate_hz=100)
        self.pad = factory.pad
        self.step = 0

    def loop(self) -> None:
        named = self.get_data("controller_data")
        if named is None:
            return  # the controller loop has not stored its first state yet
        if self.step == 0:
            self.pad.set_axis(0, 16384)
            self.pad.set_button(2, True)  # A on a Steam controller
            self.step = 1
        elif self.step == 1 and named.get("A") == 1:
            self.pad.set_button(2, False)
            self.step = 2


class PadPresserFactory(LoopFactory):
    def __init__(self, pad: VirtualPad) -> None:
        super().__init__()
        self.pad = pad

    def get(self, parent: AbstractNode) -> PadPresserLoop:
        return PadPresserLoop(self, parent)


@unittest.skipUnless(pygame is not None, reason("pygame"))
class TestControllerLoopOnPygame(SNRTestCase):
    def setUp(self) -> None:
        # Leave pygame as each test found it: stopped.
        self.addCleanup(pygame.display.quit)
        self.addCleanup(pygame.joystick.quit)

    def test_no_controller_is_a_clear_error(self) -> None:
        pygame.joystick.init()
        if pygame.joystick.get_count() != 0:
            self.skipTest("a game controller is connected to this machine")
        pygame.joystick.quit()
        with self.assertRaises(ComponentError) as caught:
            Node("test", self.get_config([ControllerLoopFactory("raw_controller_input")]))
        message = str(caught.exception)
        self.assertIn("No game controller found", message)
        self.assertIn("SimulatedJoystick()", message)
        self.assertFalse(pygame.joystick.get_init(), "pygame was left running")
        self.assertFalse(pygame.display.get_init(), "pygame was left running")

    def test_virtual_pad_end_to_end(self) -> None:
        sdl = loaded_sdl_library()
        if sdl is None:
            self.skipTest("cannot reach the SDL library pygame loaded")
        pygame.display.init()
        pygame.joystick.init()  # SDL's joystick system must be up to attach a pad
        pad = VirtualPad(sdl)
        self.addCleanup(pad.unplug)
        pressed, released = (TaskType.event, "button_pressed"), (TaskType.event, "button_released")
        with self.expector({pressed: 1, released: 1}) as expector:
            node = self.run_test_node(
                [
                    ControllerLoopFactory("raw", joystick_index=pad.index, max_tick_rate_hz=100),
                    InputMappingFactory("raw", "controller_data"),
                    ControlProcessorFactory("controller_data"),
                    PadPresserFactory(pad),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ],
                timeout_s=5,
            )
        raw: Dict[str, Any] = node.get_data("raw") or {}
        self.assertEqual(len(raw), 4 + 21 + 2)
        self.assertAlmostEqual(raw["axis_0"], 0.5, places=3)
        self.assertEqual((raw["button_2"], raw["dhat_1"]), (0, [0, 0]))
        self.assertEqual((node.get_data("controller_data") or {}).get("A"), 0)

    def test_unplugged_pad_stops_the_loop_with_a_message(self) -> None:
        sdl = loaded_sdl_library()
        if sdl is None:
            self.skipTest("cannot reach the SDL library pygame loaded")
        pygame.display.init()
        pygame.joystick.init()
        pad = VirtualPad(sdl)
        self.addCleanup(pad.unplug)
        node = Node(
            "test", self.get_config([ControllerLoopFactory("raw", joystick_index=pad.index)])
        )
        loop = node.components["controller_loop"]
        assert isinstance(loop, ThreadLoop)
        pad.unplug()
        with self.assertLogs("snr", "ERROR") as logs:
            loop.setup()
            for _ in range(50):  # the removal event arrives within a pass or two
                loop.loop()
                if loop.is_terminated():
                    break
        self.assertTrue(loop.is_terminated())
        self.assertIn("was unplugged", logs.output[0])
        node.terminate()


if __name__ == "__main__":
    unittest.main()
