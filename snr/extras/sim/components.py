"""The simulator as SNR components: `SimRobotFactory` and `SimViewFactory`.

`SimRobotLoop` plays the robot's hardware: each tick it reads the newest
``wheel_cmd`` page, moves the robot one fixed step of simulated time, and
stores what the robot senses under the keys a real robot uses (see
`snr.extras.sim.sensors`). `SimViewLoop` draws those pages: in a window
when there is a screen, into numbered PNG files when there is not, and not
at all (after saying how to get pictures) when pygame is missing.

Swapping the simulated robot for a real one changes the config only: the
real role lists the hardware's components (a `SerialLinkFactory` to the
motor board, say) where the simulated one lists `SimRobotFactory`; the
controller between them is the same object.

Example::

    world = World.load("examples/rover/room.json")
    components = {
        "sim": [SimRobotFactory(world, seed=1), SimViewFactory(world), WandererFactory()],
        "rover": [SerialLinkFactory("/dev/ttyACM0", send_keys=["wheel_cmd"]),
                  WandererFactory()],
    }
"""

from __future__ import annotations

import os
import random
import sys
from pathlib import Path
from typing import Any, List, Literal, Optional, Sequence, Union

from snr.core import LoopFactory, ThreadLoop, tasks
from snr.extras.controller.keyboard import KeyboardJoystick
from snr.extras.sim.draw import (
    NO_PICTURES,
    Scene,
    import_pygame,
    open_window,
    save_png,
    window_closed,
)
from snr.extras.sim.robot import DiffDriveRobot, Pose, RobotSpec
from snr.extras.sim.sensors import (
    RANGE,
    SCAN,
    WHEEL_CMD,
    Odometry,
    RangeSensor,
    ScanSensor,
    sensor_pages,
    wheel_command,
)
from snr.extras.sim.world import World
from snr.prelude import AbstractNode, ComponentError, DataKey

__all__ = ["SimRobotFactory", "SimRobotLoop", "SimViewFactory", "SimViewLoop", "has_display"]


class SimRobotLoop(ThreadLoop):
    """Moves the simulated robot one step per tick and stores its sensor pages.

    Build it with `SimRobotFactory`. The step is always ``1 / rate_hz``
    seconds of simulated time, however late the thread runs, so the physics
    never depends on how busy the computer is.

    Example (the pages one tick stores)::

        Page("range", {"angles_deg": [-90, ...], "ranges_m": [0.4, ...]}, "sim", ...)
        Page("bump", False, ...), Page("wheel_encoders", {...}), Page("odometry", {...}),
        Page("true_pose", {"x": 0.52, "y": 0.5, "theta": 0.0}, ...)
    """

    def __init__(self, factory: SimRobotFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name, max_tick_rate_hz=factory.rate_hz)
        self.sim = factory  # the robot and world live on the factory
        self.dt_s = 1.0 / factory.rate_hz
        self._bad_command_seen = False

    def loop(self) -> None:
        factory = self.sim
        data = self.get_data(WHEEL_CMD)
        command = wheel_command(data)
        if command is not None:
            factory.robot.command(*command)
        elif data is not None and not self._bad_command_seen:
            self._bad_command_seen = True  # once: the page is read 50 times a second
            self.warn(
                "The %r page holds %r, which is not a wheel command; the robot keeps its "
                'last command. Store {"left": m/s, "right": m/s}.',
                WHEEL_CMD,
                data,
            )
        factory.robot.step(self.dt_s, factory.world)
        factory.steps += 1
        for key, value in sensor_pages(
            factory.robot, factory.world, factory.range_sensor, factory.odometry
        ).items():
            self.store_data(key, value)
        scanner = factory.scan_sensor
        if scanner is not None and (factory.steps - 1) % factory.steps_per_scan == 0:
            robot = factory.robot  # a scan on the first step, then every steps_per_scan
            self.store_data(SCAN, scanner.read(factory.world, robot.pose, factory.scan_rng))


class SimRobotFactory(LoopFactory):
    """Builds a `SimRobotLoop`: a simulated differential-drive robot in ``world``.

    The robot (its pose, wheel speeds, encoder counts and random numbers)
    lives on the factory, so a hot reload of the loop carries on where it was.

    Args:
        world: the walls, and the robot's start pose (``world.start``).
        spec: the robot's size, limits and noise (`RobotSpec`).
        range_sensor: its distance sensors (`RangeSensor`; the default's five
            rays if None); False for none: no ``range`` page at all.
        scan_sensor: a lidar (`ScanSensor`), stored under ``scan``; none if None.
        seed: seeds every random number of the run: same seed, same run.
        rate_hz: physics steps per second of simulated time (default 50).
        name: the loop's name (default ``"sim_robot"``).

    Raises:
        ComponentError: the start pose is inside a wall, or the rate is too
            low for the robot's speed (it could pass through walls).

    Example::

        SimRobotFactory(World.box(4, 3), seed=1)
        SimRobotFactory(world, range_sensor=False, scan_sensor=ScanSensor(), seed=1)
    """

    def __init__(
        self,
        world: World,
        spec: Optional[RobotSpec] = None,
        range_sensor: Union[RangeSensor, Literal[False], None] = None,
        seed: int = 0,
        rate_hz: float = 50.0,
        name: Optional[str] = None,
        scan_sensor: Optional[ScanSensor] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        self.world = world
        self.spec = spec or RobotSpec()
        self.range_sensor: Optional[RangeSensor] = (
            None if range_sensor is False else range_sensor or RangeSensor()
        )
        self.scan_sensor = scan_sensor
        self.sensor_keys: List[DataKey] = []
        """The keys of its distance sensors' pages: for ``SimViewFactory(sensor_keys=...)``."""
        if self.range_sensor is not None:
            self.sensor_keys.append(RANGE)
        if scan_sensor is not None:
            self.sensor_keys.append(SCAN)
        # Its own random numbers, so that adding a lidar changes nothing else in a run.
        self.scan_rng = random.Random(f"scan {seed}")
        if not rate_hz > 0 or self.spec.max_wheel_speed_m_s / rate_hz > self.spec.radius_m / 2:
            raise ComponentError(
                f"SimRobotFactory(rate_hz={rate_hz!r}): at {self.spec.max_wheel_speed_m_s} "
                "m/s the robot would move more than half its radius per step and could "
                "pass through a wall. Use a higher rate_hz (50 is the default)."
            )
        self.rate_hz = float(rate_hz)
        self.steps_per_scan = max(1, round(rate_hz / scan_sensor.rate_hz)) if scan_sensor else 1
        x, y, theta = world.start
        if world.clearance_m(x, y) < self.spec.radius_m:
            raise ComponentError(
                f"SimRobotFactory: the robot starts at ({x}, {y}) in world "
                f"{world.name!r}, less than its radius ({self.spec.radius_m} m) from a wall. "
                "Move the world's start pose into open space."
            )
        self.robot = DiffDriveRobot(self.spec, Pose(x, y, theta), seed)
        self.odometry = Odometry(self.spec, self.robot.pose)
        self.steps = 0
        """Physics steps taken so far."""
        self.name = name or "sim_robot"

    def get(self, parent: AbstractNode) -> SimRobotLoop:
        return SimRobotLoop(self, parent)


def has_display() -> bool:
    """True if a window can be opened here (False over ssh, in CI, or with SDL's dummy driver).

    Example::

        SimViewFactory(world, window=has_display())
    """
    if os.environ.get("SDL_VIDEODRIVER") in ("dummy", "offscreen"):
        return False
    platform: str = sys.platform  # a variable: mypy would judge sys.platform statically
    if platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


class SimViewLoop(ThreadLoop):
    """Draws the robot's pages: in a window, or as PNG frames. Build it with `SimViewFactory`.

    It only reads pages (``true_pose``, ``odometry``, ``range``, ``bump``),
    so it draws a real robot's odometry and ranges just as well.

    Example::

        view = SimViewFactory(world, frames_dir="frames", window=False)
        ...                                     # run a node with it
        print(view.frames_written, "frames in", view.frames_dir)
    """

    def __init__(self, factory: SimViewFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name, max_tick_rate_hz=factory.rate_hz)
        self.settings = factory
        self.scene: Optional[Scene] = None
        self.window: Optional[Any] = None

    def setup(self) -> None:
        try:
            pygame = import_pygame()
        except ComponentError:
            self.warn("%s", NO_PICTURES)
            self.set_terminate_flag("no pygame")
            return
        self.scene = self.settings.scene(pygame)
        if self.settings.window:
            # pygame's display belongs to this loop's thread from here on.
            self.window = open_window(pygame, self.scene.view.size_px, self.settings.title)
        else:
            self.info("Drawing the simulator into %s", self.settings.frames_dir)

    def loop(self) -> None:
        scene = self.scene
        if scene is None:
            return
        surface = scene.draw(self.get_data, self.window)
        if self.window is not None:
            scene.pygame.display.flip()
            # The arrow keys / WASD go to the keyboard "controller" (teleop).
            if window_closed(scene.pygame, self.settings.keyboard):
                self.schedule(tasks.terminate("simulator window closed"))
                self.set_terminate_flag("window closed")
        elif self.settings.frames_written < self.settings.max_frames:
            name = f"frame_{self.settings.frames_written:05d}.png"
            save_png(scene.pygame, surface, self.settings.frames_dir / name)
            self.settings.frames_written += 1
            if self.settings.frames_written == self.settings.max_frames:
                self.warn(
                    "Wrote %d frames to %s, the most allowed (max_frames); writing no more.",
                    self.settings.frames_written,
                    self.settings.frames_dir,
                )
        else:
            self.settings.frames_skipped += 1

    def terminate(self) -> None:
        if self.window is not None and self.scene is not None:
            self.scene.pygame.display.quit()
            self.window = None


class SimViewFactory(LoopFactory):
    """Builds a `SimViewLoop`, which draws ``world`` and the robot's pages.

    Args:
        world: the walls to draw (the same `World` the robot drives in).
        frames_dir: where PNG frames go when there is no window (default
            ``sim_frames``), named ``frame_00000.png``, ``frame_00001.png``, ...
        window: True for a window, False for PNG frames; by default a window
            when there is a screen (see `has_display`).
        rate_hz: pictures per second (default 10).
        max_frames: the most PNG files one run writes (default 600, a minute
            at 10 Hz); later frames are counted in ``frames_skipped``.
        width_px: the picture's width; its height follows the world's shape.
        radius_m: the robot's radius, as drawn.
        trail_points: how many of its past positions are drawn as its path.
        sensor_keys: the distance sensors' pages to draw: ``range`` rays, a
            lidar's ``scan`` (a robot's own: its ``sensor_keys``).
            A key nothing stores would be read for nothing (DEBUG mode says so).

    Attributes:
        keyboard: the window's arrow keys / WASD as a `KeyboardJoystick`:
            give it to ``ControllerLoopFactory(joystick=view.keyboard)`` to
            drive the robot from the keyboard (docs/simulator.md, "Drive it
            yourself"). Without a window no key is ever pressed.

    Example::

        SimViewFactory(world)                                   # window if possible
        SimViewFactory(world, frames_dir="frames", window=False)   # PNG frames
        SimViewFactory(world, sensor_keys=sim.sensor_keys)      # what robot `sim` has
    """

    def __init__(
        self,
        world: World,
        frames_dir: Union[str, Path] = "sim_frames",
        window: Optional[bool] = None,
        rate_hz: float = 10.0,
        max_frames: int = 600,
        width_px: int = 640,
        radius_m: float = RobotSpec().radius_m,
        trail_points: int = 1000,
        name: Optional[str] = None,
        sensor_keys: Sequence[DataKey] = (RANGE,),
    ) -> None:
        super().__init__(sys.modules[__name__])
        if not rate_hz > 0 or max_frames < 0 or width_px < 100:
            raise ComponentError(
                f"SimViewFactory(rate_hz={rate_hz!r}, max_frames={max_frames!r}, "
                f"width_px={width_px!r}): the rate must be > 0, max_frames 0 or more and "
                "the width at least 100 pixels."
            )
        self.world = world
        self.frames_dir = Path(frames_dir)
        self.window = has_display() if window is None else window
        self.rate_hz = float(rate_hz)
        self.max_frames = max_frames
        self.width_px = width_px
        self.radius_m = radius_m
        self.trail_points = max(0, trail_points)
        self.name = name or "sim_view"
        self.sensor_keys = list(sensor_keys)
        self.keyboard = KeyboardJoystick()
        # Counted here, on the factory, so they can be read after the run.
        self.frames_written = 0
        """PNG frames written so far."""
        self.frames_skipped = 0
        """Frames not written because ``max_frames`` were already on disk."""

    @property
    def title(self) -> str:
        """The window's title."""
        return f"SNR simulator: {self.world.name}"

    def scene(self, pygame: Any) -> Scene:
        """A `Scene` drawn as these settings say (for a loop, or a window on the main thread)."""
        return Scene(
            pygame, self.world, self.width_px, self.radius_m, self.trail_points, self.sensor_keys
        )

    def get(self, parent: AbstractNode) -> SimViewLoop:
        return SimViewLoop(self, parent)
