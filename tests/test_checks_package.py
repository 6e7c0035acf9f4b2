"""snr/core/checks/ is read second: the node loads its DEBUG helpers only when it uses them.

A student reads snr/core first; the helpers that explain mistakes sit in
snr/core/checks/. These tests keep the two apart: no checks module imports
``snr.core.node`` (so no import runs in a circle), a fresh ``import snr`` does
not load the DEBUG helpers, and a DEPLOYED node never loads them.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import unittest
from pathlib import Path
from typing import Dict, List

__all__ = ["TestChecksPackage"]

ROOT = Path(__file__).resolve().parent.parent
CHECKS = ROOT / "snr" / "core" / "checks"
DEBUG_HELPERS = [
    "snr.core.checks.node_checks",
    "snr.core.checks.class_checks",
    "snr.core.checks.wiring_checks",
    "snr.core.checks.watchdog",
]


def imported_modules(source: str) -> List[str]:
    """Every module ``source`` imports, anywhere in it (``if TYPE_CHECKING:`` too)."""
    found: List[str] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module is not None:
            found += [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
    return found


def loaded_after(code: str) -> Dict[str, bool]:
    """Which DEBUG helpers a fresh interpreter has loaded after running ``code``."""
    listed = f"{{m: m in sys.modules for m in {DEBUG_HELPERS!r}}}"
    script = f"{code}\nimport json, sys\nprint(json.dumps({listed}))"
    path = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env=dict(os.environ, PYTHONPATH=path),
        cwd=ROOT,
        timeout=60,
    )
    if result.returncode != 0:
        raise AssertionError(result.stderr)
    loaded: Dict[str, bool] = json.loads(result.stdout.strip().splitlines()[-1])
    return loaded


class TestChecksPackage(unittest.TestCase):
    def test_no_checks_module_imports_the_node(self) -> None:
        modules = sorted(CHECKS.glob("*.py"))
        self.assertGreater(len(modules), 5)
        for path in modules:
            with self.subTest(module=path.name):
                source = path.read_text(encoding="utf-8")
                self.assertNotIn("snr.core.node", imported_modules(source))

    def test_the_reader_sees_an_import_under_type_checking(self) -> None:
        # The scan above would fail for the import the watchdog had before.
        source = "if TYPE_CHECKING:\n    from snr.core.node import Node\n"
        self.assertIn("snr.core.node", imported_modules(source))
        self.assertIn("snr.core.node", imported_modules("def f():\n    import snr.core.node\n"))

    def test_import_snr_loads_no_debug_helper(self) -> None:
        self.assertEqual([m for m, yes in loaded_after("import snr").items() if yes], [])

    def test_a_deployed_node_loads_none_and_a_debug_node_all(self) -> None:
        make = (
            "import snr\n"
            "factories = {{'robot': [snr.TimeoutLoopFactory(seconds=1)]}}\n"
            "node = snr.Node('robot', snr.Config(factories, mode=snr.Mode.{}))\n"
        )
        deployed = loaded_after(make.format("DEPLOYED") + "assert node.watchdog is None\n")
        self.assertEqual([m for m, yes in deployed.items() if yes], [])
        debug = loaded_after(make.format("DEBUG") + "assert node.watchdog is not None\n")
        self.assertEqual([m for m, yes in debug.items() if not yes], [])


if __name__ == "__main__":
    unittest.main()
