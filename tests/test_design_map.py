"""The map in docs/design.md's "Layers" section names every module under snr/.

A newcomer reads that map before opening the code; this test keeps it true:
it fails when a module is added without a line on the map, or when the map
names a module that was moved or deleted.
"""

from __future__ import annotations

import re
import unittest
from pathlib import Path

__all__ = ["DesignMapTest"]

ROOT = Path(__file__).resolve().parent.parent
PACKAGE_LINE = re.compile(r"^(snr(?:\.\w+)*)(?:\s|$)")
MODULE_NAME = re.compile(r"\b(\w+)\.py\b")


def modules_on_the_map(design_text: str) -> set[str]:
    """Dotted names of the modules the Layers section's first block lists.

    A line that starts at column 0 with ``snr...`` opens a package; every
    ``name.py`` on it and on the indented lines after it is a module of
    that package. Example: ``snr.core  node.py`` gives ``snr.core.node``.
    """
    section = design_text.split("## Layers", 1)[1].split("\n## ", 1)[0]
    block = section.split("```", 2)[1]
    found: set[str] = set()
    package = ""
    for line in block.splitlines():
        opened = PACKAGE_LINE.match(line)
        if opened:
            package = opened.group(1)
        for name in MODULE_NAME.findall(line):
            if name != "__init__" and package:
                found.add(f"{package}.{name}")
    return found


def modules_on_disk() -> set[str]:
    """Dotted names of every module under snr/, packages' __init__ aside."""
    return {
        ".".join(path.relative_to(ROOT).with_suffix("").parts)
        for path in (ROOT / "snr").rglob("*.py")
        if path.name != "__init__.py" and "__pycache__" not in path.parts
    }


class DesignMapTest(unittest.TestCase):
    """docs/design.md's map of the layers matches the modules there are."""

    def test_every_module_is_on_the_map_and_nothing_else(self) -> None:
        text = (ROOT / "docs" / "design.md").read_text(encoding="utf-8")
        on_map = modules_on_the_map(text)
        on_disk = modules_on_disk()
        self.assertEqual(
            sorted(on_disk - on_map), [], "modules missing from the map in docs/design.md"
        )
        self.assertEqual(sorted(on_map - on_disk), [], "the map names modules that are gone")

    def test_the_reader_finds_a_missing_module(self) -> None:
        # The parser really reads packages: a module under the wrong package is not found.
        text = "## Layers\n```\nsnr.core      node.py\nsnr.prelude   task.py\n```\n## Next\n"
        self.assertEqual(modules_on_the_map(text), {"snr.core.node", "snr.prelude.task"})


if __name__ == "__main__":
    unittest.main()
