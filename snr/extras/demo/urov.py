"""The components of the UROV system of thesis listing 5.1, with simulated hardware.

``python -m snr demo`` runs them (see `snr.extras.demo`), and so does
``examples/urov/main.py``. Nobody reading this has the vehicle, so the
hardware is simulated behind the same factories a real robot would use:

* topside: a game controller playing a scripted dive (`XboxControllerFactory`),
  `InputProcessorFactory` turning sticks into surge/yaw/heave commands, and a
  live terminal display of the telemetry (`SensorDisplayEndpointFactory`).
* urov: `ControlsProcessorFactory` mixing commands into thruster speeds,
  `SerialConnectionFactory` sending them as text lines over a serial port to a
  simulated motor board (a pseudo-terminal, exactly as a USB Arduino would
  appear), and `SensorReaderFactory` reading noisy depth and heading sensors.

Data keys, in the order data flows::

    raw_controller_input -> controller_input ==TCP==> controller_input
    -> motor_speed -> serial "M,left,right,vertical" -> motor board -> physics
    -> depth_raw, heading -> (moving average) depth -> sensor_data ==TCP==> display
"""

from __future__ import annotations

import os
import random
import sys
import threading
import time
from typing import Any, Dict, List, Optional, TextIO

from snr import (
    AbstractNode,
    ControllerLoopFactory,
    DataKey,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Page,
    SimulatedJoystick,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
)
from snr.extras.controller import JoystickStep
from snr.prelude.install import install_hint

__all__ = [
    "PILOT_SCRIPT",
    "ControlsProcessorFactory",
    "InputProcessorFactory",
    "MotorBoard",
    "SensorDisplayEndpointFactory",
    "SensorReaderFactory",
    "SerialConnectionFactory",
    "TelemetryFactory",
    "Vehicle",
    "XboxControllerFactory",
    "vehicle",
]

# Stick axes of the controller: left stick X/Y, right stick X/Y (-1 .. 1).
SURGE_AXIS, YAW_AXIS, HEAVE_AXIS = "axis_1", "axis_2", "axis_3"

PILOT_SCRIPT: List[JoystickStep] = [
    # Dive: right stick down (positive Y is "down" on most pads).
    JoystickStep(0.5, HEAVE_AXIS, 0.8),
    JoystickStep(3.0, HEAVE_AXIS, 0.0),
    # Go forward while turning right.
    JoystickStep(3.5, SURGE_AXIS, -0.7),
    JoystickStep(3.5, YAW_AXIS, 0.4),
    JoystickStep(6.5, YAW_AXIS, 0.0),
    # Straight ahead, then turn left and climb a little.
    JoystickStep(8.0, YAW_AXIS, -0.5),
    JoystickStep(8.0, HEAVE_AXIS, -0.4),
    JoystickStep(10.0, YAW_AXIS, 0.0),
    JoystickStep(10.0, HEAVE_AXIS, 0.0),
    JoystickStep(11.0, SURGE_AXIS, 0.0),
]
"""Twelve seconds of stick movements that dive, cruise and turn; then it repeats."""


def _clamp(value: float, low: float = -1.0, high: float = 1.0) -> float:
    return max(low, min(high, value))


# ---------------------------------------------------------------------------
# Topside
# ---------------------------------------------------------------------------
class XboxControllerFactory(ControllerLoopFactory):
    """A game controller: a real pad, or (``simulated=True``) the pilot script."""

    def __init__(self, output_data: DataKey, simulated: bool = True) -> None:
        joystick = (
            SimulatedJoystick(PILOT_SCRIPT, repeat_after_s=12.0, name="Simulated pilot")
            if simulated
            else None
        )
        super().__init__(output_data, joystick=joystick, max_tick_rate_hz=20)


class InputProcessor(Endpoint):
    """Turns raw stick axes into ``{"surge", "yaw", "heave"}`` commands."""

    DEADBAND = 0.08  # sticks never rest exactly at 0

    def __init__(
        self, factory: EndpointFactory, parent: AbstractNode, input: DataKey, output: DataKey
    ) -> None:
        super().__init__(factory, parent, "input_processor")
        self.output = output
        self.task_handlers = {(TaskType.store_page, input): self.process}

    def axis(self, raw: Dict[str, Any], name: str) -> float:
        value = float(raw.get(name, 0.0))
        return 0.0 if abs(value) < self.DEADBAND else round(_clamp(value), 3)

    def process(self, task: Task, key: TaskId) -> SomeTasks:
        raw = task.val_list[0].data
        if not isinstance(raw, dict):
            self.warn("Expected a dict of controller axes, got %r", raw)
            return None
        command = {
            "surge": -self.axis(raw, SURGE_AXIS),  # stick forward is negative Y
            "yaw": self.axis(raw, YAW_AXIS),
            "heave": -self.axis(raw, HEAVE_AXIS),  # stick down means dive
        }
        return self.store_data_task(self.output, command)


class InputProcessorFactory(EndpointFactory):
    """Builds the `InputProcessor` (listing 5.1)."""

    def __init__(self, input: DataKey, output: DataKey) -> None:
        super().__init__(sys.modules[__name__])
        self.input, self.output = input, output

    def get(self, parent: AbstractNode) -> InputProcessor:
        return InputProcessor(self, parent, self.input, self.output)


class SensorDisplay(Endpoint):
    """Shows the latest telemetry: redrawn in place on a terminal, a line a second otherwise."""

    def __init__(
        self, factory: SensorDisplayEndpointFactory, parent: AbstractNode, input: DataKey
    ) -> None:
        super().__init__(factory, parent, "sensor_display")
        self.stream = factory.stream or sys.stdout
        self.live = self.stream.isatty()
        self.period_s = 0.25 if self.live else 1.0
        self.last_shown = -1.0
        self.task_handlers = {(TaskType.store_page, input): self.show}

    def show(self, task: Task, key: TaskId) -> SomeTasks:
        page: Page = task.val_list[0]
        now = self.parent.get_time_s()
        if now - self.last_shown < self.period_s or not isinstance(page.data, dict):
            return None
        self.last_shown = now
        line = self.format(page.data, age_ms=(time.time() - page.created_at_s) * 1000)
        if self.live:
            self.stream.write("\r\x1b[K" + line)
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
        return None

    @staticmethod
    def format(data: Dict[str, Any], age_ms: float) -> str:
        """One line of telemetry, e.g. ``depth  2.41 m | heading  87° | ...``."""
        thrust = data.get("thrusters", {})
        return (
            f"t={data.get('time_s', 0):5.1f} s | depth {data.get('depth_m', 0):5.2f} m | "
            f"heading {data.get('heading_deg', 0):5.1f}° | "
            f"speed {data.get('speed_m_s', 0):4.2f} m/s | "
            f"thrusters L{thrust.get('left', 0):+4d} R{thrust.get('right', 0):+4d} "
            f"V{thrust.get('vertical', 0):+4d} | link {age_ms:4.0f} ms"
        )

    def terminate(self) -> None:
        if self.live:
            self.stream.write("\n")
            self.stream.flush()


class SensorDisplayEndpointFactory(EndpointFactory):
    """Builds the `SensorDisplay` for telemetry stored under ``input``."""

    def __init__(self, input: DataKey, stream: Optional[TextIO] = None) -> None:
        super().__init__(sys.modules[__name__])
        self.input = input
        self.stream = stream

    def get(self, parent: AbstractNode) -> SensorDisplay:
        return SensorDisplay(self, parent, self.input)


# ---------------------------------------------------------------------------
# The simulated vehicle and its motor board
# ---------------------------------------------------------------------------
class Vehicle:
    """Very simple physics of a small ROV: three thrusters, drag, a compass.

    Thruster speeds are percentages (-100 .. 100). Units: metres, seconds, degrees.
    """

    def __init__(self, seed: int = 1) -> None:
        self.lock = threading.Lock()
        self.rng = random.Random(seed)
        self.depth_m = 0.0
        self.heading_deg = 90.0
        self.speed_m_s = 0.0
        self.yaw_rate_deg_s = 0.0
        self.climb_m_s = 0.0
        self.thrusters = {"left": 0, "right": 0, "vertical": 0}

    def set_thrusters(self, left: int, right: int, vertical: int) -> None:
        with self.lock:
            self.thrusters = {"left": left, "right": right, "vertical": vertical}

    def step(self, dt: float) -> None:
        """Advance the physics by ``dt`` seconds."""
        with self.lock:
            left, right = self.thrusters["left"] / 100, self.thrusters["right"] / 100
            vertical = self.thrusters["vertical"] / 100
            self.speed_m_s += (0.8 * (left + right) / 2 - 0.9 * self.speed_m_s) * dt
            self.yaw_rate_deg_s += (60 * (left - right) - 1.5 * self.yaw_rate_deg_s) * dt
            self.climb_m_s += (0.5 * vertical - 1.2 * self.climb_m_s) * dt
            self.heading_deg = (self.heading_deg + self.yaw_rate_deg_s * dt) % 360
            self.depth_m = max(0.0, self.depth_m - self.climb_m_s * dt)

    def read_sensors(self) -> Dict[str, float]:
        """Noisy depth and heading readings, as the real sensors give them."""
        with self.lock:
            return {
                "depth_m": max(0.0, self.depth_m + self.rng.gauss(0, 0.05)),
                "heading_deg": (self.heading_deg + self.rng.gauss(0, 1.0)) % 360,
                "speed_m_s": self.speed_m_s,
            }


class MotorBoard:
    """The microcontroller that drives the thrusters, simulated in a thread.

    It reads lines ``M,<left>,<right>,<vertical>`` (percentages) from its end of
    a serial link and steps the vehicle's physics at 50 Hz. Malformed lines are
    counted and ignored, as firmware should.
    """

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle
        self.bad_lines = 0
        self.commands = 0
        self.port_name: Optional[str] = None
        self._fd: Optional[int] = None
        self._stop = threading.Event()
        self._buffer = b""
        self._threads: List[threading.Thread] = []

    def start(self) -> str:
        """Start the board; returns the serial port name the node should open."""
        if self.port_name is not None:
            return self.port_name
        master, slave = os.openpty()
        self._fd = master
        self.port_name = os.ttyname(slave)
        os.close(slave)  # the node opens it by name, as it would a USB device
        self._threads = [
            threading.Thread(target=self._physics, name="motor-board-physics", daemon=True),
            threading.Thread(target=self._read_serial, name="motor-board-serial", daemon=True),
        ]
        for thread in self._threads:
            thread.start()
        return self.port_name

    def handle_line(self, line: str) -> None:
        """Apply one command line from the serial link."""
        parts = line.strip().split(",")
        try:
            if parts[0] != "M" or len(parts) != 4:
                raise ValueError(line)
            left, right, vertical = (max(-100, min(100, int(p))) for p in parts[1:])
        except ValueError:
            self.bad_lines += 1
            return
        self.commands += 1
        self.vehicle.set_thrusters(left, right, vertical)

    def _physics(self) -> None:
        while not self._stop.wait(0.02):
            self.vehicle.step(0.02)

    def _read_serial(self) -> None:
        import select

        assert self._fd is not None
        while not self._stop.is_set():
            ready, _, _ = select.select([self._fd], [], [], 0.1)
            if not ready:
                continue
            try:
                chunk = os.read(self._fd, 1024)
            except OSError:  # the node closed its end: wait for it to reopen
                self._stop.wait(0.1)
                continue
            self._buffer += chunk
            while b"\n" in self._buffer:
                line, self._buffer = self._buffer.split(b"\n", 1)
                self.handle_line(line.decode("ascii", "replace"))

    def stop(self) -> None:
        """Stop the board's threads and close its end of the link."""
        self._stop.set()
        for thread in self._threads:
            thread.join(1.0)
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        # Ready to start again with a new port, for the next node in this process.
        self.port_name = None
        self._stop = threading.Event()
        self._buffer = b""


vehicle = Vehicle()
"""The one simulated vehicle of this process (the urov node's hardware)."""

motor_board = MotorBoard(vehicle)


# ---------------------------------------------------------------------------
# UROV
# ---------------------------------------------------------------------------
class ControlsProcessor(Endpoint):
    """Mixes surge/yaw/heave commands into three thruster percentages."""

    def __init__(
        self, factory: EndpointFactory, parent: AbstractNode, input: DataKey, output: DataKey
    ) -> None:
        super().__init__(factory, parent, "controls_processor")
        self.output = output
        self.task_handlers = {(TaskType.store_page, input): self.mix}

    def mix(self, task: Task, key: TaskId) -> SomeTasks:
        command = task.val_list[0].data
        if not isinstance(command, dict):
            self.warn("Expected surge/yaw/heave commands, got %r", command)
            return None
        surge = _clamp(float(command.get("surge", 0)))
        yaw = _clamp(float(command.get("yaw", 0)))
        heave = _clamp(float(command.get("heave", 0)))
        speeds = {
            "left": round(100 * _clamp(surge + yaw)),
            "right": round(100 * _clamp(surge - yaw)),
            "vertical": round(100 * heave),
        }
        return self.store_data_task(self.output, speeds)


class ControlsProcessorFactory(EndpointFactory):
    """Builds the `ControlsProcessor` (listing 5.1)."""

    def __init__(self, input: DataKey, output: DataKey) -> None:
        super().__init__(sys.modules[__name__])
        self.input, self.output = input, output

    def get(self, parent: AbstractNode) -> ControlsProcessor:
        return ControlsProcessor(self, parent, self.input, self.output)


class SerialConnection(Endpoint):
    """Writes thruster speeds to the motor board as ``M,left,right,vertical`` lines.

    Uses pyserial when it is installed (``pip install 'snr-robotics[serial]'``); without
    it, the port is opened as a plain file, which works for the simulated board's
    pseudo-terminal, and for a real USB device at the baud rate it already has.
    """

    def __init__(
        self, factory: SerialConnectionFactory, parent: AbstractNode, input: DataKey
    ) -> None:
        super().__init__(factory, parent, "serial_connection")
        self.port_name = factory.port_name
        self.port: Any = None
        self.task_handlers = {(TaskType.store_page, input): self.send}

    def begin(self) -> None:
        # Hardware is opened here, not in __init__: building a component has no
        # side effects, so `python -m snr graph` can build it just to look at it.
        if self.port_name is None:
            self.port_name = motor_board.start()
        simulated = self.port_name == motor_board.port_name
        if simulated:
            self.info(
                "No serial device: the motor board (an Arduino on the real vehicle) is "
                "simulated, listening on the pseudo-terminal %s",
                self.port_name,
            )
        try:
            import serial

            self.port = serial.serial_for_url(self.port_name, baudrate=115200, timeout=0.1)
        except ImportError:
            if not simulated:  # a pseudo-terminal needs no settings; a USB device might
                self.info(
                    "pyserial is not installed (%s), so %s is opened "
                    "as a plain file, at the baud rate it already has",
                    install_hint("serial"),
                    self.port_name,
                )
            self.port = open(self.port_name, "wb", buffering=0)  # noqa: SIM115

    def send(self, task: Task, key: TaskId) -> SomeTasks:
        speeds = task.val_list[0].data
        line = f"M,{speeds['left']},{speeds['right']},{speeds['vertical']}\n"
        self.port.write(line.encode("ascii"))
        return None

    def terminate(self) -> None:
        if self.port is not None:
            self.port.write(b"M,0,0,0\n")  # stop the thrusters before letting go
            self.port.close()
        if self.port_name is not None and self.port_name == motor_board.port_name:
            motor_board.stop()


class SerialConnectionFactory(EndpointFactory):
    """Builds the `SerialConnection`; by default to the simulated motor board."""

    def __init__(self, input: DataKey, port_name: Optional[str] = None) -> None:
        super().__init__(sys.modules[__name__])
        self.input = input
        self.port_name = port_name

    def get(self, parent: AbstractNode) -> SerialConnection:
        return SerialConnection(self, parent, self.input)


class SensorReader(ThreadLoop):
    """Reads the depth and heading sensors ten times a second."""

    def __init__(self, factory: SensorReaderFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sensor_reader", max_tick_rate_hz=10)
        self.output = factory.output

    def loop(self) -> None:
        readings = vehicle.read_sensors()
        depth_m = round(readings["depth_m"], 3)
        heading_deg = round(readings["heading_deg"], 1)
        speed_m_s = round(readings["speed_m_s"], 3)
        self.store_data("depth_raw", depth_m)
        self.store_data("heading", heading_deg)
        self.store_data("speed", speed_m_s)
        if self.output is not None:
            thrusters = self.get_data("motor_speed")
            data = telemetry(self.parent, depth_m, heading_deg, speed_m_s, thrusters)
            self.store_data(self.output, data)


class SensorReaderFactory(LoopFactory):
    """Builds the `SensorReader`.

    Raw readings go to ``depth_raw``, ``heading`` and ``speed``. Given an
    ``output`` key, as in listing 5.1's ``SensorReaderFactory("sensor_data")``,
    the reader also stores them together (unfiltered) as one telemetry page
    under that key, ready for the display.
    """

    def __init__(self, output: Optional[DataKey] = None) -> None:
        super().__init__(sys.modules[__name__])
        self.output = output

    def get(self, parent: AbstractNode) -> SensorReader:
        return SensorReader(self, parent)


def telemetry(
    node: AbstractNode,
    depth_m: float,
    heading_deg: float,
    speed_m_s: float,
    thrusters: Optional[Dict[str, int]],
) -> Dict[str, Any]:
    """One telemetry page's data, as `SensorDisplay` shows it."""
    return {
        "time_s": round(node.get_time_s(), 2),
        "depth_m": depth_m,
        "heading_deg": heading_deg,
        "speed_m_s": speed_m_s,
        "thrusters": thrusters or {"left": 0, "right": 0, "vertical": 0},
    }


class Telemetry(Endpoint):
    """Gathers the latest filtered readings into one ``sensor_data`` page."""

    def __init__(self, factory: TelemetryFactory, parent: AbstractNode, output: DataKey) -> None:
        super().__init__(factory, parent, "telemetry")
        self.output = output
        self.task_handlers = {(TaskType.store_page, "depth"): self.publish}

    def publish(self, task: Task, key: TaskId) -> SomeTasks:
        data = telemetry(
            self.parent,
            round(task.val_list[0].data, 3),
            self.get_data("heading") or 0.0,
            self.get_data("speed") or 0.0,
            self.get_data("motor_speed"),
        )
        return self.store_data_task(self.output, data)


class TelemetryFactory(EndpointFactory):
    """Builds the `Telemetry` endpoint storing under ``output``."""

    def __init__(self, output: DataKey) -> None:
        super().__init__(sys.modules[__name__])
        self.output = output

    def get(self, parent: AbstractNode) -> Telemetry:
        return Telemetry(self, parent, self.output)


def heading_error_deg(a: float, b: float) -> float:
    """The smallest angle between two headings, in degrees."""
    return abs((a - b + 180) % 360 - 180)
