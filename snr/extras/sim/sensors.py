"""What the simulated robot senses, as the pages a real robot would store.

The simulator and a real rover store the same keys, so the code that reads
them cannot tell which one it is driving:

============== =============================================== ===============
key            data                                            a real rover
============== =============================================== ===============
``range``      ``{"angles_deg": [...], "ranges_m": [...]}``    distance sensors
``scan``       the same form, 72 rays all round, 10 a second   a lidar (if given)
``bump``       ``True`` while the bumper touches a wall        bumper switch
``wheel_encoders`` ``{"left_ticks": int, "right_ticks": int}`` wheel encoders
``odometry``   ``{"x": m, "y": m, "theta": rad}`` from ticks   same `Odometry`
``true_pose``  where the robot really is (for grading only)    (none)
``wheel_cmd``  ``{"left": m/s, "right": m/s}``, read by it     motor driver
============== =============================================== ===============

Range sensors measure from the robot's centre along each angle (0 is
straight ahead, +90 its left) and read ``max_range_m`` when they see nothing.
A `ScanSensor` (a lidar, for lesson 3) is stored under ``scan`` only when the
robot is given one; its rays read ``0.0`` for no echo, as a real lidar's do.

Example::

    sensor = RangeSensor(angles_deg=(-90, 0, 90), max_range_m=2.0)
    pages = sensor_pages(robot, world, sensor, Odometry(robot.spec, robot.pose))
    pages["range"]["ranges_m"]      # [0.5, 2.0, 1.2]
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Tuple

from snr.extras.sim.robot import DiffDriveRobot, Pose, RobotSpec
from snr.extras.sim.world import World
from snr.prelude import ComponentError, DataKey

__all__ = [
    "BUMP",
    "ODOMETRY",
    "RANGE",
    "SCAN",
    "TRUE_POSE",
    "WHEEL_CMD",
    "WHEEL_ENCODERS",
    "Odometry",
    "RangeSensor",
    "ScanSensor",
    "sensor_pages",
    "wheel_command",
]

RANGE: DataKey = "range"
SCAN: DataKey = "scan"
BUMP: DataKey = "bump"
WHEEL_ENCODERS: DataKey = "wheel_encoders"
ODOMETRY: DataKey = "odometry"
TRUE_POSE: DataKey = "true_pose"
WHEEL_CMD: DataKey = "wheel_cmd"


@dataclass(frozen=True)
class RangeSensor:
    """A fan of distance sensors (ultrasound, infrared, a tiny lidar).

    Attributes:
        angles_deg: where each ray points, relative to straight ahead;
            positive is to the robot's left.
        max_range_m: the farthest a ray sees; it reads this when it sees nothing.
        noise_m: standard deviation of each reading's (seeded) noise.

    Example::

        RangeSensor(angles_deg=(-90, -45, 0, 45, 90), max_range_m=2.0, noise_m=0.01)
    """

    angles_deg: Tuple[float, ...] = (-90.0, -45.0, 0.0, 45.0, 90.0)
    max_range_m: float = 2.0
    noise_m: float = 0.005

    def __post_init__(self) -> None:
        if not self.angles_deg or not self.max_range_m > 0 or not self.noise_m >= 0:
            raise ComponentError(
                f"RangeSensor(angles_deg={self.angles_deg!r}, max_range_m="
                f"{self.max_range_m!r}, noise_m={self.noise_m!r}): give at least one "
                "angle, a positive range and a noise of 0 or more."
            )

    def read(self, world: World, pose: Pose, rng: random.Random) -> List[float]:
        """One reading per ray: the distance to the nearest wall, with noise.

        Example::

            RangeSensor((0.0,), 5.0, 0.0).read(World.box(4, 3), Pose(1, 1, 0), rng)  # [3.0]
        """
        readings = []
        for angle in self.angles_deg:
            heading = pose.theta + math.radians(angle)
            hit = world.ray_hit_m(pose.x, pose.y, heading, self.max_range_m)
            # Noise is drawn for every ray, hit or not, so the random numbers
            # a run uses never depend on where the robot went.
            noisy = hit + rng.gauss(0.0, self.noise_m) if self.noise_m else hit
            readings.append(min(self.max_range_m, max(0.0, noisy)))
        return readings


@dataclass(frozen=True)
class ScanSensor:
    """A spinning laser scanner (a lidar): many rays all round, a few times a second.

    Its page, ``scan``, has the ``range`` page's form, ``{"angles_deg": [...],
    "ranges_m": [...]}``, but it is raw: `rays` rays evenly spaced all round,
    the first half a step after -180 degrees (so no ray points exactly
    ahead or sideways), each with noise, and a ray that got no echo (nothing
    within `max_range_m`, or the echo lost, one time in `dropout`) reads
    ``0.0``. Where a wall is must be worked out from it: perception.

    Attributes:
        rays: how many rays, all round (72: every 5 degrees).
        max_range_m: the farthest a ray sees.
        noise_m: standard deviation of each reading's (seeded) noise.
        dropout: the chance that a ray's echo is lost, 0 to 1.
        rate_hz: scans a second of simulated time (a real lidar spins 5 to 15 times).

    Example::

        ScanSensor()                        # 72 rays, 4 m, 10 scans a second
        ScanSensor(rays=8).angles_deg()     # [-157.5, -112.5, -67.5, -22.5, 22.5, ...]
    """

    rays: int = 72
    max_range_m: float = 4.0
    noise_m: float = 0.01
    dropout: float = 0.03
    rate_hz: float = 10.0

    def __post_init__(self) -> None:
        if not (
            self.rays >= 1
            and self.max_range_m > 0
            and self.noise_m >= 0
            and 0 <= self.dropout < 1
            and self.rate_hz > 0
        ):
            raise ComponentError(
                f"ScanSensor(rays={self.rays!r}, max_range_m={self.max_range_m!r}, noise_m="
                f"{self.noise_m!r}, dropout={self.dropout!r}, rate_hz={self.rate_hz!r}): give "
                "at least one ray, a positive range and rate, a noise of 0 or more and a "
                "dropout from 0 up to (not including) 1."
            )

    def angles_deg(self) -> List[float]:
        """Each ray's angle from straight ahead, in degrees, positive to the left.

        Example::

            ScanSensor().angles_deg()[:2]    # [-177.5, -172.5]
        """
        step = 360.0 / self.rays
        return [-180.0 + (i + 0.5) * step for i in range(self.rays)]

    def read(self, world: World, pose: Pose, rng: random.Random) -> Dict[str, List[float]]:
        """One scan: the ``scan`` page's data, ranges in millimetres' precision.

        Example::

            ScanSensor(rays=4, noise_m=0, dropout=0).read(World.box(4, 3), Pose(1, 1, 0), rng)
            # {"angles_deg": [-135.0, -45.0, 45.0, 135.0], "ranges_m": [1.414, 1.414, ...]}
        """
        angles = self.angles_deg()
        ranges = []
        for angle in angles:
            heading = pose.theta + math.radians(angle)
            hit = world.ray_hit_m(pose.x, pose.y, heading, self.max_range_m)
            # Two random numbers a ray, echo or not: the numbers a run draws
            # never depend on where the robot went.
            noise, lost = rng.gauss(0.0, self.noise_m), rng.random() < self.dropout
            if lost or hit >= self.max_range_m:
                ranges.append(0.0)
            else:
                ranges.append(round(min(self.max_range_m, max(0.001, hit + noise)), 3))
        return {"angles_deg": angles, "ranges_m": ranges}


class Odometry:
    """Dead reckoning: where the robot thinks it is, from its encoder ticks.

    The same arc as `DiffDriveRobot.step`, but from what the encoders
    counted, not from where the robot really went; wheel slip makes the two
    drift apart. A real rover runs this same class on its own encoder pages.

    Example::

        odometry = Odometry(RobotSpec(), Pose(0.5, 0.5, 0.0))
        odometry.update(2000, 2000)   # both wheels 1 m: 1 m straight on
        odometry.pose.x               # 1.5
    """

    def __init__(self, spec: RobotSpec, start: Pose) -> None:
        self.spec = spec
        self.pose = Pose(start.x, start.y, start.theta)
        self._last_ticks: Optional[Tuple[int, int]] = None

    def update(self, left_ticks: int, right_ticks: int) -> Pose:
        """Move the estimate by the ticks counted since the last update."""
        last_left, last_right = self._last_ticks or (0, 0)
        self._last_ticks = (left_ticks, right_ticks)
        left_m = (left_ticks - last_left) / self.spec.ticks_per_m
        right_m = (right_ticks - last_right) / self.spec.ticks_per_m
        forward = (left_m + right_m) / 2.0
        turn = (right_m - left_m) / self.spec.wheel_base_m
        heading = self.pose.theta + turn / 2.0
        theta = self.pose.theta + turn
        self.pose = Pose(
            self.pose.x + forward * math.cos(heading),
            self.pose.y + forward * math.sin(heading),
            math.atan2(math.sin(theta), math.cos(theta)),
        )
        return self.pose


def sensor_pages(
    robot: DiffDriveRobot,
    world: World,
    range_sensor: Optional[RangeSensor],
    odometry: Odometry,
    rng: Optional[random.Random] = None,
) -> Dict[DataKey, Any]:
    """Everything the robot senses now, as ``{data key: page data}``.

    ``rng`` draws the range noise (the robot's own generator by default).
    Without a ``range_sensor`` (None) there is no ``range`` page.

    Example::

        for key, data in sensor_pages(robot, world, sensor, odometry).items():
            self.store_data(key, data)
    """
    left_ticks, right_ticks = robot.encoder_ticks
    pages: Dict[DataKey, Any] = {}
    if range_sensor is not None:
        pages[RANGE] = {
            "angles_deg": list(range_sensor.angles_deg),
            "ranges_m": range_sensor.read(world, robot.pose, rng or robot.rng),
        }
    return {
        **pages,
        BUMP: robot.bumped,
        WHEEL_ENCODERS: {"left_ticks": left_ticks, "right_ticks": right_ticks},
        ODOMETRY: odometry.update(left_ticks, right_ticks).as_dict(),
        TRUE_POSE: robot.pose.as_dict(),
    }


def wheel_command(data: Any) -> Optional[Tuple[float, float]]:
    """(left, right) in m/s from a ``wheel_cmd`` page's data, or None if it is not one.

    Accepts ``{"left": 0.2, "right": 0.2}`` or a pair ``[0.2, 0.2]``.

    Example::

        wheel_command({"left": 0.2, "right": -0.2})    # (0.2, -0.2): spin right
    """
    if isinstance(data, dict):
        data = (data.get("left"), data.get("right"))
    if isinstance(data, (list, tuple)) and len(data) == 2:
        left, right = data
        numbers = all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in (left, right)
        )
        if numbers and math.isfinite(left) and math.isfinite(right):
            return float(left), float(right)
    return None
