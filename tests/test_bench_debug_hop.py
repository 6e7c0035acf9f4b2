"""bench/bench_debug_hop.py still runs and prints a row per set-up (no timing checked)."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import unittest

from tests.examples_support import ROOT
from tests.quiet import captured_logs


class TestDebugHopBench(unittest.TestCase):
    def test_prints_a_row_per_set_up(self) -> None:
        path = os.path.join(ROOT, "bench", "bench_debug_hop.py")
        spec = importlib.util.spec_from_file_location("bench_debug_hop", path)
        assert spec is not None and spec.loader is not None
        bench = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(bench)
        out = io.StringIO()
        with contextlib.redirect_stdout(out), captured_logs("snr"):
            bench.main(["--hops=200", "--rounds=1"])
        text = out.getvalue()
        self.assertIn("Node's thread, CPU per hop (200 hops, 1 interleaved rounds)", text)
        for name in bench.SETUPS:
            self.assertRegex(text, rf"\n{name} +[\d.]+ +[\d.]+-[\d.]+ +[+-][\d.]+\n")
        self.assertRegex(text, r"\nDEPLOYED +[\d.]+ +[\d.]+-[\d.]+ +\+0\.00\n")


if __name__ == "__main__":
    unittest.main()
