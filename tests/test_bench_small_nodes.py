"""bench/bench_small_nodes.py still runs: a tiny workload, no timing checked."""

from __future__ import annotations

import os
import re
import unittest

from tests.examples_support import ROOT, run_script

BENCH = os.path.join(ROOT, "bench")


class TestSmallNodesBench(unittest.TestCase):
    def test_prints_the_table_and_the_target(self) -> None:
        done = run_script(
            [os.path.join(BENCH, "bench_small_nodes.py"), "--rounds=3", "--warmup=1"],
            timeout_s=20,
        )
        self.assertEqual(done.returncode, 0, done.stderr)
        out = done.stdout
        self.assertRegex(out, r"case +p50 ms +p99 ms +max ms +vs bare p50 +CPU p50 ms")
        self.assertRegex(out, r"bare thread start/join( +[\d.]+){3} +1\.0x +[\d.]+")
        for case in ("TimeoutLoopFactory()", "loop + expector, TEST", "loop + expector, DEBUG"):
            self.assertIn(case, out)
            self.assertRegex(out, rf"  {re.escape(case)}: p99 [\d.]+ ms \((met|MISSED)\)")
        self.assertIn("Target: every node starts, runs and stops with p99 < 20 ms", out)


if __name__ == "__main__":
    unittest.main()
