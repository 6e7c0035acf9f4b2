"""The Raspberry Pi install: the README's commands are the ones the project supports.

Running them takes a network and a Debian system; .ci/run runs the venv line
as the README writes it. These checks are the fast part: the apt line names the
Debian packages of exactly SNR's dependencies and the extras the pip line asks
for, the venv sees them, and nothing tells anyone to force pip.
"""

import glob
import os
import re
import shlex
import sys
import unittest
from typing import Dict, List

from tests.examples_support import ROOT

DEBIAN_PACKAGES: Dict[str, str] = {
    "dataclasses-json": "python3-dataclasses-json",
    "typing-extensions": "python3-typing-extensions",
    "pyserial": "python3-serial",
    "pygame": "python3-pygame",
}
"""The one list of SNR's PyPI requirements that Debian 12 packages new enough."""

FORBIDDEN = "--break-system-packages"

DEBIAN_PYTHON = (3, 11)
"""Debian 12's Python: requirements whose marker leaves it out are not asked for there."""


def read(*parts: str) -> str:
    with open(os.path.join(ROOT, *parts), encoding="utf-8") as f:
        return f.read()


def pi_block(markdown: str, after: str) -> List[str]:
    """The lines of the first ```bash block after the heading ``after``."""
    start = markdown.index(after)
    block = re.search(r"```bash\n(.*?)```", markdown[start:], re.S)
    assert block is not None, f"no bash block after {after!r}"
    return block.group(1).splitlines()


def applies_on_debian(requirement: str) -> bool:
    """False for a requirement such as ``"pygame-ce>=2.5; python_version >= '3.14'"``."""
    marker = requirement.partition(";")[2].strip()
    if not marker:
        return True
    match = re.fullmatch(r"python_version\s*(<|>=)\s*'(\d+)\.(\d+)'", marker)
    assert match is not None, f"teach this test the marker {marker!r}"
    operator, major, minor = match.groups()
    debian_is_older = (int(major), int(minor)) > DEBIAN_PYTHON
    return debian_is_older if operator == "<" else not debian_is_older


def requirement_name(requirement: str) -> str:
    """``"pyserial>=3.5"`` -> ``"pyserial"``."""
    match = re.match(r"[A-Za-z0-9_.\-]+", requirement)
    assert match is not None, requirement
    return match.group(0).lower()


@unittest.skipIf(sys.version_info < (3, 11), "reads pyproject.toml with tomllib")
class TestRaspberryPiInstall(unittest.TestCase):
    def setUp(self) -> None:
        import tomllib

        self.project = tomllib.loads(read("pyproject.toml"))["project"]
        self.readme = pi_block(read("README.md"), "## On a Raspberry Pi")
        self.docs = pi_block(read("docs", "raspberry-pi.md"), "## Install")
        self.apt, self.venv = self.readme[0], self.readme[1]

    def test_the_readme_and_the_pi_page_give_the_same_commands(self) -> None:
        self.assertEqual(self.docs, self.readme[:2])
        self.assertIn("sudo usermod -a -G dialout $USER", read("docs", "raspberry-pi.md"))
        self.assertEqual(self.readme[2], "sudo usermod -a -G dialout $USER")

    def test_the_venv_sees_debian_s_packages_and_runs_the_demo(self) -> None:
        steps = [step.strip() for step in self.venv.split("&&")]
        self.assertEqual(
            steps[:2], ["python3 -m venv --system-site-packages .venv", ". .venv/bin/activate"]
        )
        self.assertTrue(steps[2].startswith("pip install -e '.["), steps[2])
        self.assertEqual(steps[3], "python -m snr demo")

    def test_apt_installs_the_debian_packages_of_what_pip_would_ask_for(self) -> None:
        words = shlex.split(self.apt)
        self.assertEqual(words[:3], ["sudo", "apt", "install"])
        pip_target = shlex.split(self.venv.split("&&")[2])[-1]  # .[serial,controller]
        extras = re.fullmatch(r"\.\[(.*)\]", pip_target)
        assert extras is not None, pip_target
        needed = list(self.project["dependencies"])
        for extra in extras.group(1).split(","):
            self.assertIn(extra, self.project["optional-dependencies"])
            needed += self.project["optional-dependencies"][extra]
        names = [requirement_name(r) for r in needed if applies_on_debian(r)]
        missing = [name for name in names if name not in DEBIAN_PACKAGES]
        self.assertEqual(missing, [], "add their Debian packages to DEBIAN_PACKAGES")
        expected = ["python3-venv"] + [DEBIAN_PACKAGES[name] for name in names]
        self.assertEqual(words[3:], expected)

    def test_ci_runs_the_readme_s_venv_line(self) -> None:
        ci = read(".ci", "run")
        self.assertIn("pi_line=$(grep -m1 -e '--system-site-packages' README.md)", ci)
        self.assertIn('bash -c "$pi_line --seconds 2"', ci)
        lines = [line for line in read("README.md").splitlines() if "--system-site" in line]
        self.assertEqual(lines, [self.venv])  # so the grep finds this line

    def test_nothing_tells_anyone_to_force_pip(self) -> None:
        texts = ["README.md", ".ci/run", *glob.glob("docs/*.md", root_dir=ROOT)]
        texts += glob.glob("examples/**/README.md", root_dir=ROOT, recursive=True)
        self.assertGreater(len(texts), 10)
        for name in texts:
            self.assertNotIn(FORBIDDEN, read(name), name)


if __name__ == "__main__":
    unittest.main()
