"""A 2-D robot simulator: a differential-drive robot among walls, as pages.

``world`` (walls, the world file), ``robot`` (the physics), ``sensors`` (the
pages it stores), ``draw`` (pygame pictures), ``components`` (the
factories a config lists), ``teleop`` (a controller's stick to wheels),
``main_window`` (the window on the main thread, as macOS requires) and
``clock`` (`SimClock`, simulated time: docs/sim-time.md). Pure Python;
pygame only to draw. Each name is imported on first use (PEP 562), so a
node on a `SimClock` loads neither the world nor the drawing.

Example::

    from snr.extras.sim import SimRobotFactory, SimViewFactory, World

    world = World.box(4.0, 3.0)
    components = {"sim": [SimRobotFactory(world, seed=1), SimViewFactory(world)]}
"""

import importlib
from typing import TYPE_CHECKING, Any, Dict, List

if TYPE_CHECKING:  # loaded on first use (_LAZY); these lines let type checkers see them
    from snr.extras.sim.clock import SimClock
    from snr.extras.sim.components import (
        SimRobotFactory,
        SimRobotLoop,
        SimViewFactory,
        SimViewLoop,
        has_display,
    )
    from snr.extras.sim.main_window import run_in_window
    from snr.extras.sim.robot import DiffDriveRobot, Pose, RobotSpec
    from snr.extras.sim.sensors import (
        BUMP,
        ODOMETRY,
        RANGE,
        SCAN,
        TRUE_POSE,
        WHEEL_CMD,
        WHEEL_ENCODERS,
        Odometry,
        RangeSensor,
        ScanSensor,
        sensor_pages,
        wheel_command,
    )
    from snr.extras.sim.teleop import StickDriveEndpoint, StickDriveFactory
    from snr.extras.sim.world import Segment, World

__all__ = [
    "BUMP",
    "DiffDriveRobot",
    "ODOMETRY",
    "Odometry",
    "Pose",
    "RANGE",
    "RangeSensor",
    "RobotSpec",
    "SCAN",
    "ScanSensor",
    "Segment",
    "SimClock",
    "SimRobotFactory",
    "SimRobotLoop",
    "SimViewFactory",
    "SimViewLoop",
    "StickDriveEndpoint",
    "StickDriveFactory",
    "TRUE_POSE",
    "WHEEL_CMD",
    "WHEEL_ENCODERS",
    "World",
    "has_display",
    "run_in_window",
    "sensor_pages",
    "wheel_command",
]

_LAZY: Dict[str, str] = {
    "clock": "SimClock",
    "components": "SimRobotFactory SimRobotLoop SimViewFactory SimViewLoop has_display",
    "main_window": "run_in_window",
    "robot": "DiffDriveRobot Pose RobotSpec",
    "sensors": (
        "BUMP ODOMETRY RANGE SCAN TRUE_POSE WHEEL_CMD WHEEL_ENCODERS Odometry RangeSensor "
        "ScanSensor sensor_pages wheel_command"
    ),
    "teleop": "StickDriveEndpoint StickDriveFactory",
    "world": "Segment World",
}
"""The names above by module of this package: each is imported the first time it is used."""

_HOME: Dict[str, str] = {name: module for module, names in _LAZY.items() for name in names.split()}


def __getattr__(name: str) -> Any:
    """Import a name of ``__all__`` from its module on first use (PEP 562)."""
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> List[str]:
    return sorted(set(globals()) | set(__all__))
