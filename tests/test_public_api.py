"""The student-facing surface: `from snr import *`, its one list, and its documentation.

``snr/__init__.py`` is the one place the public names are listed. These
tests check that the list is sorted, small, in step with its imports, and
complete: every name the thesis listings, the tutorial, the examples and
code written for the 2021 release take from ``snr`` is in it.
"""

import ast
import builtins
import importlib
import inspect
import pkgutil
import re
import unittest
from pathlib import Path
from typing import Dict, Iterator, List, Set, Tuple

import snr
from tests.optional import reason

ROOT = Path(__file__).resolve().parent.parent
MAX_NAMES = 70  # what a student can read in one screen

# Where the names students use come from: file (or Markdown page), Python source.
STUDENT_CODE = [
    *sorted((ROOT / "tests" / "listings").rglob("*.py")),
    *sorted((ROOT / "examples").rglob("*.py")),
    ROOT / "tests" / "test_compat2021_style.py",  # written as 2021 code was
    ROOT / "tests" / "test_compat2021_release.py",  # the 2021 release's 57 names
    ROOT / "docs" / "tutorial.md",
    ROOT / "docs" / "lessons.md",
]
# The packages whose names are SNR's: a name of one of them that student code
# uses without importing it is expected from `from snr import *`.
SNR_PACKAGES = [
    "snr.prelude",
    "snr.core",
    "snr.std_mods.comms",
    "snr.std_mods.filters",
    "snr.std_mods.io",
    "snr.extras.sim",
    "snr.std_mods.utils",
    "snr.utils",
    "snr.extras.compat2021",
]


def python_sources(path: Path) -> Iterator[Tuple[str, str]]:
    """(where, source) of a .py file, or of each ```python block of a Markdown page."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".py":
        yield str(path.relative_to(ROOT)), text
        return
    for block in re.finditer(r"```python\n(.*?)```", text, re.DOTALL):
        line = text.count("\n", 0, block.start()) + 2
        yield f"{path.relative_to(ROOT)}:{line}", block.group(1)


def free_names(tree: ast.AST) -> Set[str]:
    """Names the code reads but never binds (imports, assignments, defs, arguments)."""
    bound = set(dir(builtins))
    read: Set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            (read if isinstance(node.ctx, ast.Load) else bound).add(node.id)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, ast.arg):
            bound.add(node.arg)
        elif isinstance(node, ast.alias) and node.name != "*":
            bound.add((node.asname or node.name).split(".")[0])
        elif isinstance(node, ast.ExceptHandler) and node.name:
            bound.add(node.name)
    return read - bound


def names_taken_from(module: str, tree: ast.AST, star_means_all: bool, ours: Set[str]) -> Set[str]:
    """The names ``tree`` takes from ``module``: imported by name, read as ``module.X``,
    and, after ``from module import *`` (or if ``star_means_all``), read unbound if
    they are among ``ours``."""
    taken: Set[str] = set()
    star = star_means_all
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == module and not node.level:
            star = star or any(alias.name == "*" for alias in node.names)
            taken |= {alias.name for alias in node.names if alias.name != "*"}
        elif (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id == module
        ):
            taken.add(node.attr)
    return taken | (free_names(tree) & ours if star else set())


def snr_names() -> Set[str]:
    """Every name an SNR package exports (the candidates for `from snr import *`)."""
    names: Set[str] = set()
    for package in SNR_PACKAGES:
        names |= set(importlib.import_module(package).__all__)
    return names


def top_level_imports(tree: ast.Module) -> Tuple[Set[str], Dict[str, Set[str]]]:
    """The names snr/__init__.py imports at once, and those under ``if TYPE_CHECKING:``
    by module."""
    eager: Set[str] = set()
    typed: Dict[str, Set[str]] = {}
    for statement in tree.body:
        if isinstance(statement, ast.ImportFrom) and (statement.module or "").startswith("snr"):
            eager |= {alias.name for alias in statement.names}
        if isinstance(statement, ast.If) and ast.unparse(statement.test) == "TYPE_CHECKING":
            for inner in statement.body:
                assert isinstance(inner, ast.ImportFrom) and inner.module, ast.unparse(inner)
                typed[inner.module] = {alias.name for alias in inner.names}
    return eager, typed


class TestTheOneList(unittest.TestCase):
    def test_all_is_sorted_without_repeats_and_short(self) -> None:
        import snr.extras.compat2021

        self.assertEqual(snr.__all__, sorted(set(snr.__all__)))
        # The names kept for 2021 code are counted apart: they are not today's API.
        today = set(snr.__all__) - set(snr.extras.compat2021.__all__)
        self.assertLessEqual(
            len(today),
            MAX_NAMES,
            "snr exports more than a screen of names: export a new component from its "
            "own package (snr.std_mods.comms, ...) unless the tutorial or the examples need it",
        )

    def test_every_name_is_imported_once_and_the_lazy_table_follows_the_imports(self) -> None:
        tree = ast.parse(Path(snr.__file__).read_text(encoding="utf-8"))
        eager, typed = top_level_imports(tree)
        lazy = {module: set(names.split()) for module, names in snr._LAZY.items()}
        self.assertEqual(typed, lazy, "the TYPE_CHECKING imports and _LAZY must name the same")
        every_import = sorted(eager.union(*lazy.values()))
        self.assertEqual(every_import, snr.__all__, "each import, and nothing else, in __all__")
        self.assertEqual(eager & snr._HOME.keys(), set(), "a name is imported at once or lazily")

    def test_lazy_names_come_from_where_the_table_says(self) -> None:
        for name, module in snr._HOME.items():
            with self.subTest(name=name):
                self.assertIs(getattr(snr, name), getattr(importlib.import_module(module), name))

    def test_dir_lists_every_export(self) -> None:
        self.assertLessEqual(set(snr.__all__), set(dir(snr)))

    def test_a_name_left_out_of_snr_stays_importable_from_its_package(self) -> None:
        from snr.core.task_queue import TaskQueue
        from snr.std_mods.comms import SocketsServerFactory

        self.assertNotIn("TaskQueue", snr.__all__)
        self.assertNotIn("SocketsServerFactory", snr.__all__)
        self.assertTrue(callable(TaskQueue) and callable(SocketsServerFactory))
        with self.assertRaises(AttributeError):
            snr.TaskQueue  # noqa: B018


class TestWhatStudentCodeUses(unittest.TestCase):
    def test_every_name_student_code_takes_from_snr_is_exported(self) -> None:
        candidates = snr_names()
        missing: List[str] = []
        for path in STUDENT_CODE:
            for where, source in python_sources(path):
                try:
                    tree = ast.parse(source)
                except SyntaxError:
                    continue  # a fragment of a line in the tutorial's prose
                # A Markdown block without imports runs after the tutorial's `from snr import *`.
                is_fragment = path.suffix == ".md" and "import" not in source
                # An unbound name is expected from snr only if it is one of SNR's.
                taken = names_taken_from("snr", tree, is_fragment, candidates)
                missing += [f"{where}: {n}" for n in sorted(taken - set(snr.__all__))]
        self.assertEqual(missing, [], "names student code takes from snr that snr lacks")

    def test_the_check_above_finds_a_missing_name(self) -> None:
        code = "from snr import *\nfrom snr import Node\nTaskQueue()\nsnr.Profiler\nq = 1\nq\n"
        taken = names_taken_from("snr", ast.parse(code), False, snr_names())
        self.assertEqual(taken, {"Node", "TaskQueue", "Profiler"})
        unimported = ast.parse("TaskQueue()")  # no `from snr import *`: not from snr
        self.assertEqual(names_taken_from("snr", unimported, False, snr_names()), set())

    def test_the_2021_names_are_exported(self) -> None:
        import snr.extras.compat2021

        self.assertLessEqual(set(snr.extras.compat2021.__all__), set(snr.__all__))

    def test_the_listings_star_imports_of_snr_core_and_snr_prelude_give_what_they_use(
        self,
    ) -> None:
        import snr.core
        import snr.prelude

        given = set(snr.core.__all__) | set(snr.prelude.__all__)
        for path in sorted((ROOT / "tests" / "listings" / "moving_avg").glob("*.py")):
            with self.subTest(listing=path.name):
                tree = ast.parse(path.read_text(encoding="utf-8"))
                self.assertEqual(free_names(tree) - given, set())


class TestDocumented(unittest.TestCase):
    def test_every_public_name_is_documented_with_an_example(self) -> None:
        missing = []
        for name in snr.__all__:
            obj = getattr(snr, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj) or inspect.ismodule(obj)):
                continue
            if getattr(obj, "__module__", "") == "builtins":
                continue  # a type alias such as DataKey = str
            doc = inspect.getdoc(obj) or ""
            if "Example" not in doc:
                missing.append(name)
        self.assertEqual(missing, [], "public names without a docstring example")

    def test_every_module_declares_all(self) -> None:
        for info in pkgutil.walk_packages(snr.__path__, "snr."):
            if info.name.endswith("__main__"):
                continue
            with self.subTest(module=info.name):
                try:
                    module = importlib.import_module(info.name)
                except ModuleNotFoundError as error:
                    package = (error.name or "snr").split(".")[0]
                    if package == "snr":
                        raise
                    # A module for an extra, e.g. the live view's server needs websockets.
                    self.skipTest(reason(package))
                self.assertTrue(hasattr(module, "__all__"), info.name)


if __name__ == "__main__":
    unittest.main()
