"""The profiler's table: one section per thread, whose shares add up to 100%."""

import re
import unittest
from typing import Dict, List

from snr import (
    AbstractNode,
    Config,
    ListReplayerFactory,
    Mode,
    MovingAvgFilterFactory,
    Node,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
)
from snr.core.checks.profiler import Profiler
from tests.helpers import LoopFactoryOf, StopWhenFactory

SHARE = re.compile(r" -> +([\d.]+)%: ")
SECTION = re.compile(r"^(node thread|loop thread \S+):$")


def shares_by_section(dump: str) -> Dict[str, List[float]]:
    """``{"node thread": [share, ...], "loop thread NAME": [...]}`` from a dump's table."""
    sections: Dict[str, List[float]] = {}
    current = None
    for line in dump.splitlines():
        if not line:
            break  # the comms reports start after a blank line
        heading = SECTION.match(line)
        if heading:
            current = heading.group(1)
            sections[current] = []
            continue
        share = SHARE.search(line)
        if share:
            assert current is not None, f"a share before any section: {line!r}"
            sections[current].append(float(share.group(1)))
    return sections


class TestProfileShares(unittest.TestCase):
    def test_each_threads_shares_add_up_to_100_percent_on_a_real_run(self) -> None:
        """A loop (the replayer) feeds handlers (the filter) on the node's thread.

        In one list, as in 2021, the loop's share and the handlers' would be
        added although they run at the same time on two threads.
        """
        config = Config(
            {
                "robot": [
                    ListReplayerFactory(list(range(40)), "x", period_s=0.001),
                    MovingAvgFilterFactory("x", "y", length=4),
                    StopWhenFactory((TaskType.store_page, "y"), count=40),
                    TimeoutLoopFactory(seconds=5),  # only if the stop never comes
                ]
            },
            mode=Mode.TEST,
            profile=True,
        )
        node = Node("robot", config)
        node.loop()
        self.assertEqual(node.terminate_reason, "test work done")
        assert node.profiler is not None
        dump = node.profiler.dump()
        sections = shares_by_section(dump)
        self.assertIn("node thread", sections, dump)
        self.assertIn("loop thread list_replayer_x", sections, dump)
        for name, shares in sections.items():
            # Each row is rounded to 0.001%: the sum may be off by a few thousandths.
            self.assertAlmostEqual(sum(shares), 100.0, delta=0.5, msg=f"{name}:\n{dump}")
        node_rows = dump.split("node thread:\n")[1].split("loop thread")[0]
        self.assertIn("(store_page, 'x'):snr.std_mods.filters", node_rows)
        self.assertNotIn("Loop(", node_rows)  # loops are in sections of their own

    def test_times_that_nest_are_said_to_add_up_to_more(self) -> None:
        """Two handler rows longer than the whole run: one must have run inside the other."""
        profiler = Profiler()
        profiler.task_cell((TaskType.event, "outer"), "robot")[:] = [1, 1000.0]
        profiler.task_cell((TaskType.event, "inner"), "robot")[:] = [1, 900.0]
        dump = profiler.dump()
        self.assertIn("add up to more than 100%: some ran inside others", dump)
        self.assertIn("->   0.000%: (outside handlers", dump)  # never a negative share


class Counting(ThreadLoop):
    """Stores how many times its loop() ran, once every 20 s."""

    def __init__(self, factory: LoopFactoryOf, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counting", max_tick_rate_hz=0.05)
        self.calls = 0
        factory.built = self  # type: ignore[attr-defined]

    def loop(self) -> None:
        self.calls += 1
        self.store_data("calls", self.calls)


class TestLoopPasses(unittest.TestCase):
    def test_a_pass_stopped_in_its_wait_is_counted_and_the_wait_ends(self) -> None:
        """A loop counts a pass after the wait that follows it: a stop in that wait still counts it.

        The node stops on the first page, while the loop waits out the rest of
        its 20 s; the loop must wake from that wait (not sleep it out) and
        its one pass must be in the profiler's table.
        """
        factory = LoopFactoryOf(Counting)
        config = Config(
            {"robot": [factory, StopWhenFactory((TaskType.store_page, "calls"))]},
            mode=Mode.TEST,
            profile=True,
        )
        node = Node("robot", config)
        node.loop()
        loop: Counting = factory.built  # type: ignore[attr-defined]
        loop.join(5.0)
        self.assertFalse(loop.is_alive(), "the loop slept out its wait instead of stopping")
        self.assertEqual(loop.calls, 1)
        assert node.profiler is not None
        dump = node.profiler.dump()
        self.assertRegex(dump, r"(?m)^ +1 x .*Loop\(counting\)$")


if __name__ == "__main__":
    unittest.main()
