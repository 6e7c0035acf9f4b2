"""The stress benchmark (thesis section 5.4, listing A.5).

A stressor endpoint schedules a "stress" task; handling it adds another
stressor endpoint built by the same factory, which does the same, and so on,
until the time target. The output is that of thesis listing 5.2: how many
endpoints were made, when the terminate task was handled, the profiler's table
and the time each test took.

    python bench_stress_endpoint_fac.py
    SNR_BENCH_SECONDS=0.5 python bench_stress_endpoint_fac.py   # a shorter run

As printed in the thesis, but for its typos; see docs/deviations.md.
"""

import logging
import os
import unittest
from typing import List, Optional

from snr import *

STRESS_TASK_NAME: TaskName = "stress"

TIME_TARGET_S: float = float(os.environ.get("SNR_BENCH_SECONDS", "2.0"))
"""How long test_stress_endpoint stresses the node (the thesis used 2 s)."""


class StressorEndpoint(Endpoint):
    def __init__(
        self,
        factory: EndpointFactory,
        parent: AbstractNode,
        name: ComponentName,
    ) -> None:
        super().__init__(factory, parent, name)
        self.task_handlers = {
            (TaskType.event, STRESS_TASK_NAME): self.replicate,
        }

    def replicate(self, task: Task, key: TaskId) -> SomeTasks:
        return tasks.add_component(self.factory)

    def begin(self) -> None:
        self.schedule(tasks.event(STRESS_TASK_NAME))

    def halt(self) -> None:
        pass

    def terminate(self) -> None:
        pass


class StressorEndpointFactory(EndpointFactory):
    def __init__(
        self,
        max_endpoints: int = 1000,
        time_limit_s: float = 0.500,
    ) -> None:
        super().__init__()
        self.max_endpoints = max_endpoints
        self.time_limit_s = time_limit_s
        self.calls = 0
        self.num_children = 0

    def get(self, parent: AbstractNode) -> Optional[Endpoint]:
        self.calls += 1
        if self.is_limited(parent):
            return None
        self.num_children += 1
        return StressorEndpoint(self, parent, f"stressor_endpoint_{self.num_children}")

    def is_limited(self, parent: AbstractNode) -> bool:
        return self.num_children >= self.max_endpoints or (
            self.time_limit_s != 0 and parent.get_time_s() >= self.time_limit_s
        )


class BenchStressEndpointFac(SNRTestCase):
    def setUp(self) -> None:
        self.test_timer = Timer()

    def tearDown(self) -> None:
        # The last lines of listing 5.2: how long each test took.
        print(f"{self.test_timer.current_s() * 1000:.2f} ms: {self.id()}")

    def test_stress_endpoint_init(self) -> None:
        stressor_fac = StressorEndpointFactory(max_endpoints=1, time_limit_s=0.050)

        times: List[float] = []
        node: AbstractNode = Node(
            "test",
            self.get_config(
                [
                    stressor_fac,
                    TimeoutLoopFactory(seconds=0.010),
                    StopwatchEndpointFactory(times, [TaskType.terminate]),
                ],
                Mode.DEBUG,
            ),
        )
        node.log.setLevel(logging.WARNING)
        node.loop()
        self.assertEqual(stressor_fac.num_children, 1)
        self.assertEqual(len(times), 1)

    def test_stress_endpoint(self) -> None:
        time_target_s: float = TIME_TARGET_S
        stressor_fac = StressorEndpointFactory(max_endpoints=10000, time_limit_s=time_target_s)
        times: List[float] = []
        timer = Timer()
        node: AbstractNode = Node(
            "test",
            self.get_config(
                [
                    stressor_fac,
                    TimeoutLoopFactory(seconds=time_target_s),
                    StopwatchEndpointFactory(times, [TaskType.terminate]),
                ],
                Mode.DEBUG,
            ),
        )
        node.log.setLevel(logging.WARNING)
        node.loop()
        t_s = timer.current_s()
        print(
            "\nStressed with:\n",
            f"\t{stressor_fac.num_children} stressor endpoints\n",
            f"\t{stressor_fac.calls} stressor factory calls\n",
            f"\tTerminate expected at {time_target_s * 1000:.0f} ms\n",
            f"\t{times[0] * 1000:.3f} ms terminate handled\n",
            f"\t{t_s * 1000:.3f} ms total time\n",
        )
        if node.profiler:
            print(node.profiler.dump())


if __name__ == "__main__":
    unittest.main()
