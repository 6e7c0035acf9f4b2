"""`DiffDriveRobot`: a two-wheeled robot's motion, step by step.

A differential-drive robot (a Roomba, most classroom rovers) has two driven
wheels on one axle. Driving both at the same speed goes straight; driving
them at different speeds turns. Each `DiffDriveRobot.step`:

1. moves each wheel's speed towards its command, no faster than the motor's
   acceleration limit (a real motor cannot jump to full speed);
2. turns the wheels, and counts encoder ticks for what they turned;
3. adds wheel slip (seeded random noise), so the robot really moves a little
   more or less than the wheels say: this is why odometry drifts;
4. moves the robot along the arc the two wheels trace;
5. stops it at a wall it would drive into, and sets ``bumped``.

Every random number comes from one `random.Random` seeded at the start, so
the same seed and the same commands give exactly the same run.

Example::

    robot = DiffDriveRobot(RobotSpec(), Pose(0.5, 0.5, 0.0), seed=1)
    robot.command(0.2, 0.2)                # both wheels 0.2 m/s: straight on
    for _ in range(50):
        robot.step(0.02, world)            # one second of driving
    robot.pose.x                           # about 0.7 (it sped up first)
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import Dict, Tuple

from snr.extras.sim.world import World
from snr.prelude import ComponentError

__all__ = ["Pose", "RobotSpec", "DiffDriveRobot"]

CONTACT_M = 0.002
"""A wall this close to the robot's edge (2 mm) presses the bumper."""


@dataclass
class Pose:
    """Where the robot is: x and y in metres, heading ``theta`` in radians.

    ``theta`` is 0 facing +x and grows anticlockwise (pi/2 faces +y).

    Example::

        Pose(1.0, 2.0, math.pi / 2)    # at (1, 2), facing +y
    """

    x: float
    y: float
    theta: float

    def as_dict(self) -> Dict[str, float]:
        """The pose as page data: ``{"x": ..., "y": ..., "theta": ...}``.

        Example::

            Pose(1.0, 2.0, 0.0).as_dict()    # {'x': 1.0, 'y': 2.0, 'theta': 0.0}
        """
        return {"x": self.x, "y": self.y, "theta": self.theta}


@dataclass(frozen=True)
class RobotSpec:
    """What kind of robot: size, motor limits, sensors' resolution and noise.

    The defaults are a small classroom rover.

    Attributes:
        radius_m: the robot is a circle this big (its bumper).
        wheel_base_m: distance between the two wheels.
        max_wheel_speed_m_s: commands above this are clipped.
        max_wheel_accel_m_s2: how fast a wheel can change speed.
        slip: standard deviation of wheel slip, as a fraction of the distance
            the wheel turned (0.02: 2 %); 0 for a perfect robot.
        ticks_per_m: encoder ticks per metre a wheel rolls.

    Example::

        RobotSpec(max_wheel_speed_m_s=1.0, slip=0.0)    # faster, no slip
    """

    radius_m: float = 0.1
    wheel_base_m: float = 0.18
    max_wheel_speed_m_s: float = 0.5
    max_wheel_accel_m_s2: float = 1.0
    slip: float = 0.02
    ticks_per_m: float = 2000.0

    def __post_init__(self) -> None:
        for name in ("radius_m", "wheel_base_m", "max_wheel_speed_m_s", "max_wheel_accel_m_s2"):
            if not getattr(self, name) > 0:
                raise ComponentError(f"RobotSpec({name}={getattr(self, name)!r}) must be > 0.")
        if not 0 <= self.slip < 0.5 or not self.ticks_per_m > 0:
            raise ComponentError(
                f"RobotSpec(slip={self.slip!r}, ticks_per_m={self.ticks_per_m!r}): slip "
                "is a fraction from 0 to 0.5 and ticks_per_m must be > 0."
            )


def _towards(current: float, target: float, max_change: float) -> float:
    """``current`` moved towards ``target`` by at most ``max_change``."""
    return current + max(-max_change, min(max_change, target - current))


class DiffDriveRobot:
    """A differential-drive robot's true state, moved by `step`.

    Attributes:
        pose: where it really is (the simulator's "ground truth").
        wheel_speeds_m_s: (left, right) speeds the wheels turn at now.
        encoder_ticks: (left, right) ticks counted since the start.
        bumped: True while the bumper touches a wall.

    Example::

        robot = DiffDriveRobot(RobotSpec(), Pose(0.5, 0.5, 0.0), seed=1)
        robot.command(-0.1, 0.1)          # spin anticlockwise on the spot
        robot.step(0.02, World.box(4, 3))
    """

    def __init__(self, spec: RobotSpec, pose: Pose, seed: int = 0) -> None:
        self.spec = spec
        self.pose = pose
        self.rng = random.Random(seed)
        self.target_m_s: Tuple[float, float] = (0.0, 0.0)
        self.wheel_speeds_m_s: Tuple[float, float] = (0.0, 0.0)
        self.encoder_ticks: Tuple[int, int] = (0, 0)
        # Encoders count whole ticks; keep the fractions so none are lost.
        self._wheel_travel_m = [0.0, 0.0]
        self.bumped = False
        # Distance from the centre to the nearest wall, kept from the last step.
        self._clearance_m = math.inf

    def command(self, left_m_s: float, right_m_s: float) -> None:
        """Ask for wheel speeds; values beyond the motors' limit are clipped.

        Example::

            robot.command(0.3, 0.1)    # curve to the right
        """
        limit = self.spec.max_wheel_speed_m_s
        self.target_m_s = (
            max(-limit, min(limit, float(left_m_s))),
            max(-limit, min(limit, float(right_m_s))),
        )

    def step(self, dt_s: float, world: World) -> None:
        """Advance the robot ``dt_s`` seconds in ``world``.

        Raises:
            ComponentError: ``dt_s`` is so long that at full speed the robot
                would move more than half its radius in one step, and could
                jump through a thin wall. Use shorter steps.
        """
        spec = self.spec
        if not 0 < dt_s * spec.max_wheel_speed_m_s <= spec.radius_m / 2:
            raise ComponentError(
                f"DiffDriveRobot.step(dt_s={dt_s!r}): at {spec.max_wheel_speed_m_s} m/s "
                "the robot would move more than half its radius in one step and could "
                "pass through a wall. Step more often (a smaller dt_s)."
            )
        # 1. Motors accelerate towards their command, within their limit.
        max_change = spec.max_wheel_accel_m_s2 * dt_s
        left = _towards(self.wheel_speeds_m_s[0], self.target_m_s[0], max_change)
        right = _towards(self.wheel_speeds_m_s[1], self.target_m_s[1], max_change)
        self.wheel_speeds_m_s = (left, right)
        # 2. What the wheels turned: this is what the encoders see.
        turned_left, turned_right = left * dt_s, right * dt_s
        # 3. Slip: the ground moves a little more or less than the wheel turned.
        #    Drawn on every step, moving or not, so a run's random numbers
        #    never depend on timing.
        slip_left = 1.0 + self.rng.gauss(0.0, spec.slip) if spec.slip else 1.0
        slip_right = 1.0 + self.rng.gauss(0.0, spec.slip) if spec.slip else 1.0
        moved_left, moved_right = turned_left * slip_left, turned_right * slip_right
        # 4. The arc: forward by the mean of the wheels, turn by their difference.
        forward = (moved_left + moved_right) / 2.0
        turn = (moved_right - moved_left) / spec.wheel_base_m
        # Moving along the mid-step heading is exact enough for short steps.
        mid_heading = self.pose.theta + turn / 2.0
        new_x = self.pose.x + forward * math.cos(mid_heading)
        new_y = self.pose.y + forward * math.sin(mid_heading)
        # 5. Walls: drive only as far as the bumper allows. Blocked part way,
        #    the robot makes that part of the whole move (turn included), and
        #    the encoders count only that part: the wheels stall, as on a real
        #    rover whose bumper cuts its motors.
        fraction, clearance = self._free_fraction(world, new_x, new_y)
        if fraction < 1.0:
            self.wheel_speeds_m_s = (0.0, 0.0)
            new_x = self.pose.x + fraction * (new_x - self.pose.x)
            new_y = self.pose.y + fraction * (new_y - self.pose.y)
            clearance = world.clearance_m(new_x, new_y)
        self.pose = Pose(new_x, new_y, _wrap(self.pose.theta + fraction * turn))
        self._clearance_m = clearance
        self._count_ticks(turned_left * fraction, turned_right * fraction)
        self.bumped = clearance <= spec.radius_m + CONTACT_M

    def _free_fraction(self, world: World, new_x: float, new_y: float) -> Tuple[float, float]:
        """How much of the move to (new_x, new_y) is clear of walls (0 to 1), and the
        clearance at (new_x, new_y)."""
        # A robot placed overlapping a wall may still back away from it.
        radius = min(self.spec.radius_m, self._clearance_m)
        clearance = world.clearance_m(new_x, new_y)
        if clearance >= radius:
            return 1.0, clearance
        # Bisection: the largest fraction of the move that keeps the robot's
        # circle off every wall. 12 halvings is well under a millimetre.
        x0, y0 = self.pose.x, self.pose.y
        low, high = 0.0, 1.0
        for _ in range(12):
            middle = (low + high) / 2.0
            x, y = x0 + middle * (new_x - x0), y0 + middle * (new_y - y0)
            if world.clearance_m(x, y) >= radius:
                low = middle
            else:
                high = middle
        return low, clearance

    def _count_ticks(self, turned_left_m: float, turned_right_m: float) -> None:
        self._wheel_travel_m[0] += turned_left_m
        self._wheel_travel_m[1] += turned_right_m
        per_m = self.spec.ticks_per_m
        self.encoder_ticks = (
            math.floor(self._wheel_travel_m[0] * per_m),
            math.floor(self._wheel_travel_m[1] * per_m),
        )


def _wrap(angle: float) -> float:
    """``angle`` in (-pi, pi]: headings that differ by a full turn are the same."""
    return math.atan2(math.sin(angle), math.cos(angle))
