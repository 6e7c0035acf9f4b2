"""`python -m snr demo`: it ships inside the package, and its screen is quiet.

The demo must run after a plain ``pip install`` (no source checkout). The
build backend, hatchling, puts every file of the ``snr/`` folder into the
wheel, and the guide's pages (``docs/*.md``) as ``snr/guide/``, and nothing
else, so the tests check that pyproject.toml still says so, copy those files
the way an install does, and run the demo from that copy with the checkout
nowhere on the path. CI (``.ci/run``) also installs the package into a fresh
virtualenv with ``pip install .`` and runs the demo, and builds the docs, there.
"""

import os
import re
import shutil
import tempfile
import unittest
from pathlib import Path
from typing import Any, List, Tuple

from tests.examples_support import ROOT, StartedScript, early, script_env, start_script

TELEMETRY = re.compile(r"t=\s*([\d.]+) s \| depth\s+([\d.]+) m \| heading\s+([\d.]+)°")

# Runs `python -m snr demo` after checking that snr is the installed copy.
RUN_DEMO = (
    "import runpy, sys\n"
    "import snr\n"
    "assert snr.__file__.startswith(sys.argv[1]), 'snr came from ' + snr.__file__\n"
    "sys.argv = ['snr', 'demo', *sys.argv[2:]]\n"
    "runpy.run_module('snr', run_name='__main__', alter_sys=True)\n"
)


def telemetry_lines(output: str) -> List[Any]:
    return [tuple(float(v) for v in m.groups()) for m in TELEMETRY.finditer(output)]


def log_lines(stderr: str, level: str) -> List[str]:
    return [line for line in stderr.splitlines() if f" {level}: " in line]


def _installed_copy() -> Path:
    """The ``snr/`` folder alone (and the guide), as an install puts it, in a temp folder."""
    folder = Path(tempfile.mkdtemp(prefix="snr-installed-"))
    lib = folder / "site-packages"
    shutil.copytree(Path(ROOT, "snr"), lib / "snr", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(Path(ROOT, "docs"), lib / "snr" / "guide", ignore=shutil.ignore_patterns("api"))
    return folder


def _start_package_demo() -> Tuple[Path, StartedScript]:
    """The installed copy, and the demo started from it."""
    installed = _installed_copy()
    return installed, start_script(
        ["-c", RUN_DEMO, str(installed / "site-packages"), "--seconds", "2.5"],
        cwd=str(installed),
        timeout_s=40,
        env=script_env({"PYTHONPATH": str(installed / "site-packages")}),
    )


# Both demo runs start when this module is imported (`early`) and run while
# other tests do: each takes seconds of waiting, which the suite then pays only once.
PACKAGE_DEMO = early(_start_package_demo)
VERBOSE_DEMO = early(
    lambda: start_script(["-m", "snr", "demo", "--seconds", "0.6", "--verbose"], timeout_s=40)
)


def setUpModule() -> None:
    PACKAGE_DEMO()  # (started already, unless in a pytest-xdist worker)
    VERBOSE_DEMO()


class TestDemoShipsInThePackage(unittest.TestCase):
    """The ``snr/`` folder alone, as an install puts it, run from a folder outside the checkout."""

    folder: Path
    lib: Path

    @classmethod
    def setUpClass(cls) -> None:
        cls.folder = PACKAGE_DEMO()[0]
        cls.lib = cls.folder / "site-packages"

    @classmethod
    def tearDownClass(cls) -> None:
        PACKAGE_DEMO()[1].result()  # the demo has finished with the folder
        shutil.rmtree(cls.folder, ignore_errors=True)

    def test_the_wheel_is_the_whole_snr_folder_and_the_guide(self) -> None:
        """hatchling ships snr/ and docs/ (as snr/guide/), all their files, nothing else."""
        text = Path(ROOT, "pyproject.toml").read_text(encoding="utf-8")
        self.assertIn('build-backend = "hatchling.build"', text, "update this test's copy")
        self.assertIn('only-include = ["snr", "docs"]', text)
        self.assertIn('dev-mode-dirs = ["."]', text, "pip install -e must stay a .pth entry")
        self.assertRegex(
            text, r'\[tool\.hatch\.build\.targets\.wheel\.sources\]\n"docs" = "snr/guide"\n'
        )
        files = {p.relative_to(self.lib).as_posix() for p in self.lib.rglob("*") if p.is_file()}
        for name in ["__init__.py", "run.py", "system.py", "urov.py"]:
            self.assertIn(f"snr/extras/demo/{name}", files)
        self.assertIn("snr/py.typed", files)
        self.assertIn("snr/guide/tutorial.md", files)
        self.assertEqual(sorted(os.listdir(self.lib)), ["snr"], "no examples/ beside it")

    def test_the_installed_copy_finds_its_guide(self) -> None:
        import snr.extras.docs.docsite

        self.assertEqual(
            snr.extras.docs.docsite.find_guide(self.lib / "snr"), self.lib / "snr" / "guide"
        )

    def test_the_demo_runs_from_the_package_alone(self) -> None:
        """CI's smoke run, on the installed copy: a banner and the telemetry, no log chatter."""
        result = PACKAGE_DEMO()[1].result()
        self.assertEqual(result.returncode, 0, result.stderr)
        out = result.stdout.splitlines()
        self.assertTrue(out and out[0].startswith("SNR demo: "), result.stdout)
        lines = telemetry_lines(result.stdout)
        self.assertGreaterEqual(len(lines), 2, result.stdout + result.stderr)
        self.assertEqual(len(out), 1 + len(lines), "the banner, then only telemetry")
        self.assertGreater(lines[-1][1], lines[0][1])  # the pilot script dives
        self.assertEqual(log_lines(result.stderr, "INFO"), [], "no chatter by default")
        self.assertNotIn("Lost the link", result.stderr, "an orderly end is no lost link")
        self.assertNotIn("Traceback", result.stderr)


class TestVerboseDemo(unittest.TestCase):
    def test_verbose_shows_the_nodes_log(self) -> None:
        result = VERBOSE_DEMO().result()
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("Listening for sockets clients on 127.0.0.1:", result.stderr)
        self.assertIn("Connected to the sockets server", result.stderr)
        self.assertIn("No serial device: the motor board", result.stderr)
        self.assertIn("terminated: Timeout", result.stderr)
        self.assertNotIn("--verbose", result.stdout.splitlines()[0], "no hint once verbose")
        self.assertEqual(log_lines(result.stderr, "WARNING"), [], result.stderr)


if __name__ == "__main__":
    unittest.main()
