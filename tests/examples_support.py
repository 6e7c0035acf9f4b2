"""Helpers for the tests that run the examples and the tutorial (not part of SNR).

Examples are scripts in folders without ``__init__.py``: the tests load them
from their paths, or run them as a student would, in a subprocess.
"""

from __future__ import annotations

import functools
import importlib.util
import os
import subprocess
import sys
from types import ModuleType
from typing import Callable, Dict, Optional, Sequence, TypeVar

T = TypeVar("T")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(ROOT, "examples")
TUTORIAL = os.path.join(EXAMPLES, "tutorial")


def example_path(*parts: str) -> str:
    """The path of a file under examples/."""
    return os.path.join(EXAMPLES, *parts)


def load_module(path: str, module_name: str) -> ModuleType:
    """Import the file at ``path`` as ``module_name``, with its folder on sys.path.

    The folder stays on sys.path only while the module runs its top level, so
    ``from sibling import x`` works as it does for ``python file.py``. The
    sibling modules it imported are left in sys.modules (unique names).
    """
    folder = os.path.dirname(path)
    spec = importlib.util.spec_from_file_location(module_name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, folder)
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(folder)
    return module


def script_env(extra: Optional[Dict[str, str]] = None) -> Dict[str, str]:
    """The environment for running an example: this checkout's snr first."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in [ROOT, env.get("PYTHONPATH", "")] if p)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env.update(extra or {})
    return env


IN_XDIST_WORKER = "PYTEST_XDIST_WORKER" in os.environ
"""True in a pytest-xdist worker, which imports every test module but runs only some."""


def early(make: Callable[[], T]) -> Callable[[], T]:
    """Runs ``make()`` once: now, or in a pytest-xdist worker at the first call; gives its value.

    Tests that only read a script's output can start it when their module is
    imported, so the script runs while other tests do (the suite waits on it
    once, not one after another). unittest and ``pytest -n 0`` import every
    module before any test runs, so ``make`` runs at import there. A
    pytest-xdist worker imports every module too, but runs only the files it
    is given (``--dist loadfile``): there ``make`` runs at the first call,
    which the module's ``setUpModule`` makes, so every script of the file
    starts together, once, on the worker that runs the file.

    Example::

        DEMO = early(lambda: start_script(["-m", "snr", "demo", "--seconds", "1"]))

        def setUpModule() -> None:
            DEMO()          # (started already, unless in a pytest-xdist worker)
        ...
        done = DEMO().result()   # in the test: a CompletedProcess
    """
    value = functools.cache(make)  # made once, at the first call
    if not IN_XDIST_WORKER:
        value()
    return value


class StartedScript:
    """A script started now, in the background; `result` waits for it.

    See `early` for starting one when a test module is imported.
    """

    def __init__(
        self,
        args: Sequence[str],
        cwd: Optional[str] = None,
        timeout_s: float = 30.0,
        env: Optional[Dict[str, str]] = None,
        allow_hints: bool = False,
    ) -> None:
        self.args = list(args)
        self.timeout_s = timeout_s
        self.allow_hints = allow_hints
        self._done: Optional[subprocess.CompletedProcess[str]] = None
        self._process = subprocess.Popen(
            [sys.executable, *args],
            cwd=cwd or ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env or script_env(),
        )

    def result(self) -> subprocess.CompletedProcess[str]:
        """Wait (at most ``timeout_s``) for the script; its output, checked for hints."""
        if self._done is None:
            try:
                out, err = self._process.communicate(timeout=self.timeout_s)
            except subprocess.TimeoutExpired:
                self._process.kill()
                out, err = self._process.communicate()
                raise AssertionError(
                    f"{' '.join(self.args)} ran over {self.timeout_s} s:\n{out}\n{err}"
                ) from None
            self._done = subprocess.CompletedProcess(
                self._process.args, self._process.returncode, out, err
            )
        if not self.allow_hints:
            hints = [
                line
                for line in (self._done.stdout + self._done.stderr).splitlines()
                if "Did you mean" in line
            ]
            if hints:
                raise AssertionError(
                    f"{' '.join(self.args)} logged a false hint:\n" + "\n".join(hints)
                )
        return self._done


def start_script(
    args: Sequence[str],
    cwd: Optional[str] = None,
    timeout_s: float = 30.0,
    env: Optional[Dict[str, str]] = None,
    allow_hints: bool = False,
) -> StartedScript:
    """Start ``python *args`` now; ``.result()`` waits for it (see `StartedScript`)."""
    return StartedScript(args, cwd, timeout_s, env, allow_hints)


def run_script(
    args: Sequence[str],
    cwd: Optional[str] = None,
    timeout_s: float = 30.0,
    env: Optional[Dict[str, str]] = None,
    allow_hints: bool = False,
) -> subprocess.CompletedProcess[str]:
    """Run ``python *args`` as a student would and capture its output.

    The shipped examples must not log a "Did you mean" hint: one there is a
    false alarm that teaches students to ignore hints. Unless ``allow_hints``,
    such a line fails the test that ran the script.
    """
    return start_script(args, cwd, timeout_s, env, allow_hints).result()
