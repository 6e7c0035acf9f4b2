"""SNR as a package: its name, the install lines it prints, its version and its licence.

SNR's distribution is ``snr-robotics`` (``snr`` on the package index is another
project) and is imported as ``snr``. Every line that tells a user what to
install comes from ``snr.prelude.install``; these tests pin what it builds, that
no user-facing text still gives the old name, that ``snr --version`` answers
with the installed version, and that the metadata carries the licence.
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import io
import re
import subprocess
import sys
import unittest
from pathlib import Path
from typing import Any, Dict, List

import snr
from snr.__main__ import main
from snr.prelude.install import DISTRIBUTION, install_hint, upgrade_hint
from tests.examples_support import ROOT, script_env
from tests.optional import EXTRA_FOR, reason

OLD_NAME = re.compile(r"""pip install (?:-U |--upgrade )?snr(?![-\w])|['"]snr\[""")
"""An install line with the old distribution name: ``pip install snr``, ``'snr[zenoh]'``."""

TEXT_SUFFIXES = {".py", ".md", ".toml", ".txt", ".json", ".sh", ".ino", ".cfg"}


def old_name_lines(text: str) -> List[str]:
    """The lines of ``text`` that tell a user to install SNR by its old name."""
    return [line.strip() for line in text.splitlines() if OLD_NAME.search(line)]


def pyproject() -> Dict[str, Any]:
    """pyproject.toml, read with tomllib (Python 3.11 and newer)."""
    import tomllib

    with open(Path(ROOT, "pyproject.toml"), "rb") as f:
        return tomllib.load(f)


def hinted_extras(source: str) -> List[str]:
    """The extras the ``install_hint("...")`` calls in ``source`` name."""
    return re.findall(r"""install_hint\(\s*['"]([\w-]+)['"]\s*\)""", source)


class TestInstallHint(unittest.TestCase):
    def test_the_hint_names_the_distribution_and_quotes_the_extra(self) -> None:
        self.assertEqual(DISTRIBUTION, "snr-robotics")
        self.assertEqual(install_hint("zenoh"), "pip install 'snr-robotics[zenoh]'")
        self.assertEqual(install_hint("controller"), "pip install 'snr-robotics[controller]'")
        self.assertEqual(install_hint(), "pip install snr-robotics")
        self.assertEqual(upgrade_hint(), "pip install -U snr-robotics")

    def test_the_tests_skip_reasons_give_the_same_hint_as_snr(self) -> None:
        self.assertEqual(reason("zenoh"), "needs zenoh: pip install 'snr-robotics[zenoh]'")
        self.assertEqual(reason("mcap"), f"needs mcap: {install_hint('mcap')}")
        self.assertEqual(reason("hypothesis"), f"needs hypothesis: {install_hint('dev')}")

    @unittest.skipIf(sys.version_info < (3, 11), "reads pyproject.toml with tomllib")
    def test_every_hinted_extra_exists_and_the_name_is_the_project_s(self) -> None:
        project = pyproject()["project"]
        self.assertEqual(project["name"], DISTRIBUTION)
        extras = set(project["optional-dependencies"])
        hinted = set(EXTRA_FOR.values())
        for folder in ["snr", "bench", "tests"]:
            for path in sorted(Path(ROOT, folder).rglob("*.py")):
                hinted.update(hinted_extras(path.read_text(encoding="utf-8")))
        self.assertGreaterEqual(
            hinted, {"controller", "docs", "fast", "mcap", "serial", "view", "zenoh"}
        )
        self.assertEqual(sorted(hinted - extras), [], "hints name extras pyproject.toml lacks")


class TestNoOldName(unittest.TestCase):
    def test_the_check_finds_the_old_name_and_passes_the_new(self) -> None:
        old = [
            "pip install snr",
            "run: pip install -U snr now.",
            "needs `pip install 'snr[viz]'`",
            'extras = ["snr[zenoh]"]',
        ]
        self.assertEqual(old_name_lines("\n".join(old)), old)
        new = f"{install_hint()}\n{upgrade_hint()}\n{install_hint('viz')}\npip install snr-robotics"
        self.assertEqual(old_name_lines(new + "\npip install -e '.[dev]'\nimport snr"), [])

    def test_no_user_facing_line_gives_the_old_name(self) -> None:
        root = Path(ROOT)
        files = [root / "README.md", root / "pyproject.toml"]
        for folder in ["snr", "docs", "examples", "bench", "tests"]:
            files += [
                p
                for p in (root / folder).rglob("*")
                if p.suffix in TEXT_SUFFIXES and "api" not in p.relative_to(root).parts[:2]
            ]
        self.assertGreater(len(files), 100)
        found = []
        for path in files:
            if path.name == Path(__file__).name:
                continue  # its own examples of the old name
            for line in old_name_lines(path.read_text(encoding="utf-8", errors="replace")):
                found.append(f"{path.relative_to(root)}: {line}")
        self.assertEqual(found, [], f"say {DISTRIBUTION}, as snr.prelude.install does")


class TestVersion(unittest.TestCase):
    def test_snr_version_is_the_installed_distribution_s(self) -> None:
        try:
            installed = importlib.metadata.version(DISTRIBUTION)
        except importlib.metadata.PackageNotFoundError:
            self.fail(f"{DISTRIBUTION} is not installed: run `pip install -e .` in the checkout")
        self.assertEqual(snr.__version__, installed, "reinstall: pip install -e .")

    def test_python_m_snr_version_prints_the_name_and_version_and_exits_0(self) -> None:
        result = subprocess.run(
            [sys.executable, "-m", "snr", "--version"],
            capture_output=True,
            text=True,
            env=script_env(),
            timeout=60,
        )
        self.assertEqual((result.returncode, result.stderr), (0, ""))
        self.assertEqual(result.stdout, f"snr-robotics {snr.__version__}\n")

    def test_the_snr_command_answers_version_too(self) -> None:
        command = Path(sys.executable).with_name("snr.exe" if sys.platform == "win32" else "snr")
        if not command.exists():
            self.skipTest(f"no snr command beside {sys.executable}")
        result = subprocess.run(
            [str(command), "--version"], capture_output=True, text=True, timeout=60
        )
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(result.stdout, f"snr-robotics {snr.__version__}\n")

    def test_the_version_subcommand_prints_the_number(self) -> None:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.assertEqual(main(["version"]), 0)
        self.assertEqual(out.getvalue(), f"{snr.__version__}\n")

    @unittest.skipIf(sys.version_info < (3, 11), "reads pyproject.toml with tomllib")
    def test_the_version_is_written_in_one_place(self) -> None:
        config = pyproject()
        self.assertNotIn("version", config["project"])
        self.assertIn("version", config["project"]["dynamic"])
        self.assertEqual(config["tool"]["hatch"]["version"], {"path": "snr/__init__.py"})
        init = Path(ROOT, "snr", "__init__.py").read_text(encoding="utf-8")
        self.assertEqual(re.findall(r"^__version__ = \"(.*)\"$", init, re.M), [snr.__version__])


class TestLicence(unittest.TestCase):
    def test_the_licence_file_is_mit(self) -> None:
        text = Path(ROOT, "LICENSE").read_text(encoding="utf-8")
        self.assertTrue(text.startswith("MIT License\n"), text[:40])
        self.assertIn("Copyright (c) 2021-2026 SNR developers", text)

    def test_the_installed_metadata_says_mit_and_names_the_file(self) -> None:
        metadata = importlib.metadata.metadata(DISTRIBUTION)
        self.assertEqual(metadata["License-Expression"], "MIT")
        self.assertEqual(metadata.get_all("License-File"), ["LICENSE"])

    @unittest.skipIf(sys.version_info < (3, 11), "reads pyproject.toml with tomllib")
    def test_pyproject_uses_the_licence_expression(self) -> None:
        project = pyproject()["project"]
        self.assertEqual((project["license"], project["license-files"]), ("MIT", ["LICENSE"]))
        ci = Path(ROOT, ".ci", "run").read_text(encoding="utf-8")
        self.assertTrue("python -m pip wheel" in ci, ".ci/run builds the wheel to check it")


class TestPygameOrPygameCe(unittest.TestCase):
    @unittest.skipIf(sys.version_info < (3, 11), "reads pyproject.toml with tomllib")
    def test_the_controller_extra_takes_pygame_ce_where_pygame_has_no_wheels(self) -> None:
        extras = pyproject()["project"]["optional-dependencies"]
        either = [
            "pygame>=2.1; python_version < '3.14'",
            "pygame-ce>=2.5; python_version >= '3.14'",
        ]
        self.assertEqual(extras["controller"], either)
        self.assertEqual([r for r in extras["dev"] if r.startswith("pygame")], either)

    def test_the_missing_pygame_messages_say_either_works(self) -> None:
        from snr.extras.controller import controller
        from snr.extras.sim import draw

        for hint in [controller._INSTALL_HINT, draw.INSTALL_HINT]:
            self.assertIn(install_hint("controller"), hint)
            self.assertIn("pip install pygame-ce", hint)
            self.assertIn("either works", hint)


if __name__ == "__main__":
    unittest.main()
