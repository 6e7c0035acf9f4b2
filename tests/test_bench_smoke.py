"""The benchmarks in bench/ still run: each one with a tiny workload, no timing checked.

All three start when this module is imported (`early`) and run side by side,
and beside other tests: they are checked for what they print, not for speed.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import tempfile
import unittest
from typing import Callable, Tuple

from tests.examples_support import ROOT, StartedScript, early, start_script

BENCH = os.path.join(ROOT, "bench")


def _bench(script: str, *args: str, timeout_s: float) -> Callable[[], StartedScript]:
    """``bench/<script> args`` started early (see `early`)."""
    return early(lambda: start_script([os.path.join(BENCH, script), *args], timeout_s=timeout_s))


# The bounds are for a busy machine: each takes well under a second alone.
LOOP_LATENCY = _bench(
    "bench_loop_latency.py", "--samples=20", "--rounds=1", "--interval-ms=0.5", timeout_s=20.0
)
COMMS = _bench(
    "bench_comms.py",
    "--quick",
    "--pages=300",
    "--round-trips=30",
    "--rounds=1",
    "--idle-s=0.1",
    "--settle-s=0.02",
    timeout_s=8.0,
)


def _start_sim_bench() -> Tuple[str, StartedScript]:
    """The folder for the picture, and bench_sim.py started."""
    picture = os.path.join(tempfile.mkdtemp(prefix="snr-bench-sim-"), "sim.png")
    return picture, start_script(
        [os.path.join(BENCH, "bench_sim.py"), "--steps=50", "--rounds=1", "--lesson-s=0.5"]
        + (["--picture", picture] if importlib.util.find_spec("pygame") else []),
        timeout_s=10.0,
    )


SIM = early(_start_sim_bench)


def setUpModule() -> None:
    for started in (LOOP_LATENCY, COMMS, SIM):
        started()  # (started already, unless in a pytest-xdist worker)


class TestLoopLatencyBench(unittest.TestCase):
    def test_prints_the_table_and_the_target(self) -> None:
        done = LOOP_LATENCY().result()
        self.assertEqual(done.returncode, 0, done.stderr)
        out = done.stdout
        self.assertIn("Loop -> handler latency", out)
        self.assertRegex(out, r"case +p50 us +p99 us +max us +vs bare p50")
        for condition in ("idle", "load"):
            self.assertRegex(out, rf"bare SimpleQueue, {condition} +[\d.]+ +[\d.]+ +\d+ +1\.00x")
            for mode in ("DEBUG", "DEPLOYED"):
                self.assertRegex(out, rf"SNR {mode}, {condition} +[\d.]+ +[\d.]+ +\d+ +[\d.]+x")
                self.assertRegex(out, rf"  SNR {mode}, {condition}: [\d.]+x \((met|MISSED)\)")
        self.assertIn("Target: node p50 <= 2x the bare hand-off's p50", out)


class TestCommsBench(unittest.TestCase):
    def test_prints_the_tables_and_the_targets(self) -> None:
        done = COMMS().result()
        self.assertEqual(done.returncode, 0, done.stderr)
        out = done.stdout
        self.assertIn("Comms between two processes on 127.0.0.1: 300 pages one way", out)
        self.assertRegex(out, r"JSON backend: (orjson|json)")
        self.assertRegex(out, r"one-way throughput +pages/s +spread +x bare +x PUSH/PULL")
        self.assertRegex(out, r"round trip +p50 us +spread +x bare +x REQ/REP +p99 us")
        rows = ["bare TCP, one sendall a frame", "SNR default \\(DEBUG\\)", "SNR DEPLOYED"]
        if importlib.util.find_spec("zmq") is not None:
            self.assertRegex(out, r"pyzmq PUSH/PULL +[\d,]+ ")
            self.assertRegex(out, r"pyzmq REQ/REP +\d+ ")
            self.assertIn("throughput >= 0.75x pyzmq PUSH/PULL", out)
        else:
            self.assertIn("pyzmq is not installed", out)
        for row in rows:
            # Every page arrives once and in order: 0 lost, 0 duplicated, 0 reordered.
            self.assertRegex(out, rf"{row} +[\d,]+ +[\d,]+-[\d,]+ +[\d.]+ +\S+ +0 +0 +0 +0")
        self.assertRegex(out, r"bare TCP, batched sends +[\d,]+")
        self.assertRegex(out, r"  \+ reader thread hand-off +\d+")
        self.assertRegex(out, r"idle connected pair +% core")
        for mode in ("SNR default (DEBUG):", "SNR DEPLOYED:"):
            self.assertIn(mode, out)
        self.assertRegex(
            out, r"throughput >= 0.50x bare, one sendall a frame +[\d.]+x (met|MISSED)"
        )
        self.assertRegex(out, r"p50 round trip <= 1.3x bare +[\d.]+x (met|MISSED)")
        self.assertRegex(
            out, r"p50 round trip <= 1.25x reader thread hand-off +[\d.]+x (met|MISSED)"
        )
        self.assertRegex(out, r"0 pages lost / duplicated / reordered +0 / 0 / 0 .* met")


class TestSimBench(unittest.TestCase):
    def test_prints_a_row_per_case_and_writes_the_picture(self) -> None:
        picture, started = SIM()
        self.addCleanup(shutil.rmtree, os.path.dirname(picture), ignore_errors=True)
        done = started.result()
        self.assertEqual(done.returncode, 0, done.stderr)
        out = done.stdout
        self.assertIn("Simulator speed: 50 steps of 20 ms, 9 walls, 5 range rays", out)
        self.assertRegex(out, r"bare physics \(inline\) +\d+ +\d+x +1\.00x")
        self.assertRegex(out, r"\nsimulator +\d+ +\d+x +[\d.]+x")
        if importlib.util.find_spec("pygame"):
            for every in ("5th", "step"):
                self.assertRegex(out, rf"\nsimulator \+ draw every {every} +\d+ +\d+x +[\d.]+x")
            self.assertGreater(os.path.getsize(picture), 1000)
        self.assertIn("Lesson 1 as a node on a SimClock", out)
        for mode in ("DEBUG", "DEPLOYED"):
            self.assertRegex(out, rf"\n{mode} +[\d.]+ +\d+x")
        self.assertIn("target: a 60 s lesson runs >= 20x faster than real time", out)


if __name__ == "__main__":
    unittest.main()
