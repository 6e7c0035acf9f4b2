"""examples/moving_average: the student's filter (thesis 5.2, listings A.1-A.3)."""

import contextlib
import io
import unittest

from snr import TaskType
from tests.examples_support import example_path, load_module, run_script
from tests.helpers import StopWhenFactory
from tests.quiet import captured_logs

FOLDER = example_path("moving_average")


class TestMovingAverageExample(unittest.TestCase):
    def test_the_examples_own_tests_pass(self) -> None:
        """`python -m unittest test_moving_average`, run from the example's folder."""
        done = run_script(["-m", "unittest", "-q", "test_moving_average"], cwd=FOLDER)
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertIn("Ran 4 tests", done.stderr)
        self.assertIn("OK", done.stderr)

    def test_demo_prints_raw_and_filtered_readings(self) -> None:
        demo = load_module(f"{FOLDER}/filter_demo.py", "moving_average_filter_demo")
        readings = demo.noisy_depths(10)
        out = io.StringIO()
        # A DEBUG node: its INFO lines (e.g. "terminated: Timeout") are kept here.
        with contextlib.redirect_stdout(out), captured_logs("snr.filter_demo"):
            # 10 s is only a bound: the node stops once the tenth mean is shown.
            config = demo.make_config(readings, 0.0, 10.0)
            config.factories["filter_demo"].append(
                StopWhenFactory((TaskType.store_page, "depth"), count=10)
            )
            demo.SynchronousRunner("filter_demo", config).run()
        lines = out.getvalue().splitlines()
        # Each line ends with the mean of the newest five readings so far.
        expected = [sum(readings[max(0, i - 4) : i + 1]) / min(i + 1, 5) for i in range(10)]
        self.assertEqual([line.split("filtered")[1] for line in lines],
                         [f" {mean:5.2f} m" for mean in expected])  # fmt: skip
        self.assertTrue(lines[-1].startswith(f"raw {readings[-1]:5.2f} m"))


if __name__ == "__main__":
    unittest.main()
