"""The benchmarks in bench/ still run: each one with a tiny workload, no timing checked."""

from __future__ import annotations

import os
import unittest

from tests.examples_support import ROOT, run_script

BENCH = os.path.join(ROOT, "bench")


class TestLoopLatencyBench(unittest.TestCase):
    def test_prints_the_table_and_the_target(self) -> None:
        done = run_script(
            [
                os.path.join(BENCH, "bench_loop_latency.py"),
                "--samples=20",
                "--rounds=1",
                "--interval-ms=0.5",
            ],
            timeout_s=2.5,
        )
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


if __name__ == "__main__":
    unittest.main()
