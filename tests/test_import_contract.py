"""The import contract between SNR's kernel and its extras (docs/design.md, "Layers").

* The kernel (every module under ``snr/`` outside ``snr/extras/``) never
  imports ``snr.extras``. ``snr/__init__.py`` may name extras, but only in
  its table of names loaded on first use (``_LAZY``) and under
  ``if TYPE_CHECKING:``, so that ``import snr`` loads none. The kernel
  reaches an extra only through an entry point (``snr/core/plugins.py``).
* An extra imports the kernel's public names (no name starting with ``_``,
  from no module whose name starts with ``_``), its own package, and the
  other extras it builds on (`BUILDS_ON`).

The checks read the source (``ast``); nothing is imported.
"""

from __future__ import annotations

import ast
import unittest
from pathlib import Path
from typing import Dict, Iterator, List, Set, Tuple

__all__ = ["ImportContractTest", "imports_of"]

ROOT = Path(__file__).resolve().parent.parent
SNR = ROOT / "snr"
EXTRAS = SNR / "extras"

BUILDS_ON: Dict[str, Set[str]] = {
    "demo": {"controller", "lessons", "sim", "viz"},
    "lessons": {"sim"},
    "sim": {"controller"},
}
"""The other extras an extra may import: the demo runs the simulator, the live view and
lesson 1's solution; the lessons run in the simulator, whose window is driven by the
keyboard joystick."""

Import = Tuple[int, str, List[str]]
"""An import: its line, the module, and the names taken from it (empty for ``import m``)."""


def module_name(path: Path) -> str:
    """``snr/extras/zenoh/comms.py`` -> ``snr.extras.zenoh.comms`` (a package: its folder)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports_of(path: Path, source: str) -> Iterator[Import]:
    """Every import in ``source`` (the file ``path``), relative ones made absolute.

    Example::

        list(imports_of(Path("snr/x.py"), "from snr.core import Node"))
        # [(1, 'snr.core', ['Node'])]
    """
    package = module_name(path)
    if path.name != "__init__.py":
        package = package.rpartition(".")[0]
    for node in ast.walk(ast.parse(source, str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, []
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                module = ".".join(base + ([module] if module else []))
            yield node.lineno, module, [alias.name for alias in node.names]


def _is_extras(module: str) -> bool:
    return module == "snr.extras" or module.startswith("snr.extras.")


def _allowed_lines_of_the_face(source: str) -> Set[int]:
    """The lines of snr/__init__.py where extras may be named: ``_LAZY`` and TYPE_CHECKING."""
    lines: Set[int] = set()
    for node in ast.parse(source).body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            lines.update(range(node.lineno, (node.end_lineno or node.lineno) + 1))
    return lines


def kernel_problems(files: Dict[Path, str]) -> List[str]:
    """``file:line: ...`` for each kernel module that imports an extra."""
    problems: List[str] = []
    for path, source in sorted(files.items()):
        if EXTRAS in path.parents:
            continue
        allowed = _allowed_lines_of_the_face(source) if path == SNR / "__init__.py" else set()
        for line, module, names in imports_of(path, source):
            targets = [module] + [f"{module}.{name}" for name in names]
            if any(_is_extras(t) for t in targets) and line not in allowed:
                problems.append(
                    f"{path.relative_to(ROOT)}:{line}: the kernel imports {module!r}; "
                    "the kernel never imports an extra: reach it through an entry point "
                    "(snr/core/plugins.py), or move this code into the extra"
                )
    return problems


def extras_problems(files: Dict[Path, str]) -> List[str]:
    """``file:line: ...`` for each extra that imports what it may not."""
    problems: List[str] = []
    for path, source in sorted(files.items()):
        if EXTRAS not in path.parents or path.parent == EXTRAS:
            continue
        own = path.relative_to(EXTRAS).parts[0]
        may = {own} | BUILDS_ON.get(own, set())
        where = f"{path.relative_to(ROOT)}"
        for line, module, names in imports_of(path, source):
            if not (module == "snr" or module.startswith("snr.")):
                continue  # the standard library and third-party packages
            if _is_extras(module):
                parts = module.split(".")
                other = parts[2] if len(parts) > 2 else ""
                if other not in may:
                    problems.append(
                        f"{where}:{line}: the extra {own!r} imports {module!r}; it may import "
                        f"the kernel, its own package and {sorted(may - {own}) or 'no other extra'}"
                        " (tests/test_import_contract.py, BUILDS_ON)"
                    )
                continue
            private = [p for p in module.split(".") if p.startswith("_") and p != "__main__"]
            private += [name for name in names if name.startswith("_")]
            if private:
                problems.append(
                    f"{where}:{line}: the extra {own!r} imports {private[0]!r} from "
                    f"{module!r}, a private name of the kernel; use a public one (or make "
                    "it public, with a docstring, in the kernel)"
                )
    return problems


def snr_sources() -> Dict[Path, str]:
    """Every ``.py`` file under ``snr/`` and its text."""
    return {
        path: path.read_text(encoding="utf-8")
        for path in SNR.rglob("*.py")
        if "__pycache__" not in path.parts
    }


PRELUDE = SNR / "prelude"
PRELUDE_MAY_IMPORT = "snr.prelude"
"""The only SNR modules layer 0 imports (besides the standard library, dataclasses-json and
typing-extensions): its own. The node, the checks and the rest build on it, never under it."""


def prelude_problems(files: Dict[Path, str]) -> List[str]:
    """``file:line imports module`` for each prelude import of SNR above the prelude.

    Example::

        prelude_problems({SNR / "prelude" / "page.py": "from snr.core import Node\n"})
        # ['snr/prelude/page.py:1 imports snr.core']
    """
    problems = []
    for path, source in sorted(files.items()):
        if PRELUDE not in path.parents:
            continue
        for line, module, _names in imports_of(path, source):
            if module.split(".")[0] == "snr" and not module.startswith(PRELUDE_MAY_IMPORT):
                where = path.relative_to(ROOT).as_posix()
                problems.append(f"{where}:{line} imports {module}")
    return problems


class ImportContractTest(unittest.TestCase):
    """The kernel never imports an extra; extras use the kernel's public names."""

    def test_the_prelude_imports_nothing_of_snr_above_it(self) -> None:
        self.assertEqual(prelude_problems(snr_sources()), [])

    def test_a_prelude_import_from_above_is_found(self) -> None:
        bad = {
            PRELUDE / "page.py": "import json\nfrom snr.core import Node\n",
            PRELUDE / "abstract.py": "def f():\n    from snr.core.checks import explain\n",
            PRELUDE / "task.py": "from snr.prelude.names import TaskType\n",
        }
        self.assertEqual(
            prelude_problems(bad),
            [
                "snr/prelude/abstract.py:2 imports snr.core.checks",
                "snr/prelude/page.py:2 imports snr.core",
            ],
        )

    def test_the_kernel_imports_no_extra(self) -> None:
        self.assertEqual(kernel_problems(snr_sources()), [])

    def test_extras_import_public_kernel_names_and_their_own_package(self) -> None:
        sources = snr_sources()
        self.assertGreaterEqual(len([p for p in sources if EXTRAS in p.parents]), 30)
        self.assertEqual(extras_problems(sources), [])

    def test_a_kernel_module_importing_an_extra_is_found(self) -> None:
        files = {
            SNR / "std_mods" / "io" / "recorder.py": (
                "import os\nfrom snr.extras.viz.mcap_files import McapPageWriter\n"
            ),
            SNR / "core" / "node.py": "from snr import extras\n",
            SNR / "std_mods" / "comms" / "pipe.py": "from ...extras import zenoh\n",
        }
        problems = kernel_problems(files)
        self.assertEqual(len(problems), 3, problems)
        self.assertTrue(problems[0].startswith("snr/core/node.py:1: "), problems)
        self.assertIn("snr/std_mods/io/recorder.py:2: ", problems[2])

    def test_the_face_may_name_extras_only_for_type_checkers(self) -> None:
        face = SNR / "__init__.py"
        lazy = (
            "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n"
            "    from snr.extras.sim import World\n"
        )
        self.assertEqual(kernel_problems({face: lazy}), [])
        eager = "from snr.extras.sim import World\n"
        self.assertEqual(len(kernel_problems({face: eager})), 1)

    def test_an_extra_importing_a_private_name_or_another_extra_is_found(self) -> None:
        files = {
            EXTRAS / "zenoh" / "comms.py": (
                "from snr.core.logs import LossReport, _secret\n"
                "from snr.extras.zenoh.inbox import SampleChannel\n"
                "from snr.extras.sim import World\n"
                "from snr.core import _internal\n"
            ),
        }
        problems = extras_problems(files)
        self.assertEqual(len(problems), 3, problems)
        self.assertIn("comms.py:1: ", problems[0])
        self.assertIn("'_secret'", problems[0])
        self.assertIn("comms.py:3: ", problems[1])
        self.assertIn("comms.py:4: ", problems[2])


if __name__ == "__main__":
    unittest.main()
