"""A 2-D robot simulator: a differential-drive robot among walls, as pages.

``world`` (walls, the world file), ``robot`` (the physics), ``sensors`` (the
pages it stores), ``draw`` (pygame pictures), ``components`` (the
factories a config lists), ``teleop`` (a controller's stick to wheels) and
``main_window`` (the window on the main thread, as macOS requires).
Pure Python; pygame only to draw.

Example::

    from snr.extras.sim import SimRobotFactory, SimViewFactory, World

    world = World.box(4.0, 3.0)
    components = {"sim": [SimRobotFactory(world, seed=1), SimViewFactory(world)]}
"""

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
