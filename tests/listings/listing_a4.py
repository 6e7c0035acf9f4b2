"""Thesis listing A.4: Example configuration of lunar module landing simulation.

Printed in Appendix A (line 968 of the thesis text); the full example is
``examples/lunar_lander/main.py``. Run it with ``python listing_a4.py``.

Repaired PDF artefacts: indentation, and lines 46, 92 and 99, each broken in two.
Deviations (each marked ``DEVIATION`` on its line):
- [A.4-imports] line 4: ``Page``, ``SomeTasks``, ``Task``, ``TaskId`` and
  ``TaskType`` are used but were not imported (a ``NameError`` at import).
- [A.4-page-data] lines 82-87: ``set_throttle`` read the radar reading as
  the task's first value, but a store task carries a ``Page``: ``len()`` of it
  raised ``TypeError`` on the first reading, and the asserts wanted index 0 to
  be an ``int`` and a ``float`` at once. It reads ``t.val_list[0].data`` and
  checks that both of its values are floats.
- [A.4-q-function] line 101: the factory built the endpoint without the
  ``q_function`` its constructor requires (a ``TypeError`` when the node
  starts). Training the Q function is the thesis's exercise; the factory passes
  a placeholder that rates every action 0, so the policy picks action 0.
The flight still cannot land, as printed: the engine gives at most 0.3 against
a gravity of 9.8, so the lander hits the ground on the third reading, four
seconds in, and the loop raises "High velocity impact": ``python listing_a4.py``
prints the ``LoopError`` and exits with status 1. The example
(``examples/lunar_lander``) fixes the physics (see docs/deviations.md).
"""
from typing import Any, Callable

import snr
from snr import (AbstractNode, Endpoint, EndpointFactory,
                 LoopFactory,
                 ThreadLoop, tasks,
                 Page, SomeTasks, Task, TaskId, TaskType)  # DEVIATION [A.4-imports]


class RadarSensorLoop(ThreadLoop):

    fuel: int
    altitude: float
    velocity: float

    def __init__(self,
                 factory: LoopFactory,
                 parent: AbstractNode,
                 fuel: int,
                 ) -> None:
        super().__init__(factory, parent,
                         "radar_sensor_endpoint",
                         max_tick_rate_hz=0.5)
        self.fuel = fuel
        self.altitude = 50.0
        self.velocity = 0.0

    def setup(self) -> None:
        self.store_data("thruster_data", 0)

    def loop(self) -> None:
        page = self.get_page("thruster_data")
        assert isinstance(page, Page) and isinstance(page.data, int)
        thruster_value: int = page.data

        self.velocity += -9.8 + thruster_value * 0.1
        self.altitude += self.velocity

        if self.altitude <= 0:
            # *Attempted Landing*
            if self.velocity < -1.0:
                raise Exception("High velocity impact")
            else:
                self.schedule(tasks.terminate("Landed Safely"))
                self.set_terminate_flag()

        self.store_data("radar_data", (self.altitude, self.velocity))

    def halt(self) -> None:
        pass

    def terminate(self) -> None:
        pass


class RadarSensorLoopFactory(LoopFactory):

    initial_fuel: int

    def __init__(self, initial_fuel: int) -> None:
        super().__init__()
        self.initial_fuel = initial_fuel

    def get(self, parent: AbstractNode) -> RadarSensorLoop:
        return RadarSensorLoop(self, parent, self.initial_fuel)


class QLearningControllerEndpoint(Endpoint):

    def __init__(self,
                 factory: EndpointFactory,
                 parent: AbstractNode,
                 q_function: Callable[[Any, int], float],
                 ) -> None:
        super().__init__(factory, parent, "q_learning_controller")
        self.task_handlers = {
            (TaskType.store_data, "radar_data"): self.set_throttle,
        }
        self.q_function = q_function
        self.actions = [0, 1, 2, 3, ]

    def set_throttle(self, t: Task, key: TaskId) -> SomeTasks:
        assert (len(t.val_list) > 0 and
                len(t.val_list[0].data) == 2 and  # DEVIATION [A.4-page-data]
                isinstance(t.val_list[0].data[0], float) and  # DEVIATION [A.4-page-data]
                isinstance(t.val_list[0].data[1], float))  # DEVIATION [A.4-page-data]
        radar_data = t.val_list[0].data  # DEVIATION [A.4-page-data]
        value = self.policy(radar_data)
        return tasks.store_data("thruster_data", value)

    def policy(self, data: Any) -> int:
        return max(self.actions, key=lambda a: self.q_function(data, a))


class QLearningControllerEndpointFactory(EndpointFactory):
    def __init__(self) -> None:
        super().__init__()

    def get(self, parent: AbstractNode) -> QLearningControllerEndpoint:
        return QLearningControllerEndpoint(self, parent,
                                           lambda data, action: 0.0)  # DEVIATION [A.4-q-function]


config = snr.Config(factories={
    "lunar_module": [
        RadarSensorLoopFactory(initial_fuel=100),
        QLearningControllerEndpointFactory(),
    ],
})


def main():
    snr.SynchronousRunner("lunar_module", config).run()


if __name__ == "__main__":
    main()
