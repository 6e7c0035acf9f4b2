"""The README's promises: its two set-up commands and its example robot."""

import os
import re
import shutil
import tempfile
import unittest

from tests.examples_support import ROOT, StartedScript, early, start_script

README = os.path.join(ROOT, "README.md")


def without_ages(text: str) -> str:
    """``text`` with every page's age, e.g. ``(0.0 s ago)``, replaced by ``(AGE)``."""
    return re.sub(r"\(\d+\.\d s ago\)", "(AGE)", text).strip()


def _start_readme_robot() -> "tuple[str, StartedScript]":
    """The README's robot, written to a temp folder and started (it runs for 1 s)."""
    with open(README, encoding="utf-8") as f:
        code = re.search(r"```python\n(.*?)```", f.read(), re.S)
    assert code is not None
    folder = tempfile.mkdtemp(prefix="snr-readme-")
    path = os.path.join(folder, "robot.py")
    with open(path, "w", encoding="utf-8") as f:
        f.write(code.group(1))
    return folder, start_script([path, "robot"], cwd=folder, timeout_s=20)


# Started when this module is imported (`early`); it runs while other tests do.
README_ROBOT = early(_start_readme_robot)


def setUpModule() -> None:
    README_ROBOT()  # (started already, unless in a pytest-xdist worker)


class TestReadme(unittest.TestCase):
    def setUp(self) -> None:
        with open(README, encoding="utf-8") as f:
            self.text = f.read()

    def test_starts_with_the_two_set_up_commands(self) -> None:
        first_block = re.search(r"```bash\n(.*?)```", self.text, re.S)
        assert first_block is not None
        self.assertEqual(
            first_block.group(1).splitlines(),
            [
                "python3 -m venv .venv && . .venv/bin/activate && pip install -e . "
                "&& python -m snr demo",
                "python3 -m venv .venv && . .venv/bin/activate && pip install -e '.[dev]' "
                "&& python -m pytest",
            ],
        )

    def test_ci_runs_the_readme_test_command_as_written(self) -> None:
        first_block = re.search(r"```bash\n(.*?)```", self.text, re.S)
        assert first_block is not None
        test_command = first_block.group(1).splitlines()[1]
        with open(os.path.join(ROOT, ".ci", "run"), encoding="utf-8") as f:
            ci_lines = [line.strip() for line in f]
        self.assertIn(test_command, ci_lines)
        before = self.text[: first_block.start()].strip()
        self.assertEqual(before.count("\n"), 0, "only the title comes before the commands")

    def test_example_robot_runs_as_shown(self) -> None:
        folder, robot = README_ROBOT()
        result = robot.result()
        self.addCleanup(shutil.rmtree, folder, True)
        self.assertEqual(result.returncode, 0, result.stderr)
        # The output block after the code, exactly, but for the pages' ages.
        shown = re.search(r"```python\n.*?```.*?```text\n(.*?)```", self.text, re.S)
        assert shown is not None
        self.assertEqual(without_ages(result.stdout), without_ages(shown.group(1)))
        self.assertEqual(len(result.stdout.splitlines()), 3, result.stdout)


if __name__ == "__main__":
    unittest.main()
