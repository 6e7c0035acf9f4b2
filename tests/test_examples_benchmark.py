"""examples/benchmark: the stress benchmark of thesis 5.4 (listing A.5), run short."""

import contextlib
import io
import re
import unittest
from unittest import mock

from tests.examples_support import example_path, load_module, run_script, script_env
from tests.quiet import captured_logs

BENCH = example_path("benchmark", "bench_stress_endpoint_fac.py")
TIME_TARGET_S = 0.3


class TestBenchmarkExample(unittest.TestCase):
    def run_listing(self) -> str:
        """Run the listing's test case with a short time target; its printed output."""
        bench = load_module(BENCH, "benchmark_example")
        suite = unittest.defaultTestLoader.loadTestsFromTestCase(bench.BenchStressEndpointFac)
        out = io.StringIO()
        # The listing's factory returns None once it is limited, and says so in a warning.
        short = mock.patch.object(bench, "TIME_TARGET_S", TIME_TARGET_S)
        with short, contextlib.redirect_stdout(out), captured_logs("snr.test"):
            result = unittest.TextTestRunner(stream=io.StringIO(), verbosity=0).run(suite)
        self.assertTrue(result.wasSuccessful(), result.failures + result.errors)
        self.assertEqual(result.testsRun, 2)
        return out.getvalue()

    def test_prints_the_figures_and_profile_of_listing_5_2(self) -> None:
        printed = self.run_listing()
        figures = dict(
            (label, float(value))
            for value, label in re.findall(r"\t([\d.]+) (?:ms )?([a-z ]+)\n", printed)
        )
        self.assertGreater(figures["stressor endpoints"], 10)  # the node really was stressed
        self.assertGreaterEqual(figures["stressor factory calls"], figures["stressor endpoints"])
        self.assertIn(f"Terminate expected at {TIME_TARGET_S * 1000:.0f} ms", printed)
        self.assertGreaterEqual(figures["terminate handled"], TIME_TARGET_S * 1000)
        self.assertGreaterEqual(figures["total time"], figures["terminate handled"])
        self.assertIn("Times called,          Avg runtime, Task/Loop type,", printed)
        self.assertRegex(printed, r"\d+ x +[\d.]+ us -> +[\d.]+%: \(event, 'stress'\)")
        self.assertRegex(printed, r"\(event, 'add_component'\):snr.core.node")
        self.assertRegex(printed, r"ms: \S+BenchStressEndpointFac.test_stress_endpoint\n")
        self.assertRegex(printed, r"ms: \S+BenchStressEndpointFac.test_stress_endpoint_init\n")

    def test_runs_as_a_script(self) -> None:
        done = run_script([BENCH], env=script_env({"SNR_BENCH_SECONDS": "0.2"}))
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertIn("Ran 2 tests", done.stderr)


if __name__ == "__main__":
    unittest.main()
