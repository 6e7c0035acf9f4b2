"""`runner_built` and `runner_ran`: a runner built and never run is said at exit.

And `no_role_given`: ``python robot.py`` without a role, answered with the roles.
Only a runner built by ``__main__``'s own code is named: not in a
``unittest.TestCase`` method, with pytest loaded, in DEPLOYED mode, or after an
uncaught error (docs/errors.md, 15q).

Example::

    runner = CliRunner({"robot": [...]})   # runner_built(runner, config) in __init__
    runner.run()                            # runner_ran(runner) as run() starts
"""

from __future__ import annotations

import atexit
import sys
from typing import Any, Dict, List, NoReturn, Sequence, Tuple

from snr.core.checks.student_code import frame_location, outside_runtime, source_block
from snr.prelude import AbstractConfig, Mode

__all__ = ["no_role_given", "runner_built", "runner_ran"]

# id(runner) -> (runner, kept so its id is not reused; "robot.py:4 in <module>"; its line).
_not_run: Dict[int, Tuple[object, str, str]] = {}
_registered: List[bool] = []


def runner_built(runner: object, config: AbstractConfig) -> None:
    """Remember ``runner`` until it runs, if the program's own code built it.

    Example::

        runner_built(self, self.config)   # last line of a runner's __init__
    """
    frame = outside_runtime(sys._getframe(1))
    if frame is None or frame.f_globals.get("__name__") != "__main__":
        return
    if config.mode is Mode.DEPLOYED or "pytest" in sys.modules:
        return
    unittest = sys.modules.get("unittest")
    if unittest is not None and isinstance(frame.f_locals.get("self"), unittest.TestCase):
        return
    block = source_block(frame.f_code.co_filename, frame.f_lineno, frame.f_code.co_name)
    _not_run[id(runner)] = (runner, frame_location(frame), block)
    if not _registered:
        _registered.append(True)
        atexit.register(_say_not_run)


def runner_ran(runner: object) -> None:
    """``runner.run()`` was called: nothing to say about it at exit.

    Example::

        runner_ran(self)   # first line of a runner's run()
    """
    _not_run.pop(id(runner), None)


def _say_not_run() -> None:
    if getattr(sys, "last_value", None) is not None:
        return
    for runner, place, block in _not_run.values():
        name = type(runner).__name__
        print(
            f"{name} built at {place} never ran: the program ended without starting a "
            f"node. Call its run(): `{name}(...).run()`, or `runner.run()` on the name "
            f"you gave it.\n{block}",
            file=sys.stderr,
            flush=True,
        )
    _not_run.clear()


def no_role_given(parser: Any, prog: str, roles: Sequence[str]) -> NoReturn:
    """Exit (status 2) with ``parser``'s usage, the roles to choose from and an example.

    Example::

        no_role_given(parser, "robot.py", ["urov", "topside"])
        # robot.py: error: no role given. Choose one of: urov, topside. For example: ...
    """
    parser.print_usage(sys.stderr)
    print(
        f"{prog}: error: no role given. Choose one of: {', '.join(roles)}. "
        f"For example: python {prog} {roles[0] if roles else 'ROLE'}",
        file=sys.stderr,
    )
    raise SystemExit(2)
