"""Get the `Config` out of a student's program without running its nodes.

``python -m snr graph main.py`` needs the system that ``main.py`` would run.
The rule: the file is run as ``python main.py`` would run it (as
``__main__``, its folder first on ``sys.path``, ``sys.argv`` = the file and
any extra arguments), except that every SNR runner stops at the moment it
would start a node, and hands over its config instead:
``CliRunner(...).run()``, ``SynchronousRunner``, ``MultiProcRunner``,
``TestRunner`` and ``Node.loop()``. A file that calls no runner may instead
leave a `Config` (or a dict of factories, a ``ComponentsByRole``) in a
module-level variable: ``config`` or ``components`` first, else the only one.

Everything before the runner does run (the file's own argument parsing, its
prints), so keep hardware out of module level and of component constructors.

Example::

    config = config_from_script("examples/urov/main.py")
"""

from __future__ import annotations

import os
import runpy
import sys
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from snr.core import Config, Node
from snr.core.checks.runner_checks import runner_ran
from snr.core.runners import SynchronousRunner, TestRunner
from snr.prelude import AbstractConfig, AbstractFactory, ConfigError
from snr.std_mods.runners import CliRunner, MultiProcRunner

__all__ = ["config_from_script"]

_RUNNERS: Tuple[type, ...] = (CliRunner, SynchronousRunner, MultiProcRunner, TestRunner)
_NAMES = ("config", "components")


class _Captured(BaseException):
    """Raised by a patched runner: carries the config out of the script.

    A BaseException, so a script's ``except Exception`` cannot swallow it.
    """

    def __init__(self, config: AbstractConfig) -> None:
        super().__init__("config captured")
        self.config = config


def _capture(self: Any) -> None:
    runner_ran(self)  # it was asked to run: nothing to say about it at exit
    config = getattr(self, "config", None)
    if not isinstance(config, AbstractConfig):  # a Node keeps it too; runners always
        raise ConfigError("An SNR runner started without a config.")
    raise _Captured(config)


def config_from_script(path: str, argv: Sequence[str] = ()) -> AbstractConfig:
    """The config the program at ``path`` would run (see the module docstring).

    Raises:
        ConfigError: the file does not exist, exits before starting a node,
            or starts no runner and leaves no config behind (the message
            says how to fix it). Errors raised by the file itself propagate.
    """
    if not os.path.isfile(path):
        raise ConfigError(f"No such file: {path!r}. Give the program that runs your nodes.")
    saved_argv, saved_path = sys.argv, list(sys.path)
    originals: List[Tuple[type, Callable[..., Any]]] = [(c, c.run) for c in _RUNNERS]  # type: ignore[attr-defined]
    original_loop = Node.loop
    try:
        sys.argv = [path, *argv]
        sys.path.insert(0, os.path.dirname(os.path.abspath(path)))
        for runner, _ in originals:
            runner.run = _capture  # type: ignore[attr-defined]
        Node.loop = _capture  # type: ignore[method-assign]
        try:
            names = runpy.run_path(path, run_name="__main__")
            for value in names.values():  # a runner built and left for us to read
                if isinstance(value, _RUNNERS):
                    runner_ran(value)
        except _Captured as captured:
            return captured.config
        except SystemExit as stop:
            raise ConfigError(
                f"{path} exited (status {stop.code}) before it started any SNR node, so "
                "there is no system to draw. If it needs arguments, give them after the "
                "file name, e.g. `python -m snr graph main.py -- --port 9100`."
            ) from None
    finally:
        for runner, run in originals:
            runner.run = run  # type: ignore[attr-defined]
        Node.loop = original_loop  # type: ignore[method-assign]
        sys.argv = saved_argv
        sys.path[:] = saved_path
    found = _config_in(names)
    if found is None:
        raise ConfigError(
            f"{path} ran to the end without starting an SNR runner, and has no module-level "
            "`config` (a snr.Config) or `components` (a dict of role to factories). Call "
            "snr.CliRunner(components).run() under `if __name__ == '__main__':`, or keep "
            "the system in a variable named `config`."
        )
    return found


def _config_in(names: Dict[str, Any]) -> Optional[AbstractConfig]:
    candidates = {name: value for name, value in names.items() if _as_config(value) is not None}
    for name in _NAMES:
        if name in candidates:
            return _as_config(candidates[name])
    if len(candidates) == 1:
        return _as_config(next(iter(candidates.values())))
    return None


def _as_config(value: Any) -> Optional[AbstractConfig]:
    if isinstance(value, AbstractConfig):
        return value
    if isinstance(value, dict) and value and all(_factories(v) for v in value.values()):
        return Config(value)
    return None


def _factories(value: Any) -> bool:
    return isinstance(value, (list, tuple)) and all(isinstance(f, AbstractFactory) for f in value)
