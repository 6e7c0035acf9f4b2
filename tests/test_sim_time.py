"""Nodes on a `SimClock`: loops tick, timeouts fire and pages are stamped in simulated time."""

from __future__ import annotations

import threading
import time
import unittest
from typing import List

from snr import (
    AbstractNode,
    Config,
    LoopFactory,
    Mode,
    MultiProcRunner,
    Node,
    SimClock,
    ThreadLoop,
    TimeoutLoopFactory,
)
from snr.core import TestRunner
from snr.prelude import ConfigError, LoopError
from snr.utils import DummyEndpointFactory
from tests.page_collector import PageCollectorFactory
from tests.quiet import capture_test_logs, captured_logs

JOIN_S = 10.0
"""The most a test waits for a node's thread (a bound for a broken build, never reached)."""


class Ticker(ThreadLoop):
    """Stores its tick count under ``key`` each pass and notes the node's time."""

    def __init__(self, factory: TickerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name, max_tick_rate_hz=factory.rate_hz)
        self.ticks = factory

    def setup(self) -> None:
        self.store_data(f"{self.name}_ready", True)

    def loop(self) -> None:
        # What setup() stored is in the datastore by the first pass.
        self.ticks.ready_seen.append(self.get_data(f"{self.name}_ready") is True)
        self.ticks.times_s.append(self.parent.get_time_s())
        self.store_data(self.name, len(self.ticks.times_s))
        if len(self.ticks.times_s) == self.ticks.fail_at:
            raise RuntimeError("tick failed on purpose")


class TickerFactory(LoopFactory):
    def __init__(self, rate_hz: float, name: str = "ticker", fail_at: int = 0) -> None:
        super().__init__()
        self.rate_hz = rate_hz
        self.name = name
        self.fail_at = fail_at
        self.times_s: List[float] = []
        self.ready_seen: List[bool] = []

    def get(self, parent: AbstractNode) -> Ticker:
        return Ticker(self, parent)


class Napper(ThreadLoop):
    """No tick rate: it only waits on the clock, in ``wait_s`` (as `TimeoutLoop` does)."""

    follows_clock = True

    def __init__(self, factory: NapperFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "napper")
        self.naps = factory

    def loop(self) -> None:
        self.naps.woke_s.append(self.parent.get_time_s())
        self.wait_s(0.25)


class NapperFactory(LoopFactory):
    def __init__(self) -> None:
        super().__init__()
        self.woke_s: List[float] = []

    def get(self, parent: AbstractNode) -> Napper:
        return Napper(self, parent)


def run_node(node: Node) -> None:
    """Run ``node`` on a thread and wait for it, bounded."""
    thread = threading.Thread(target=node.loop, name=f"test-{node.role}", daemon=True)
    thread.start()
    thread.join(JOIN_S)
    if thread.is_alive():
        node.set_terminate_flag("test gave up")
        raise AssertionError(f"node {node.role!r} did not stop within {JOIN_S} s")


class TestTicks(unittest.TestCase):
    def test_a_10_hz_loop_ticks_exactly_10_times_each_simulated_second(self) -> None:
        clock = SimClock(epoch_s=1000.0)
        ticker = TickerFactory(rate_hz=10)
        pages = PageCollectorFactory(["ticker"])
        config = Config(
            {"sim": [ticker, pages, TimeoutLoopFactory(seconds=3)]}, mode=Mode.TEST, clock=clock
        )
        node = Node("sim", config)
        run_node(node)
        self.assertEqual(node.terminate_reason, "Timeout")
        # Ticks at n / 10 s, n = 0..30: the tick at 3.0 comes before the timeout,
        # whose loop's name sorts after "ticker".
        self.assertEqual(ticker.times_s, [n / 10 for n in range(31)])
        for second in range(3):
            in_it = [t for t in ticker.times_s if second <= t < second + 1]
            self.assertEqual(len(in_it), 10, (second, ticker.times_s))
        self.assertTrue(all(ticker.ready_seen), "setup()'s page was missing at a tick")
        # created_at_s: the fixed epoch plus the simulated time of the tick.
        self.assertEqual(
            [page.created_at_s for page in pages.pages], [1000.0 + n / 10 for n in range(31)]
        )
        self.assertEqual(clock(), 3.0)
        self.assertEqual(node.get_time_s(), 3.0)
        # Only simulation: the clock never waited for the wall clock.
        self.assertEqual((clock.wall_waits, clock.paced_waits), (0, 0))

    def test_an_hour_with_nothing_to_do_passes_in_one_jump(self) -> None:
        clock = SimClock()
        config = Config(
            {"sim": [DummyEndpointFactory(), TimeoutLoopFactory(seconds=3600)]},
            mode=Mode.TEST,
            clock=clock,
        )
        node = Node("sim", config)
        run_node(node)
        self.assertEqual(node.terminate_reason, "Timeout")
        self.assertEqual(clock(), 3600.0)
        self.assertEqual(clock.jumps, 1)

    def test_wait_s_in_a_loop_that_follows_the_clock_waits_simulated_seconds(self) -> None:
        napper = NapperFactory()
        config = Config(
            {"sim": [napper, TimeoutLoopFactory(seconds=1)]}, mode=Mode.TEST, clock=SimClock()
        )
        run_node(Node("sim", config))
        # Woken at 1.0 too: "napper" sorts before "timeout_loop".
        self.assertEqual(napper.woke_s, [0.0, 0.25, 0.5, 0.75, 1.0])

    def test_a_failing_loop_stops_the_node_at_its_simulated_time(self) -> None:
        clock = SimClock()
        ticker = TickerFactory(rate_hz=10, fail_at=6)
        config = Config(
            {"sim": [ticker, TimeoutLoopFactory(seconds=60)]}, mode=Mode.TEST, clock=clock
        )
        with captured_logs("snr.sim"), self.assertRaisesRegex(LoopError, "failed on purpose"):
            Node("sim", config).loop()
        self.assertEqual(clock(), 0.5)  # the sixth tick, not the timeout's 60 s


class TestSeveralNodes(unittest.TestCase):
    def test_nodes_built_with_one_clock_take_turns_on_it(self) -> None:
        capture_test_logs(self)  # an earlier test may have left role 'a' logging INFO
        clock = SimClock()
        fast, slow = TickerFactory(rate_hz=10, name="fast"), TickerFactory(rate_hz=4, name="slow")
        config = Config(
            {
                "a": [fast, TimeoutLoopFactory(seconds=1)],
                "b": [slow, TimeoutLoopFactory(seconds=1)],
            },
            mode=Mode.TEST,
            clock=clock,
        )
        nodes = [Node("a", config), Node("b", config)]  # every node built first, then run
        threads = [threading.Thread(target=node.loop, daemon=True) for node in nodes]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(JOIN_S)
        self.assertFalse(any(thread.is_alive() for thread in threads), "a node did not stop")
        self.assertEqual(fast.times_s, [n / 10 for n in range(11)])
        self.assertEqual(slow.times_s, [n / 4 for n in range(5)])
        self.assertEqual([node.terminate_reason for node in nodes], ["Timeout", "Timeout"])
        self.assertEqual(clock(), 1.0)

    def test_multiproc_runner_refuses_a_simulated_clock(self) -> None:
        config = Config({"a": [DummyEndpointFactory()]}, clock=SimClock())
        with self.assertRaisesRegex(ConfigError, "one process"):
            MultiProcRunner(["a"], config)


class TestSafetyStaysOnTheWallClock(unittest.TestCase):
    def test_a_node_whose_clock_cannot_move_is_stopped_by_the_test_limit(self) -> None:
        # Nothing waits on the clock and nothing comes from outside: simulated
        # time stands still. The wall-clock limit still ends the run.
        clock = SimClock()
        config = Config({"sim": [DummyEndpointFactory()]}, mode=Mode.TEST, clock=clock)
        runner = TestRunner("sim", config, timeout_s=0.3)
        runner.run()
        self.assertTrue(runner.timed_out)
        self.assertEqual(clock(), 0.0)
        self.assertGreater(clock.wall_waits, 0)

    def test_a_paced_clock_waits_on_the_wall_clock(self) -> None:
        clock = SimClock(speed=20.0)
        ticker = TickerFactory(rate_hz=10)
        config = Config(
            {"sim": [ticker, TimeoutLoopFactory(seconds=0.5)]}, mode=Mode.TEST, clock=clock
        )
        started = time.monotonic()
        run_node(Node("sim", config))
        self.assertEqual(ticker.times_s, [n / 10 for n in range(6)])
        self.assertGreater(clock.paced_waits, 0)
        # 0.5 simulated seconds at 20x take at least 25 ms (a lower bound only).
        self.assertGreaterEqual(time.monotonic() - started, 0.5 / 20 * 0.9)


class TestBadInput(unittest.TestCase):
    def test_config_takes_only_a_sim_clock(self) -> None:
        with self.assertRaisesRegex(ConfigError, "SimClock"):
            Config({"a": [DummyEndpointFactory()]}, clock=time.monotonic)  # type: ignore[arg-type]

    def test_speed_must_be_above_zero(self) -> None:
        for speed in (0, -1.0, "fast"):
            with self.subTest(speed=speed), self.assertRaisesRegex(ConfigError, "speed"):
                SimClock(speed=speed)  # type: ignore[arg-type]


if __name__ == "__main__":
    unittest.main()
