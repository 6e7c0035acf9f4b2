"""Helpers for the tests that run the examples and the tutorial (not part of SNR).

Examples are scripts in folders without ``__init__.py``: the tests load them
from their paths, or run them as a student would, in a subprocess.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from types import ModuleType
from typing import Dict, List, Optional, Sequence

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
    command: List[str] = [sys.executable, *args]
    done = subprocess.run(
        command,
        cwd=cwd or ROOT,
        capture_output=True,
        text=True,
        timeout=timeout_s,
        env=env or script_env(),
    )
    if not allow_hints:
        hints = [
            line
            for line in (done.stdout + done.stderr).splitlines()
            if "Did you mean" in line
        ]
        if hints:
            raise AssertionError(f"{' '.join(args)} logged a false hint:\n" + "\n".join(hints))
    return done
