"""The README's promises: its two set-up commands and its example robot."""

import os
import re
import shutil
import tempfile
import unittest

from tests.examples_support import ROOT, run_script

README = os.path.join(ROOT, "README.md")


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
                "pip install -e . && python -m snr demo",
                "pip install -e '.[dev]' && python -m pytest",
            ],
        )
        before = self.text[: first_block.start()].strip()
        self.assertEqual(before.count("\n"), 0, "only the title comes before the commands")

    def test_example_robot_runs_as_shown(self) -> None:
        code = re.search(r"```python\n(.*?)```", self.text, re.S)
        assert code is not None
        folder = tempfile.mkdtemp(prefix="snr-readme-")
        self.addCleanup(shutil.rmtree, folder, True)
        path = os.path.join(folder, "robot.py")
        with open(path, "w", encoding="utf-8") as f:
            f.write(code.group(1))
        result = run_script([path, "robot"], cwd=folder, timeout_s=20)
        self.assertEqual(result.returncode, 0, result.stderr)
        doubled = re.findall(r"\(store_page, '2x'\): \[Page\(key='2x', data=(\d+)", result.stdout)
        self.assertEqual(doubled, ["2", "4", "6"])


if __name__ == "__main__":
    unittest.main()
