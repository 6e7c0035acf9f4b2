"""A robot, a laptop and a logger over Zenoh: three machines, one program.

Every machine runs this same file with its own role (README.md says what to
type on each)::

    python team.py robot  --listen tcp/0.0.0.0:7447
    python team.py laptop --listen tcp/0.0.0.0:7447 --connect tcp/192.168.1.10:7447
    python team.py logger --connect tcp/192.168.1.10:7447 --connect tcp/192.168.1.11:7447

* ``robot`` drives back and forth on a track in front of a wall (simulated),
  publishes its sensors (``sensors/range``, ``sensors/battery``) five times a
  second, obeys the drive commands (``commands/drive``) and says what it does
  in ``robot/status``. When the laptop leaves, the robot stops.
* ``laptop`` sends a drive command five times a second (a fixed plan:
  forward, stop, back, stop) and prints the robot's telemetry once a second.
* ``logger`` records every page of the team, the robot's and the laptop's,
  to a JSON-lines file (``team_log.jsonl``; replay it with
  `ReplayerLoopFactory`).

On one machine, without endpoints (the nodes find each other by multicast),
all three at once: ``python team.py robot laptop logger``. Needs Zenoh:
``pip install -e '.[zenoh]'`` in a checkout of SNR.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any, List, Optional, Sequence, Tuple

from snr import (
    COMMS_DISCONNECTED,
    AbstractFactory,
    AbstractNode,
    CliRunner,
    ComponentsByRole,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    RecorderEndpointFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    ZenohCommsFactory,
)

__all__ = [
    "COMMAND",
    "PLAN",
    "SENSORS",
    "STATUS",
    "DriverFactory",
    "LogCounterFactory",
    "PilotFactory",
    "RobotBodyFactory",
    "TelemetryFactory",
    "make_components",
    "parse_options",
    "planned_speed",
]

# The keys the team shares. Zenoh carries each under snr/<system>/<key>.
COMMAND = "commands/drive"
"""The laptop's drive command: ``{"n": 12, "speed_m_s": 0.25}`` (n counts commands)."""
SENSORS = ["sensors/range", "sensors/battery"]
"""The robot's sensors: metres to the wall ahead, battery volts."""
STATUS = "robot/status"
"""What the robot does and why: ``{"speed_m_s": 0.25, "command": 12, "why": "..."}``."""

RATE_HZ = 5.0
"""How often the robot measures and the laptop sends a command."""
START_RANGE_M = 2.0
"""The robot starts this far from the wall."""
FULL_BATTERY_V = 12.6
PLAN: List[Tuple[float, float]] = [(2.0, 0.25), (1.0, 0.0), (2.0, -0.25), (1.0, 0.0)]
"""The laptop's drive plan, repeated: (seconds, speed in m/s; negative is backwards)."""


# -- the robot ----------------------------------------------------------------------------
class Driver(Endpoint):
    """Obeys the laptop's drive commands; stops when the laptop leaves.

    Each command is answered with a ``robot/status`` page, so the laptop (and
    the logger) see which command the robot obeys. The body (`RobotBody`)
    reads that page to move.

    Example (a command in, the status out)::

        commands/drive {"n": 12, "speed_m_s": 0.25}
        -> robot/status {"speed_m_s": 0.25, "command": 12, "why": "command #12 from laptop"}
    """

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "driver")
        self.task_handlers = {
            (TaskType.store_page, COMMAND): self.obey,
            (TaskType.event, COMMS_DISCONNECTED): self.peer_left,
        }

    def obey(self, task: Task, key: TaskId) -> SomeTasks:
        """Drive at the commanded speed (printed when it changes)."""
        page = task.val_list[0]
        speed = float(page.data["speed_m_s"])
        why = f"command #{page.data['n']} from {page.origin}"
        return self.drive(speed, page.data["n"], why)

    def peer_left(self, task: Task, key: TaskId) -> SomeTasks:
        """A robot whose driver has gone stops (values: [comms name, the other's role])."""
        if task.val_list[1] != "laptop":
            return None
        return self.drive(0.0, None, "the laptop left")

    def drive(self, speed: float, command: Optional[int], why: str) -> Task:
        """The robot's new status: drive at ``speed`` for ``command`` (None: a stop of its own)."""
        before = self.get_data(STATUS)
        # Say each change of speed, and every stop the laptop did not command.
        if before is None or before["speed_m_s"] != speed or command is None:
            print(f"robot: driving at {speed:+.2f} m/s ({why})", flush=True)
        return self.store_data_task(STATUS, {"speed_m_s": speed, "command": command, "why": why})


class DriverFactory(EndpointFactory):
    """Builds a `Driver`.

    Example::

        DriverFactory()
    """

    def get(self, parent: AbstractNode) -> Driver:
        return Driver(self, parent)


class RobotBody(ThreadLoop):
    """The simulated robot: moves as ``robot/status`` says and measures.

    Five times a second it moves (at the speed of the last status page),
    then stores the range to the wall ahead and the battery voltage, which
    drops a little with every metre driven.
    """

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "robot_body", max_tick_rate_hz=RATE_HZ)
        self.range_m = START_RANGE_M
        self.driven_m = 0.0
        self.last_tick = time.monotonic()

    def loop(self) -> None:
        now = time.monotonic()
        status = self.get_data(STATUS)
        speed = status["speed_m_s"] if status else 0.0
        step = speed * (now - self.last_tick)
        self.last_tick = now
        self.range_m = max(0.0, self.range_m - step)
        self.driven_m += abs(step)
        self.store_data("sensors/range", round(self.range_m, 3))
        self.store_data("sensors/battery", round(FULL_BATTERY_V - 0.05 * self.driven_m, 3))


class RobotBodyFactory(LoopFactory):
    """Builds a `RobotBody`.

    Example::

        RobotBodyFactory()
    """

    def get(self, parent: AbstractNode) -> RobotBody:
        return RobotBody(self, parent)


# -- the laptop ---------------------------------------------------------------------------
class Pilot(ThreadLoop):
    """Sends a drive command five times a second, following `PLAN` over and over.

    A command is sent again and again, not once: a robot (or logger) that
    joins late, or misses one, has the current command within 0.2 s.
    """

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pilot", max_tick_rate_hz=RATE_HZ)
        self.sent = 0

    def loop(self) -> None:
        self.sent += 1
        self.store_data(COMMAND, {"n": self.sent, "speed_m_s": planned_speed(self.sent)})


def planned_speed(n: int) -> float:
    """The speed of command ``n`` (the first is 1) in `PLAN`.

    Example::

        planned_speed(1)    # 0.25: forward for the first 2 s (10 commands)
        planned_speed(11)   # 0.0: then stop for 1 s
    """
    t = ((n - 1) / RATE_HZ) % sum(seconds for seconds, _ in PLAN)
    for seconds, speed in PLAN:
        if t < seconds - 1e-9:
            return speed
        t -= seconds
    return PLAN[-1][1]


class PilotFactory(LoopFactory):
    """Builds a `Pilot`.

    Example::

        PilotFactory()
    """

    def get(self, parent: AbstractNode) -> Pilot:
        return Pilot(self, parent)


class Telemetry(ThreadLoop):
    """Prints the robot's latest sensor pages and status once a second."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "telemetry", max_tick_rate_hz=1.0)

    def loop(self) -> None:
        range_m = self.get_data("sensors/range")
        battery_v = self.get_data("sensors/battery")
        status = self.get_data(STATUS)
        if range_m is None or battery_v is None or status is None:
            print("laptop: no telemetry from the robot yet", flush=True)
            return
        print(
            f"laptop: wall {range_m:.2f} m ahead, battery {battery_v:.2f} V, "
            f"robot at {status['speed_m_s']:+.2f} m/s ({status['why']})",
            flush=True,
        )


class TelemetryFactory(LoopFactory):
    """Builds a `Telemetry` printer.

    Example::

        TelemetryFactory()
    """

    def get(self, parent: AbstractNode) -> Telemetry:
        return Telemetry(self, parent)


# -- the logger ---------------------------------------------------------------------------
class LogCounter(ThreadLoop):
    """Prints every two seconds how many pages the recorder has written."""

    def __init__(
        self, factory: LogCounterFactory, parent: AbstractNode, recorder: RecorderEndpointFactory
    ) -> None:
        super().__init__(factory, parent, "log_counter", max_tick_rate_hz=0.5)
        self.recorder = recorder

    def loop(self) -> None:
        written = self.recorder.pages_written
        print(f"logger: {written} pages written to {self.recorder.path}", flush=True)


class LogCounterFactory(LoopFactory):
    """Builds a `LogCounter` for ``recorder``.

    Example::

        recorder = RecorderEndpointFactory("team_log.jsonl", [COMMAND, STATUS])
        LogCounterFactory(recorder)
    """

    def __init__(self, recorder: RecorderEndpointFactory) -> None:
        super().__init__()
        self.recorder = recorder

    def get(self, parent: AbstractNode) -> LogCounter:
        return LogCounter(self, parent, self.recorder)


def make_components(
    system: str = "team7",
    listen: Sequence[str] = (),
    connect: Sequence[str] = (),
    mode: str = "peer",
    seconds: Optional[float] = None,
    log_file: str = "team_log.jsonl",
) -> ComponentsByRole:
    """The three roles; ``listen``, ``connect`` and ``mode`` are this machine's.

    Example::

        make_components("team7", listen=["tcp/0.0.0.0:7447"])   # on the robot
    """

    def zenoh(publish: List[str], subscribe: List[str]) -> ZenohCommsFactory:
        # Without endpoints, nodes find each other by multicast ("scouting").
        return ZenohCommsFactory(
            system,
            publish=publish,
            subscribe=subscribe,
            mode=mode,
            listen=listen,
            connect=connect,
            scouting=not (listen or connect),
        )

    stop: List[AbstractFactory] = [TimeoutLoopFactory(seconds=seconds)] if seconds else []
    recorder = RecorderEndpointFactory(log_file, [*SENSORS, STATUS, COMMAND])
    return {
        "robot": [
            zenoh(publish=[*SENSORS, STATUS], subscribe=[COMMAND]),
            DriverFactory(),  # obeys each command, stores robot/status
            RobotBodyFactory(),  # moves, stores sensors/range and sensors/battery
            *stop,
        ],
        "laptop": [
            zenoh(publish=[COMMAND], subscribe=["sensors/*", STATUS]),
            PilotFactory(),  # stores commands/drive five times a second
            TelemetryFactory(),  # prints the robot's pages once a second
            *stop,
        ],
        "logger": [
            zenoh(publish=[], subscribe=["**"]),  # "**": every key of the system
            recorder,  # writes every page to log_file
            LogCounterFactory(recorder),  # prints how many, every 2 s
            *stop,
        ],
    }


def parse_options(argv: Sequence[str]) -> Tuple[Any, List[str]]:
    """This example's options; the rest (the role) goes to `CliRunner`.

    Example::

        options, rest = parse_options(["team.py", "robot", "--listen", "tcp/0.0.0.0:7447"])
        options.listen   # ['tcp/0.0.0.0:7447'];  rest: ['team.py', 'robot']
    """
    parser = argparse.ArgumentParser(
        prog=argv[0] if argv else "team.py",
        description="A robot, a laptop and a logger over Zenoh: run one role per machine.",
        epilog="SNR's own option --mode (debug, test, deployed) goes on to CliRunner.",
    )
    parser.add_argument("roles", nargs="*", metavar="ROLE", help="robot, laptop or logger")
    parser.add_argument(
        "--system", default="team7", help="your team's name: nodes only hear their own (team7)"
    )
    parser.add_argument(
        "--listen",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="where this node accepts connections, e.g. tcp/0.0.0.0:7447 (repeatable)",
    )
    parser.add_argument(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="a node (or router) to connect to, e.g. tcp/192.168.1.10:7447 (repeatable); "
        "with --listen or --connect, multicast scouting is off",
    )
    parser.add_argument(
        "--zenoh-mode",
        choices=["peer", "client", "router"],
        default="peer",
        help="peer (default); client, with a Zenoh router to --connect to",
    )
    parser.add_argument("--seconds", type=float, default=None, help="stop after this long")
    parser.add_argument(
        "--log-file", default="team_log.jsonl", help="the logger's file (team_log.jsonl)"
    )
    options, rest = parser.parse_known_args(argv[1:])
    return options, [argv[0] if argv else "team.py", *options.roles, *rest]


def main(argv: Sequence[str]) -> None:
    """Run the role(s) named on the command line."""
    options, runner_argv = parse_options(argv)
    components = make_components(
        options.system,
        options.listen,
        options.connect,
        options.zenoh_mode,
        options.seconds,
        options.log_file,
    )
    CliRunner(components, runner_argv).run()


if __name__ == "__main__":
    main(sys.argv)
