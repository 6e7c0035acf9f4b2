"""A small rover, simulated or real: the role you run chooses which.

Run it in the simulator (a window if you have a screen, else PNG frames in
``sim_frames/``)::

    python examples/rover/main.py sim --seconds 20

or drive the simulated rover yourself with the arrow keys (or WASD) of its
window::

    python examples/rover/main.py drive

or drive a real rover whose microcontroller, on a serial port, reads
``wheel_cmd`` pages and writes ``range``, ``bump`` and ``wheel_encoders``
pages (one JSON page per line, see docs/serial.md)::

    python examples/rover/main.py rover --port /dev/ttyACM0

The two roles list the same brain, `WandererFactory`: it reads the
``range`` page and stores ``wheel_cmd``, and cannot tell which robot it
drives. Only what stands between it and the wheels differs.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import List, Optional

import snr
from snr import AbstractNode, Endpoint, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr.extras.sim import StickDriveFactory

HERE = os.path.dirname(os.path.abspath(__file__))

CRUISE_M_S = 0.3
"""Speed on open ground."""
TURN_M_S = 0.15
"""Wheel speed while turning on the spot."""
CLEAR_M = 0.45
"""Closer than this ahead, stop and turn."""


class WandererEndpoint(Endpoint):
    """Drives forward; turns on the spot towards open space when something is ahead.

    Example (a range page in, a wheel command out)::

        {"angles_deg": [-90, -45, 0, 45, 90], "ranges_m": [1, 1, 0.3, 1, 2]}
        -> {"left": -0.15, "right": 0.15}     # turn left: more room there
    """

    def __init__(self, factory: WandererFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "wanderer")
        self.task_handlers = {(TaskType.store_page, "range"): self.steer}

    def steer(self, task: Task, key: TaskId) -> SomeTasks:
        """One wheel command for one range reading."""
        reading = task.val_list[0].data
        angles, ranges = reading["angles_deg"], reading["ranges_m"]
        ahead = min(r for a, r in zip(angles, ranges) if abs(a) <= 45)
        left = min(r for a, r in zip(angles, ranges) if a > 0)
        right = min(r for a, r in zip(angles, ranges) if a < 0)
        if ahead < CLEAR_M:
            # Turn on the spot, towards the side with more room.
            turn = TURN_M_S if left > right else -TURN_M_S
            return self.store_data_task("wheel_cmd", {"left": -turn, "right": turn})
        # Open ground: drive on, edging away from the nearer side.
        steer = 0.05 if left > right else -0.05
        return self.store_data_task(
            "wheel_cmd", {"left": CRUISE_M_S - steer, "right": CRUISE_M_S + steer}
        )


class WandererFactory(EndpointFactory):
    """Builds a `WandererEndpoint`.

    Example::

        WandererFactory()
    """

    def __init__(self, name: Optional[str] = None) -> None:
        super().__init__()
        self.name = name or "wanderer"

    def get(self, parent: AbstractNode) -> WandererEndpoint:
        return WandererEndpoint(self, parent)


def make_components(
    seconds: Optional[float] = None, port: str = "/dev/ttyACM0", seed: int = 1
) -> snr.ComponentsByRole:
    """The components of each role: ``sim`` (simulated robot), ``drive`` (the same,
    driven from the keyboard) and ``rover`` (a real one)."""
    world = snr.World.load(os.path.join(HERE, "room.json"))
    stop = [snr.TimeoutLoopFactory(seconds=seconds)] if seconds else []
    view = snr.SimViewFactory(world)
    return {
        "sim": [
            snr.SimRobotFactory(world, seed=seed),
            snr.SimViewFactory(world),
            WandererFactory(),
            *stop,
        ],
        "drive": [  # the teleop path of a game controller, fed by the window's keys
            snr.SimRobotFactory(world, seed=seed),
            view,
            snr.ControllerLoopFactory("raw_controller_input", joystick=view.keyboard),
            snr.InputMappingFactory("raw_controller_input", "controller_input"),
            StickDriveFactory("controller_input"),
            *stop,
        ],
        "rover": [
            snr.SerialLinkFactory(port, 115200, send_keys=["wheel_cmd"], mode="pages"),
            WandererFactory(),
            *stop,
        ],
    }


def main(argv: List[str]) -> None:
    """Parse this example's options; the role goes to ``snr.CliRunner``."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--port", default="/dev/ttyACM0")
    parser.add_argument("--seed", type=int, default=1)
    options, rest = parser.parse_known_args(argv[1:])
    components = make_components(options.seconds, options.port, options.seed)
    snr.CliRunner(components, [argv[0], *rest]).run()


if __name__ == "__main__":
    main(sys.argv)
