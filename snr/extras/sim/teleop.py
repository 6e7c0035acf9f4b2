"""`StickDriveFactory`: drive a two-wheeled robot with a controller's stick.

The last step of the teleop path: a controller (a pad, or the keyboard as
``KeyboardJoystick``) is read by `ControllerLoopFactory`, named by
`InputMappingFactory`, and this endpoint turns the named stick into a
``wheel_cmd`` page, which the simulated robot (or a real one's motor board)
reads::

    ControllerLoop ─raw_controller_input→ InputMapping ─controller_input→
        StickDrive ─wheel_cmd→ SimRobotLoop

Stick forward (a pad's Y reads -1 pushed forward) drives both wheels
forward; stick right slows the right wheel and speeds the left one, so the
robot turns right.

Example::

    view = SimViewFactory(world)
    components = {"sim": [
        SimRobotFactory(world), view,
        ControllerLoopFactory("raw_controller_input", joystick=view.keyboard),
        InputMappingFactory("raw_controller_input", "controller_input"),
        StickDriveFactory("controller_input"),
    ]}
"""

from __future__ import annotations

import sys
from typing import Any, Dict, Optional

from snr.core import Endpoint, EndpointFactory
from snr.extras.controller.input_mapping import stored_dict
from snr.extras.sim.sensors import WHEEL_CMD
from snr.prelude import AbstractNode, ComponentError, DataKey, SomeTasks, Task, TaskId, TaskType

__all__ = ["StickDriveEndpoint", "StickDriveFactory"]


class StickDriveEndpoint(Endpoint):
    """Stores a ``wheel_cmd`` for each named controller page. Build it with `StickDriveFactory`.

    Example (a page in, a page out, with the default speeds)::

        {"left_stick_X": 0.0, "left_stick_Y": -1.0}  ->  {"left": 0.3, "right": 0.3}
        {"left_stick_X": 1.0, "left_stick_Y": 0.0}   ->  {"left": 0.15, "right": -0.15}
    """

    def __init__(self, factory: StickDriveFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.settings = factory
        self.task_handlers = {(TaskType.store_page, factory.input_data): self.drive}
        self.produces = [factory.output_data]

    def drive(self, task: Task, key: TaskId) -> SomeTasks:
        """One wheel command from the stick's position."""
        controls = stored_dict(task)
        if controls is None:
            self.warn("Ignoring %s: expected a dict of named controls.", task)
            return None
        return self.store_data_task(self.settings.output_data, self.wheels(controls))

    def wheels(self, controls: Dict[str, Any]) -> Dict[str, float]:
        """``{"left": m/s, "right": m/s}`` for the stick in ``controls`` (missing: centred)."""
        settings = self.settings
        # 0.0 - ...: a centred stick gives 0.0, not -0.0.
        forward = 0.0 - _axis(controls.get(settings.forward_axis)) * settings.max_speed_m_s
        turn = _axis(controls.get(settings.turn_axis)) * settings.turn_speed_m_s
        return {"left": forward + turn, "right": forward - turn}


def _axis(value: Any) -> float:
    """A stick axis as a float from -1 to 1 (anything else: centred)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return max(-1.0, min(1.0, float(value)))
    return 0.0


class StickDriveFactory(EndpointFactory):
    """Builds a `StickDriveEndpoint`: a named stick in, ``wheel_cmd`` out.

    Args:
        input_data: the key of the named controller data (`InputMappingFactory`'s output).
        output_data: the key of the wheel command (default ``wheel_cmd``).
        max_speed_m_s: both wheels' speed with the stick fully forward.
        turn_speed_m_s: what a full sideways stick adds to one wheel and takes
            from the other.
        forward_axis: the control for forward/back (default ``left_stick_Y``).
        turn_axis: the control for turning (default ``left_stick_X``).
        name: the endpoint's name (default ``"stick_drive"``).

    Example::

        StickDriveFactory("controller_input", max_speed_m_s=0.2)
    """

    def __init__(
        self,
        input_data: DataKey = "controller_input",
        output_data: DataKey = WHEEL_CMD,
        max_speed_m_s: float = 0.3,
        turn_speed_m_s: float = 0.15,
        forward_axis: str = "left_stick_Y",
        turn_axis: str = "left_stick_X",
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        if not max_speed_m_s >= 0 or not turn_speed_m_s >= 0:
            raise ComponentError(
                f"StickDriveFactory(max_speed_m_s={max_speed_m_s!r}, turn_speed_m_s="
                f"{turn_speed_m_s!r}): speeds are 0 or more, in metres per second."
            )
        self.input_data = input_data
        self.output_data = output_data
        self.max_speed_m_s = float(max_speed_m_s)
        self.turn_speed_m_s = float(turn_speed_m_s)
        self.forward_axis = forward_axis
        self.turn_axis = turn_axis
        self.name = name or "stick_drive"

    def get(self, parent: AbstractNode) -> StickDriveEndpoint:
        return StickDriveEndpoint(self, parent)
