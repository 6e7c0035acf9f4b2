"""The Raspberry Pi install: the README's commands are the ones the project supports.

Running them takes a network and a Debian system; .ci/run runs the venv line
as the README writes it, and docs/raspberry-pi.md's live view line after it.
These checks are the fast part: the apt line names the Debian packages of
exactly SNR's dependencies and the extras the pip line asks for, the venv sees
them, no Pi line has pip compile anything on 32-bit Raspberry Pi OS, and nothing
tells anyone to force pip.
"""

import glob
import importlib.metadata
import os
import re
import shlex
import sys
import tempfile
import unittest
from typing import Any, Dict, List, Set
from unittest import mock

from snr import FoxgloveBridgeFactory
from snr.prelude import ConfigError
from snr.std_mods.io import PageReader
from tests.examples_support import ROOT

DEBIAN_PACKAGES: Dict[str, str] = {
    "dataclasses-json": "python3-dataclasses-json",
    "typing-extensions": "python3-typing-extensions",
    "pyserial": "python3-serial",
    "pygame": "python3-pygame",
    "lz4": "python3-lz4",
    "zstandard": "python3-zstandard",
    "matplotlib": "python3-matplotlib",
}
"""The one list of the PyPI packages that SNR's Pi lines take from Debian 12 (each new
enough): SNR's requirements, and what the ``mcap`` package requires."""

PI_WHEELS: Dict[str, List[str]] = {
    "websockets": [],
    "mcap": ["lz4", "zstandard"],
}
"""The PyPI packages a Pi line may take from PyPI, with what each requires in turn.

Each has a wheel that 32-bit Raspberry Pi OS (armv7l, Python 3.11) installs without
compiling: mcap is pure Python, websockets has armv7l wheels and a pure-Python one
(.ci/run checks the live view line's on PyPI). What they require must come from
here too, or from Debian: `test_what_the_pi_wheels_require_is_what_they_say`.
"""

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


def compiled_on_a_pi(page: str, project: Dict[str, Any]) -> List[str]:
    """What the ``pip install`` lines of ``page``'s bash blocks would compile on a 32-bit Pi.

    Each package a line installs (SNR's dependencies and those of the extras it
    names) must come from a Debian package that an apt line above it installs,
    or be one of `PI_WHEELS`, whose requirements are checked the same way.
    Returns one message per package that is neither, naming the line.
    """
    extras: Dict[str, List[str]] = project["optional-dependencies"]
    apt: Set[str] = set()
    problems: List[str] = []
    for block in re.findall(r"```bash\n(.*?)```", page, re.S):
        for line in block.splitlines():
            if line.startswith("sudo apt install "):
                apt.update(shlex.split(line)[3:])
            for step in line.split("&&"):
                words = shlex.split(step)
                if words[:2] != ["pip", "install"]:
                    continue
                target = re.fullmatch(r"\.(?:\[(.*)\])?", words[-1])
                assert target is not None, f"{line!r}: not an install of the checkout"
                needed = list(project["dependencies"])
                for extra in target.group(1).split(",") if target.group(1) else []:
                    if extra not in extras:
                        problems.append(f"{line!r}: pyproject.toml has no extra {extra!r}")
                    needed += extras.get(extra, [])
                names = [requirement_name(r) for r in needed if applies_on_debian(r)]
                while names:
                    name = names.pop()
                    if DEBIAN_PACKAGES.get(name) in apt:
                        continue  # Debian's package, with what it requires
                    if name in PI_WHEELS:
                        names += PI_WHEELS[name]
                        continue
                    problems.append(
                        f"{line!r} installs {name}, which no apt line above it provides "
                        "and which is not known to install on 32-bit Pi OS without "
                        "compiling (PI_WHEELS)"
                    )
    return problems


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

    def test_no_pi_line_has_pip_compile_anything_on_a_32_bit_pi(self) -> None:
        readme = read("README.md")
        readme_pi = readme[readme.index("## On a Raspberry Pi") :].split("\n## ")[0]
        pi_page = read("docs", "raspberry-pi.md")
        for name, page in ("README.md", readme_pi), ("docs/raspberry-pi.md", pi_page):
            with self.subTest(name):
                self.assertIn("pip install", page)
                self.assertEqual(compiled_on_a_pi(page, self.project), [])

    def test_the_check_finds_what_a_pi_would_compile(self) -> None:
        base = "sudo apt install " + " ".join(DEBIAN_PACKAGES[n] for n in DEBIAN_PACKAGES)
        apt = f"```bash\n{base}\n```\n"
        viz = "```bash\n. .venv/bin/activate && pip install -e '.[viz]'\n```\n"
        problems = "\n".join(compiled_on_a_pi(viz, self.project))
        for name in "lz4", "zstandard", "dataclasses-json":  # mcap's, and SNR's own
            self.assertIn(f"installs {name},", problems)
        self.assertNotIn("websockets", problems)
        self.assertEqual(compiled_on_a_pi(apt + viz, self.project), [])
        self.assertNotEqual(compiled_on_a_pi(viz + apt, self.project), [])  # apt too late
        unknown = "```bash\npip install -e '.[view,nosuch]'\n```\n"
        problems = "\n".join(compiled_on_a_pi(apt + unknown, self.project))
        self.assertIn("pyproject.toml has no extra 'nosuch'", problems)

    def test_what_the_pi_wheels_require_is_what_they_say(self) -> None:
        checked = 0
        for name, requires in PI_WHEELS.items():
            try:
                metadata = importlib.metadata.requires(name) or []
            except importlib.metadata.PackageNotFoundError:
                continue  # not installed here (a plain install): nothing to compare
            unconditional = [r for r in metadata if "extra ==" not in r]
            with self.subTest(name):
                self.assertEqual(sorted(map(requirement_name, unconditional)), sorted(requires))
            checked += 1
        if checked == 0:
            self.skipTest("none of PI_WHEELS is installed: pip install -e '.[viz]'")

    def test_viz_is_view_and_mcap(self) -> None:
        extras = self.project["optional-dependencies"]
        self.assertEqual(sorted(extras["viz"]), sorted(extras["view"] + extras["mcap"]))

    def test_the_pages_that_install_view_and_mcap_give_the_pi_page_s_lines(self) -> None:
        pi_page = read("docs", "raspberry-pi.md")
        for page in "viewing.md", "recording.md":
            text = read("docs", page)
            extras = re.findall(r"pip install '[\w.-]+\[(\w+)\]'", text)  # snr or a new name
            self.assertNotEqual(extras, [], page)
            for extra in extras:
                with self.subTest(page=page, extra=extra):
                    self.assertIn(f"pip install -e '.[{extra}]'", pi_page)
                    self.assertIn("raspberry-pi.md#the-live-view-and-mcap-recordings", text)
            for apt in re.findall(r"sudo apt install [a-z0-9 -]+", text):
                self.assertTrue(apt in pi_page, f"{page}: {apt!r} is not on the Pi page")

    def test_a_missing_package_s_message_names_the_extra_that_installs_it(self) -> None:
        extras = self.project["optional-dependencies"]
        hint = re.compile(r"pip install '[\w.-]*\[(\w+)\]'")
        hidden: Dict[str, Any] = {
            name: None for name in sys.modules if name.split(".")[0] in ("websockets", "mcap")
        }
        hidden.update({"websockets": None, "websockets.asyncio.server": None})
        hidden.update({"mcap": None, "mcap.stream_reader": None, "mcap.records": None})
        with mock.patch.dict(sys.modules, hidden):
            with self.assertRaises(ConfigError) as no_websockets:
                FoxgloveBridgeFactory(["depth_m"])
            with tempfile.TemporaryDirectory() as folder:
                path = os.path.join(folder, "dive.mcap")
                with open(path, "wb") as file:
                    file.write(b"\x89MCAP0\r\n")
                with self.assertRaises(ConfigError) as no_mcap:
                    PageReader(path)
        for package, caught in ("websockets", no_websockets), ("mcap", no_mcap):
            with self.subTest(package):
                extra = hint.search(str(caught.exception))
                assert extra is not None, str(caught.exception)
                names = [requirement_name(r) for r in extras[extra.group(1)]]
                self.assertEqual(names, [package], f"the extra {extra.group(1)!r}")

    def test_ci_runs_the_pi_page_s_live_view_line(self) -> None:
        ci = read(".ci", "run")
        self.assertIn(
            """view_line=$(grep -m1 -F "pip install -e '.[view]'" docs/raspberry-pi.md)""", ci
        )
        self.assertIn('bash -c "$view_line --seconds 2 --view-port 0"', ci)
        self.assertIn("Root-Is-Purelib", ci)
        pi_page = read("docs", "raspberry-pi.md")
        lines = [line for line in pi_page.splitlines() if "pip install -e '.[view]'" in line]
        self.assertEqual(len(lines), 1)  # so the grep finds the line of the bash block
        self.assertTrue(lines[0].endswith("python -m snr demo --view"), lines[0])
        self.assertIn(f"```bash\n{lines[0]}\n```", pi_page)

    def test_nothing_tells_anyone_to_force_pip(self) -> None:
        texts = ["README.md", ".ci/run", *glob.glob("docs/*.md", root_dir=ROOT)]
        texts += glob.glob("examples/**/README.md", root_dir=ROOT, recursive=True)
        self.assertGreater(len(texts), 10)
        for name in texts:
            self.assertNotIn(FORBIDDEN, read(name), name)


if __name__ == "__main__":
    unittest.main()
