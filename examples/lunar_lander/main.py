"""Landing the lunar module (thesis section 5.3, listing A.4).

The lunar module falls towards the Moon. A radar loop simulates the descent
and stores what the radar sees, ``(altitude, velocity)``, under
``radar_data``; a controller endpoint answers each reading by storing how hard
to fire the engine (0 to 3) under ``thruster_data``. Touch down slower than
2 m/s to land safely; the fuel runs out if you hover too long.

    python main.py                  # fly with the baseline controller (it lands)
    python main.py --policy q       # train a Q-learning controller, then fly with it
    python main.py --policy untrained   # the Q-learning controller before training
    python main.py --train          # only train, and print the landing rates

The exercise (thesis 5.3): write the Q function. The scaffold is here:
`QLearningControllerEndpoint` flies with any ``q_function(radar, action)``,
and `train` is a small tabular Q-learning trainer that runs the simulation
directly, without nodes, so it can play thousands of landings in a second.

The file reads top to bottom: the Moon's physics, the SNR components, the
controllers, the trainer, then the command line.
"""

import argparse
import bisect
import random
import sys
import time
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Page,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    tasks,
)

# ---------------------------------------------------------------------------
# The Moon. Listing A.4 used Earth's gravity with an engine too weak to stop
# the fall (-9.8 + 3 * 0.1 per tick), so every flight crashed; these numbers
# are the Moon's, with an engine strong enough to brake and a fuel tank that
# is not: hovering for long empties it.
# ---------------------------------------------------------------------------

MOON_GRAVITY_M_S2 = 1.62
"""The Moon's surface gravity."""

THRUST_M_S2_PER_LEVEL = 1.2
"""Upward acceleration per engine level: level 3 gives 3.6 m/s², about the
Apollo lunar module's near the end of its descent."""

SECONDS_PER_TICK = 0.5
"""Simulated time between two radar readings (one control decision)."""

FUEL_PER_LEVEL = 1
"""Fuel used in one tick per engine level (level 3 uses 3 units)."""

INITIAL_FUEL = 100
"""Fuel at the start (listing A.4's value): about 37 s of hovering."""

START_ALTITUDE_M = 50.0
"""Altitude at the start (listing A.4's value)."""

SAFE_LANDING_SPEED_M_S = 2.0
"""Touching down faster than this is a crash (Apollo's legs were built for ~3 m/s)."""

ACTIONS: List[int] = [0, 1, 2, 3]
"""The engine levels a controller may choose."""

MAX_TICKS = 1000
"""A flight longer than this ends (it cannot happen: the fuel runs out first)."""

Radar = Tuple[float, float]
"""What the radar measures: ``(altitude in m, vertical velocity in m/s, up > 0)``."""

Policy = Callable[[Radar], int]
"""A controller's decision: the engine level for a radar reading."""


@dataclass
class Lander:
    """The lunar module's state, and one step of its physics.

    Example::

        lander = Lander()
        lander.step(thrust=3)
        lander.radar()   # (49.9..., 0.99)
    """

    altitude: float = START_ALTITUDE_M
    velocity: float = 0.0
    fuel: int = INITIAL_FUEL
    time_s: float = 0.0

    def step(self, thrust: int) -> int:
        """Fire the engine at ``thrust`` for one tick; returns the level really used.

        With too little fuel left the engine gives what it can, then nothing.
        """
        level = max(0, min(int(thrust), max(ACTIONS), self.fuel // FUEL_PER_LEVEL))
        self.fuel -= level * FUEL_PER_LEVEL
        acceleration = -MOON_GRAVITY_M_S2 + level * THRUST_M_S2_PER_LEVEL
        # Update the velocity first, then move with it (semi-implicit Euler:
        # stable, and what most game physics does).
        self.velocity += acceleration * SECONDS_PER_TICK
        self.altitude += self.velocity * SECONDS_PER_TICK
        self.time_s += SECONDS_PER_TICK
        return level

    def radar(self) -> Radar:
        """The reading a radar would give now."""
        return (round(self.altitude, 3), round(self.velocity, 3))

    def has_touched_down(self) -> bool:
        """True once the module reached the surface."""
        return self.altitude <= 0.0

    def landed_safely(self) -> bool:
        """True if it touched down slowly enough."""
        return self.has_touched_down() and self.velocity >= -SAFE_LANDING_SPEED_M_S

    def outcome(self) -> str:
        """One sentence saying how the flight ended."""
        speed = abs(self.velocity)
        details = f"at {speed:.2f} m/s after {self.time_s:.1f} s, {self.fuel} fuel left"
        if self.landed_safely():
            return f"Landed safely {details}"
        return f"Crashed {details} (a safe landing is at most {SAFE_LANDING_SPEED_M_S:.1f} m/s)"


def fly(policy: Policy, lander: Optional[Lander] = None) -> Lander:
    """Fly a whole descent without SNR nodes (for training and quick checks).

    Example::

        fly(baseline_policy).landed_safely()   # True
    """
    lander = lander or Lander()
    for _ in range(MAX_TICKS):
        if lander.has_touched_down():
            break
        lander.step(policy(lander.radar()))
    return lander


# ---------------------------------------------------------------------------
# SNR components: the radar loop (the simulated world) and the controllers.
# ---------------------------------------------------------------------------


class RadarSensorLoop(ThreadLoop):
    """Simulates the descent and stores a radar reading after every tick.

    It steps in lockstep with the controller: after storing a reading it
    waits for a *new* ``thruster_data`` page before the next tick, so a run is
    the same however fast the computer is. On touchdown it stops the node
    with the outcome as the reason (no exception, so no stack trace).

    Example::

        RadarSensorLoopFactory(initial_fuel=100, speed=5)
    """

    def __init__(
        self,
        factory: "RadarSensorLoopFactory",
        parent: AbstractNode,
        fuel: int,
        speed: float,
    ) -> None:
        # speed 1 is real time (2 readings a second); 0 is as fast as possible.
        rate_hz = speed / SECONDS_PER_TICK if speed > 0 else 0.0
        super().__init__(factory, parent, "radar_sensor", max_tick_rate_hz=rate_hz)
        self.lander = Lander(fuel=fuel)
        self.command_timeout_s = factory.command_timeout_s
        self.last_command: Optional[Page] = None
        self.waiting_since = time.monotonic()

    def setup(self) -> None:
        self.store_data("thruster_data", 0)

    def loop(self) -> None:
        command = self.get_page("thruster_data")
        if command is None or command is self.last_command:
            self.wait_for_command()
            return
        self.last_command = command
        self.waiting_since = time.monotonic()
        thrust = command.data if isinstance(command.data, int) else 0
        used = self.lander.step(thrust)
        self.store_data("telemetry", self.telemetry(used))
        if self.lander.has_touched_down():
            self.land()
            return
        self.store_data("radar_data", self.lander.radar())

    def telemetry(self, thrust: int) -> Dict[str, Any]:
        """What a display shows: time, altitude, velocity, fuel and thrust."""
        altitude, velocity = self.lander.radar()
        return {
            "time_s": self.lander.time_s,
            "altitude_m": max(altitude, 0.0),
            "velocity_m_s": velocity,
            "fuel": self.lander.fuel,
            "thrust": thrust,
        }

    def land(self) -> None:
        """Touchdown: stop the node, with the outcome as the reason."""
        outcome = self.lander.outcome()
        self.store_data("outcome", outcome)
        # tasks.terminate() would jump the queue; at normal priority the node
        # first handles the pages stored above (the last telemetry, the outcome).
        self.schedule(Task(TaskType.terminate, outcome))
        self.set_terminate_flag(outcome)

    def wait_for_command(self) -> None:
        """No answer from the controller yet: wait a little, or give up."""
        if time.monotonic() - self.waiting_since > self.command_timeout_s:
            reason = (
                f"No thruster_data for {self.command_timeout_s:g} s: is a controller "
                "endpoint storing 'thruster_data' when 'radar_data' is stored?"
            )
            self.schedule(tasks.terminate(reason))
            self.set_terminate_flag(reason)
            return
        self.wait_s(0.001)


class RadarSensorLoopFactory(LoopFactory):
    """Builds the `RadarSensorLoop` (listing A.4).

    Args:
        initial_fuel: the fuel in the tank at the start.
        speed: how much faster than real time to fly (0: as fast as possible).
        command_timeout_s: stop if no controller answers for this long.

    Example::

        RadarSensorLoopFactory(initial_fuel=100)
    """

    def __init__(
        self,
        initial_fuel: int = INITIAL_FUEL,
        speed: float = 1.0,
        command_timeout_s: float = 2.0,
    ) -> None:
        super().__init__()
        self.initial_fuel = initial_fuel
        self.speed = speed
        self.command_timeout_s = command_timeout_s

    def get(self, parent: AbstractNode) -> RadarSensorLoop:
        return RadarSensorLoop(self, parent, self.initial_fuel, self.speed)


def read_radar(task: Task) -> Optional[Radar]:
    """The ``(altitude, velocity)`` in a stored ``radar_data`` page, or None.

    Example::

        read_radar(tasks.store_data("radar_data", (50.0, -1.0)))   # (50.0, -1.0)
    """
    page = task.page()
    if page is None:
        return None
    data = page.data
    if not (isinstance(data, (tuple, list)) and len(data) == 2):
        return None
    altitude, velocity = data
    if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in data):
        return None
    return (float(altitude), float(velocity))


class ControllerEndpoint(Endpoint):
    """Answers every radar reading with an engine level from ``policy``.

    Example::

        ControllerFactory(baseline_policy)
    """

    def __init__(
        self,
        factory: EndpointFactory,
        parent: AbstractNode,
        name: str,
        policy: Optional[Policy] = None,
    ) -> None:
        super().__init__(factory, parent, name)
        # TaskType.store_data is another name for TaskType.store_page.
        self.task_handlers = {
            (TaskType.store_data, "radar_data"): self.set_throttle,
        }
        self.given_policy = policy

    def set_throttle(self, t: Task, key: TaskId) -> SomeTasks:
        """Store the engine level for the radar reading in ``t``."""
        radar = read_radar(t)
        if radar is None:
            self.warn("Invalid radar data in %s: expected (altitude, velocity)", t)
            return None
        return tasks.store_data("thruster_data", self.policy(radar))

    def policy(self, radar: Radar) -> int:
        """The engine level for ``radar`` (subclasses decide differently)."""
        assert self.given_policy is not None, "pass a policy to ControllerFactory"
        return self.given_policy(radar)


class ControllerFactory(EndpointFactory):
    """Builds a `ControllerEndpoint` that flies with ``policy``.

    Example::

        ControllerFactory(baseline_policy)
    """

    def __init__(self, policy: Policy) -> None:
        super().__init__()
        self.policy = policy

    def get(self, parent: AbstractNode) -> ControllerEndpoint:
        return ControllerEndpoint(self, parent, "controller", self.policy)


def baseline_policy(radar: Radar) -> int:
    """A hand-written controller that lands: brake towards a safe descent rate.

    The lower the module, the slower it should fall: 8 m/s at 50 m, 2 m/s at
    10 m, 0.5 m/s at the surface. The engine level is what holds the module
    against gravity (1.35), plus more the faster it falls compared to that.

    Example::

        baseline_policy((50.0, 0.0))   # 0: still slow, let it fall
    """
    altitude, velocity = radar
    target_velocity = -(0.5 + 0.15 * altitude)
    too_fast_by = target_velocity - velocity
    hover_level = MOON_GRAVITY_M_S2 / THRUST_M_S2_PER_LEVEL
    level = round(hover_level + 1.5 * too_fast_by)
    return max(min(ACTIONS), min(max(ACTIONS), level))


# ---------------------------------------------------------------------------
# The Q-learning exercise (listing A.4's endpoint, fixed) and a trainer.
# ---------------------------------------------------------------------------

QFunction = Callable[[Any, int], float]
"""How good an action is in a state: ``q_function(radar_data, action)``."""


class QLearningControllerEndpoint(ControllerEndpoint):
    """Chooses the engine level with the highest Q value (listing A.4).

    Example::

        QLearningControllerEndpointFactory(table.q_value)
    """

    def __init__(
        self,
        factory: EndpointFactory,
        parent: AbstractNode,
        q_function: QFunction,
    ) -> None:
        super().__init__(factory, parent, "q_learning_controller")
        self.q_function = q_function
        self.actions = [0, 1, 2, 3]

    def policy(self, data: Any) -> int:
        return max(self.actions, key=lambda a: self.q_function(data, a))


class QLearningControllerEndpointFactory(EndpointFactory):
    """Builds a `QLearningControllerEndpoint` for ``q_function``.

    Example::

        QLearningControllerEndpointFactory(QTable().q_value)   # untrained
    """

    def __init__(self, q_function: QFunction) -> None:
        super().__init__()
        self.q_function = q_function

    def get(self, parent: AbstractNode) -> QLearningControllerEndpoint:
        return QLearningControllerEndpoint(self, parent, self.q_function)


ALTITUDE_EDGES_M = [1.0, 2.5, 5.0, 10.0, 15.0, 20.0, 30.0, 40.0, 55.0, 80.0]
VELOCITY_EDGES_M_S = [-12.0, -9.0, -7.0, -5.0, -4.0, -3.0, -2.0, -1.5, -1.0, -0.5, 0.0, 1.0]

State = Tuple[int, int]
"""A radar reading sorted into bins: ``(altitude bin, velocity bin)``."""


def state_of(radar: Radar) -> State:
    """The bins a radar reading falls in (a Q table needs few, discrete states)."""
    altitude, velocity = radar
    return (bisect.bisect(ALTITUDE_EDGES_M, altitude), bisect.bisect(VELOCITY_EDGES_M_S, velocity))


class QTable:
    """Q values for every (state, action), all 0 until trained.

    Example::

        table = QTable()
        table.q_value((50.0, 0.0), 3)    # 0.0
    """

    def __init__(self) -> None:
        self.values: Dict[State, List[float]] = {}

    def row(self, state: State) -> List[float]:
        """The Q values of every action in ``state``."""
        if state not in self.values:
            self.values[state] = [0.0 for _ in ACTIONS]
        return self.values[state]

    def q_value(self, radar: Any, action: int) -> float:
        """The ``q_function`` the Q-learning endpoint asks."""
        return self.row(state_of(radar))[action]

    def best_action(self, radar: Radar) -> int:
        """The action with the highest Q value (the lowest level on a tie)."""
        row = self.row(state_of(radar))
        return max(ACTIONS, key=lambda a: row[a])


def random_start(rng: random.Random) -> Lander:
    """A start a little different every flight, so the table learns more than one path."""
    return Lander(altitude=rng.uniform(30.0, 70.0), velocity=rng.uniform(-4.0, 1.0))


def final_reward(lander: Lander) -> float:
    """+100 for a safe landing; a crash costs more the harder it was."""
    if lander.landed_safely():
        return 100.0
    return -10.0 * abs(lander.velocity)


def train(
    table: QTable,
    episodes: int = 3000,
    seed: int = 1,
    time_limit_s: float = 5.0,
    learning_rate: float = 0.2,
    discount: float = 0.98,
    exploration: float = 0.3,
) -> int:
    """Q-learning: fly ``episodes`` descents, improving ``table`` after each tick.

    Each tick costs a little (-0.1, so dawdling is not free); touchdown gives
    `final_reward`. The chance of a random action (exploring) shrinks from
    ``exploration`` as training goes on. Stops early after ``time_limit_s``.
    Returns how many episodes were flown.

    Example::

        table = QTable()
        train(table, episodes=500)
        fly(table.best_action).landed_safely()   # very likely True
    """
    rng = random.Random(seed)
    deadline = time.monotonic() + time_limit_s
    for episode in range(episodes):
        if time.monotonic() > deadline:
            return episode
        explore = exploration * (1 - episode / episodes) + 0.02
        lander = random_start(rng)
        state = state_of(lander.radar())
        for _ in range(MAX_TICKS):
            row = table.row(state)
            if rng.random() < explore:
                action = rng.choice(ACTIONS)
            else:
                action = max(ACTIONS, key=lambda a: row[a])
            lander.step(action)
            if lander.has_touched_down():
                row[action] += learning_rate * (final_reward(lander) - row[action])
                break
            next_state = state_of(lander.radar())
            target = -0.1 + discount * max(table.row(next_state))
            row[action] += learning_rate * (target - row[action])
            state = next_state
    return episodes


def landing_rate(policy: Policy, flights: int = 200, seed: int = 99) -> float:
    """The share of ``flights`` seeded random starts that ``policy`` lands safely.

    Example::

        landing_rate(baseline_policy)   # 1.0
    """
    rng = random.Random(seed)
    landed = sum(fly(policy, random_start(rng)).landed_safely() for _ in range(flights))
    return landed / flights


def trained_table(episodes: int = 3000, seed: int = 1) -> QTable:
    """Train a fresh table and print the landing rates before and after."""
    table = QTable()
    before = landing_rate(table.best_action)
    started = time.perf_counter()
    flown = train(table, episodes=episodes, seed=seed)
    took_s = time.perf_counter() - started
    after = landing_rate(table.best_action)
    print(
        f"Q-learning: {flown} training flights in {took_s:.2f} s; "
        f"landing rate {before:.0%} before, {after:.0%} after"
    )
    return table


# ---------------------------------------------------------------------------
# The system and the command line.
# ---------------------------------------------------------------------------


class FlightDisplay(Endpoint):
    """Prints one line of telemetry per tick (say nothing with ``quiet``)."""

    def __init__(self, factory: "FlightDisplayFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "flight_display")
        self.quiet = factory.quiet
        self.task_handlers = {(TaskType.store_page, "telemetry"): self.show}

    def show(self, t: Task, key: TaskId) -> SomeTasks:
        data = t.val_list[0].data
        if not self.quiet:
            print(
                f"t={data['time_s']:5.1f} s  altitude {data['altitude_m']:6.2f} m  "
                f"velocity {data['velocity_m_s']:6.2f} m/s  "
                f"fuel {data['fuel']:3d}  thrust {data['thrust']} {'#' * data['thrust']}",
                flush=True,
            )
        return None


class FlightDisplayFactory(EndpointFactory):
    """Builds the `FlightDisplay`.

    Example::

        FlightDisplayFactory(quiet=True)
    """

    def __init__(self, quiet: bool = False) -> None:
        super().__init__()
        self.quiet = quiet

    def get(self, parent: AbstractNode) -> FlightDisplay:
        return FlightDisplay(self, parent)


def make_config(controller: EndpointFactory, speed: float = 5.0, quiet: bool = False) -> Config:
    """The one-node system of listing A.4, with a display added.

    Example::

        make_config(ControllerFactory(baseline_policy), speed=0, quiet=True)
    """
    return Config(
        factories={
            "lunar_module": [
                RadarSensorLoopFactory(initial_fuel=INITIAL_FUEL, speed=speed),
                controller,
                FlightDisplayFactory(quiet),
            ],
        }
    )


def choose_controller(policy: str, episodes: int) -> EndpointFactory:
    """The controller named on the command line."""
    if policy == "baseline":
        return ControllerFactory(baseline_policy)
    if policy == "untrained":
        return QLearningControllerEndpointFactory(QTable().q_value)
    return QLearningControllerEndpointFactory(trained_table(episodes).q_value)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Fly once (or only train) and print how it ended."""
    parser = argparse.ArgumentParser(description="Land the lunar module (thesis 5.3).")
    parser.add_argument(
        "--policy",
        choices=["baseline", "q", "untrained"],
        default="baseline",
        help="who flies: the hand-written controller, trained Q-learning, or untrained",
    )
    parser.add_argument("--train", action="store_true", help="only train; print landing rates")
    parser.add_argument("--episodes", type=int, default=3000, help="training flights")
    parser.add_argument(
        "--speed", type=float, default=5.0, help="times faster than real time (0: no waiting)"
    )
    parser.add_argument("--quiet", action="store_true", help="print only the outcome")
    args = parser.parse_args(argv)
    if args.train:
        trained_table(args.episodes)
        print(f"Baseline controller: landing rate {landing_rate(baseline_policy):.0%}")
        return 0
    config = make_config(choose_controller(args.policy, args.episodes), args.speed, args.quiet)
    runner = SynchronousRunner("lunar_module", config)
    runner.run()
    node = runner.node
    outcome = node.get_data("outcome") if node else None
    if outcome is None:
        reason = node.terminate_reason if node else None
        print(f"The flight was stopped before touchdown: {reason or 'interrupted'}")
        return 1
    print(outcome)
    return 0 if outcome.startswith("Landed") else 1


if __name__ == "__main__":
    sys.exit(main())
