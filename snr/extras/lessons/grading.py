"""Grading a student's file: load it by path, find its endpoint, drive it in the simulator.

A lesson's grader (``l01_wall_follower/grader.py``...) says what to run and
what to check; this module does the rest, the same way for every lesson:

1. `load_submission` imports the file by its path, under a module name of
   its own, so that two students' files (or a file and the solution) never
   meet; a syntax error or an exception is reported with the file's line;
2. `find_endpoint` picks the file's `Endpoint` subclass by what it does (it
   handles the lesson's sensor pages), not by its name;
3. `drive` runs that endpoint and the simulated robot as one node (`replay`
   stores recorded values into it instead), on a
   `SimClock` as fast as it goes with a fixed seed, and keeps the robot's
   true path: the same file gets the same grade on any machine
   (`kept_drives` hands each run to whoever asks, e.g. to draw its path);
4. the grader turns the `Drive` into `Check` rows, each with what was
   expected, what happened and a hint.

Example::

    module = load_submission(Path("wall_follower.py"))
    endpoint = find_endpoint(module, ["range", "bump"])
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import itertools
import math
import sys
import traceback
from dataclasses import dataclass, field
from importlib.util import module_from_spec, spec_from_file_location
from pathlib import Path
from types import ModuleType
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Type, Union

import snr
from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    Mode,
    SimClock,
    SomeTasks,
    Task,
    TaskId,
    TimeoutLoopFactory,
    World,
    tasks,
)
from snr.core import TestRunner

__all__ = [
    "Check",
    "Drive",
    "Replay",
    "SubmissionError",
    "drive",
    "endpoint_check",
    "find_endpoint",
    "first_checks",
    "handler_line",
    "kept_drives",
    "load_submission",
    "replay",
    "touch_check",
]

SEED = 1
"""The simulator's seed for every grade: the same file, the same run."""
STEP_HZ = 50
"""The simulated robot's steps a second: `Drive.path` has one point a step."""

_numbers = itertools.count(1)
_keepers: List[List[Tuple[World, Drive]]] = []
"""The lists `kept_drives` yielded, still open: `drive` adds each run to them."""


class SubmissionError(Exception):
    """A student's file could not be graded at all; the message says why, in words.

    Example::

        SubmissionError("wall_follower.py, line 12: invalid syntax")
    """


@dataclass
class Check:
    """One row of a grade: what is checked, whether it passed, and why.

    Example::

        Check("never touches a wall", False, "the bumper never pressed",
              "pressed at 8.4 s", "turn left before the wall (step 4)", line=71)
    """

    name: str
    passed: bool
    expected: str = ""
    happened: str = ""
    hint: str = ""
    line: Optional[int] = None
    """The line of the student's file to look at, when one is to blame."""


@dataclass
class Drive:
    """What happened in one graded run: the true path, the bumps, the commands, any error.

    Example::

        run, endpoint = drive(WallFollowerEndpoint, world, 60.0, path)
        run.path[-1]    # where the robot got to, (x, y) in metres
    """

    seconds: float
    path: List[Tuple[float, float]] = field(default_factory=list)
    bumps: List[int] = field(default_factory=list)
    """The steps (`STEP_HZ` a second) at which the bumper was pressed."""
    commands: int = 0
    last_command: Optional[Dict[str, float]] = None
    error: Optional[Check] = None
    """Set when the endpoint raised an exception: the run stopped there."""

    def length_m(self) -> float:
        """How far the robot drove, in metres."""
        return sum(math.dist(a, b) for a, b in zip(self.path, self.path[1:]))


@dataclass
class Replay:
    """What happened when recorded values were replayed into the student's endpoint.

    Example::

        run, endpoint = replay(DepthFilterEndpoint, Path("mine.py"), raw, "depth_raw", "depth")
        run.outputs[0]    # (1, 1.93): the first 'depth' page, stored after 1 input
    """

    inputs: int = 0
    """How many input pages were stored."""
    outputs: List[Tuple[int, Any]] = field(default_factory=list)
    """Each output page's data, with how many input pages had been stored before it."""
    error: Optional[Check] = None
    """Set when the endpoint raised an exception: the run stopped there."""


def load_submission(path: Path) -> ModuleType:
    """Import the Python file at ``path`` as a module of its own, however it is named.

    Raises:
        SubmissionError: the file is missing, has a syntax error or raised an
            exception as it was imported (the message names the line).

    Example::

        module = load_submission(Path("my_wall_follower.py"))
    """
    if not path.is_file():
        raise SubmissionError(f"{path}: no such file. Give the path of your lesson's .py file.")
    name = f"snr_submission_{next(_numbers)}_{path.stem.replace('-', '_')}"
    spec = spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise SubmissionError(f"{path}: not a Python file (its name should end in .py).")
    module = module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and typing look their module up by name
    try:
        spec.loader.exec_module(module)
    except SyntaxError as error:
        del sys.modules[name]
        raise SubmissionError(
            f"{path}, line {error.lineno}: {error.msg}. Python cannot read the file; "
            "fix that line (or the one before it) and grade again."
        ) from None
    except Exception as error:
        del sys.modules[name]
        line = _line_in(error, path)
        where = f", line {line}" if line else ""
        raise SubmissionError(
            f"{path}{where}: {type(error).__name__}: {error}, as the file was imported "
            "(before any robot ran). Run `python FILE` to see the whole traceback."
        ) from None
    return module


def find_endpoint(module: ModuleType, keys: Sequence[str]) -> Type[Endpoint]:
    """The `Endpoint` subclass of ``module`` that handles the sensor pages ``keys``.

    It is found by what it is, not by its name: the endpoint classes the
    file defines (or, if none, imports from outside SNR), and among several
    the one whose ``__init__`` names the most of ``keys``.

    Raises:
        SubmissionError: the file has no endpoint class; the message says what to write.

    Example::

        find_endpoint(module, ["range", "bump"])    # e.g. the file's WallFollowerEndpoint
    """
    library = {id(value) for value in vars(snr).values()}
    found = [
        value
        for value in vars(module).values()
        if inspect.isclass(value) and issubclass(value, Endpoint) and id(value) not in library
    ]
    own = [cls for cls in found if cls.__module__ == module.__name__]
    candidates = own or [cls for cls in found if not cls.__module__.startswith("snr.")]
    if not candidates:
        named = ", ".join(f"'{key}'" for key in keys)
        raise SubmissionError(
            f"{module.__file__}: no endpoint found. The file should define a class that "
            f"extends snr.Endpoint and handles the {named} pages in its task_handlers, as "
            "the starter file does (`python -m snr lesson start N` writes one)."
        )

    def names_keys(cls: Type[Endpoint]) -> int:
        try:
            source = inspect.getsource(cls.__init__)
        except (OSError, TypeError):
            return 0
        return sum(f'"{key}"' in source or f"'{key}'" in source for key in keys)

    return max(candidates, key=names_keys)  # the first of the best: the file's order


def handler_line(endpoint: Optional[Endpoint], key: str) -> Optional[int]:
    """The line where the handler of ``key``'s pages starts in its file, if known.

    Example::

        handler_line(endpoint, "range")    # 71: `def steer(...)`
    """
    if endpoint is None:
        return None
    for task_id, handler in endpoint.task_handlers.items():
        if isinstance(task_id, tuple) and task_id[1] == key:
            try:
                return inspect.getsourcelines(handler)[1]
            except (OSError, TypeError):
                return None
    return None


def endpoint_check(cls: Type[Endpoint], endpoint: Optional[Endpoint], key: str) -> Check:
    """The first check of every lesson: the endpoint found handles ``key``'s pages.

    Example::

        endpoint_check(WallFollowerEndpoint, endpoint, "range").passed    # True
    """
    handlers = endpoint.task_handlers if endpoint is not None else {}
    keys = sorted(repr(task_id[1]) for task_id in handlers if isinstance(task_id, tuple))
    try:
        line: Optional[int] = inspect.getsourcelines(cls)[1]
    except (OSError, TypeError):
        line = None
    return Check(
        "the endpoint",
        endpoint is not None and handler_line(endpoint, key) is not None,
        expected=f"an Endpoint that handles '{key}' pages",
        happened=f"{cls.__name__} handles {', '.join(keys) or 'no pages'}",
        hint=f'put (TaskType.store_page, "{key}"): self.HANDLER in its task_handlers',
        line=line,
    )


def first_checks(
    cls: Type[Endpoint], endpoint: Optional[Endpoint], key: str, error: Optional[Check]
) -> List[Check]:
    """Every lesson's first two checks: the endpoint handles ``key``; its run raised nothing.

    ``error`` is the run's ``error``: the check that names what the endpoint
    raised and where, or None. A grader stops after these when it is set.

    Example::

        checks = first_checks(cls, endpoint, "range", run.error)
        if run.error is not None:
            return checks
    """
    return [endpoint_check(cls, endpoint, key), error or Check("runs without an exception", True)]


def touch_check(run: Drive, name: str, hint: str, line: Optional[int]) -> Check:
    """The check ``name`` ("never touches a wall"): the bumper was never pressed in ``run``.

    When it was, it says when and where first, and for how many steps in all.

    Example::

        touch_check(run, "never touches a wall", "turn before the wall (step 4)", line=64)
    """
    if run.bumps:
        first = run.bumps[0]
        x, y = run.path[max(0, first - 1)]
        happened = (
            f"the bumper was pressed at {first / STEP_HZ:.1f} s, at ({x:.2f}, {y:.2f}); "
            f"{len(run.bumps)} steps touching in all"
        )
    else:
        happened = "never touched"
    return Check(
        name,
        not run.bumps,
        expected=f"the bumper never pressed in {run.seconds:g} s",
        happened=happened,
        hint=hint,
        line=line,
    )


class _Adopter(EndpointFactory):
    """Builds the student's endpoint class; counts on its handlers, and catches their errors.

    The student's own factory may take other arguments or be named anything:
    the grader needs only the endpoint. ``attributes`` (e.g. ``goal``) are
    set on this factory, where the endpoint's ``__init__`` reads them.
    """

    def __init__(
        self,
        cls: Type[Endpoint],
        path: Path,
        run: Union[Drive, Replay],
        attributes: Dict[str, Any],
    ):
        super().__init__()
        self.cls = cls
        self.path = path
        self.run = run
        self.endpoint: Optional[Endpoint] = None
        for name, value in attributes.items():
            setattr(self, name, value)

    def get(self, parent: AbstractNode) -> Endpoint:
        parent.slow_handler_s = 5.0  # type: ignore[attr-defined]  # a busy machine is no error
        try:
            endpoint = self.cls(self, parent)  # type: ignore[call-arg]
        except Exception as error:
            self.run.error = self.blame(error, "as the node built your endpoint")
            endpoint = Endpoint(self, parent, "broken")
            parent.schedule(tasks.terminate("the endpoint could not be built"))
        self.endpoint = endpoint
        endpoint.task_handlers = {
            task_id: self.guarded(handler) for task_id, handler in endpoint.task_handlers.items()
        }
        return endpoint

    def guarded(self, handler: Any) -> Any:
        @functools.wraps(handler)  # its __wrapped__: `handler_line` finds the student's line
        def run_handler(task: Task, key: TaskId) -> SomeTasks:
            if self.run.error is not None:
                return None
            try:
                result: SomeTasks = handler(task, key)
            except Exception as error:
                page = key[1] if isinstance(key, tuple) else key
                self.run.error = self.blame(error, f"handling a '{page}' page")
                return tasks.terminate("the endpoint raised an exception")
            return result

        return run_handler

    def blame(self, error: Exception, when: str) -> Check:
        line = _line_in(error, self.path)
        return Check(
            "runs without an exception",
            False,
            expected="every handler returns, for the whole run",
            happened=f"{type(error).__name__}: {error}, {when}; the run stopped there",
            hint="read the line named here; run your file with `python FILE` for the traceback",
            line=line,
        )


class _Recorder(Endpoint):
    """Keeps the robot's true pose, bumper and wheel commands, step by step."""

    def __init__(self, factory: _RecorderFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "grader")
        self.run = factory.run
        self.task_handlers = {
            (snr.TaskType.store_page, "true_pose"): self.pose,
            (snr.TaskType.store_page, "bump"): self.bump,
            (snr.TaskType.store_page, "wheel_cmd"): self.command,
        }

    def pose(self, task: Task, key: TaskId) -> SomeTasks:
        data = task.val_list[0].data
        self.run.path.append((float(data["x"]), float(data["y"])))
        return None

    def bump(self, task: Task, key: TaskId) -> SomeTasks:
        if task.val_list[0].data:
            self.run.bumps.append(len(self.run.path))
        return None

    def command(self, task: Task, key: TaskId) -> SomeTasks:
        self.run.commands += 1
        self.run.last_command = dict(task.val_list[0].data)
        return None


class _RecorderFactory(EndpointFactory):
    def __init__(self, run: Drive) -> None:
        super().__init__()
        self.run = run

    def get(self, parent: AbstractNode) -> _Recorder:
        return _Recorder(self, parent)


def drive(
    cls: Type[Endpoint],
    world: World,
    seconds: float,
    path: Path,
    attributes: Optional[Dict[str, Any]] = None,
    robot: Optional[Dict[str, Any]] = None,
) -> Tuple[Drive, Optional[Endpoint]]:
    """Run ``cls`` and the simulated robot in ``world`` for ``seconds`` of simulated time.

    One node, as the lesson's ``main`` builds it without the view, on a
    `SimClock` as fast as it goes, seed `SEED`. ``robot``: more arguments for
    its `SimRobotFactory` (lesson 3's sensors). Returns what happened and the
    endpoint (None if it could not be built).

    Example::

        run, endpoint = drive(WallFollowerEndpoint, make_world(), 60.0, Path("mine.py"))
        drive(ScanFollowerEndpoint, world, 60.0, path, robot={"scan_sensor": ScanSensor()})
    """
    run = Drive(seconds)
    brain = _Adopter(cls, path, run, attributes or {})
    components = [
        snr.SimRobotFactory(world, seed=SEED, **(robot or {})),
        brain,
        TimeoutLoopFactory(seconds=seconds),
        _RecorderFactory(run),
    ]
    config = Config({"grade": components}, mode=Mode.TEST, clock=SimClock())
    TestRunner("grade", config, timeout_s=60.0).run()
    for kept in _keepers:
        kept.append((world, run))
    return run, brain.endpoint


@contextlib.contextmanager
def kept_drives() -> Iterator[List[Tuple[World, Drive]]]:
    """Within the block, each `drive` adds its world and what happened to the list yielded.

    A grader returns only its checks; this is how ``lesson grade --png`` gets
    the room and the path of the run it graded, without running it again.

    Example::

        with kept_drives() as drives:
            checks = grade(Path("wall_follower.py"))
        world, run = drives[-1]    # the room, and run.path: where the robot went
    """
    kept: List[Tuple[World, Drive]] = []
    _keepers.append(kept)
    try:
        yield kept
    finally:
        _keepers.remove(kept)


class _PageKeeper(Endpoint):
    """Counts the input pages and keeps each output page's data, in order."""

    def __init__(self, factory: _PageKeeperFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "grader")
        self.run = factory.run
        self.task_handlers = {
            (snr.TaskType.store_page, factory.input): self.count,
            (snr.TaskType.store_page, factory.output): self.keep,
        }

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        self.run.inputs += 1
        return None

    def keep(self, task: Task, key: TaskId) -> SomeTasks:
        self.run.outputs.append((self.run.inputs, task.val_list[0].data))
        return None


class _PageKeeperFactory(EndpointFactory):
    def __init__(self, run: Replay, input: str, output: str) -> None:
        super().__init__()
        self.run = run
        self.input = input
        self.output = output

    def get(self, parent: AbstractNode) -> _PageKeeper:
        return _PageKeeper(self, parent)


def replay(
    cls: Type[Endpoint],
    path: Path,
    values: Sequence[Any],
    input: str,
    output: str,
    period_s: float = 0.02,
) -> Tuple[Replay, Optional[Endpoint]]:
    """Store ``values`` one by one under ``input`` in a node with ``cls``; keep its ``output``.

    One node: a `ListReplayerFactory`, the student's endpoint and a keeper of
    the pages, on a `SimClock` as fast as it goes. In simulated time each
    value is handled, and what the endpoint stores in answer kept, before the
    next value is stored: ``outputs`` pairs each answer with its input. Returns
    what happened and the endpoint (None if it could not be built).

    Example::

        run, endpoint = replay(DepthFilterEndpoint, Path("mine.py"), raw, "depth_raw", "depth")
    """
    run = Replay()
    brain = _Adopter(cls, path, run, {})
    components = [
        ListReplayerFactory(values, input, period_s=period_s, exit_when_done=True),
        brain,
        TimeoutLoopFactory(seconds=(len(values) + 50) * period_s),  # a bound, in any case
        _PageKeeperFactory(run, input, output),
    ]
    config = Config({"grade": components}, mode=Mode.TEST, clock=SimClock())
    TestRunner("grade", config, timeout_s=60.0).run()
    return run, brain.endpoint


def _line_in(error: BaseException, path: Path) -> Optional[int]:
    """The last line of ``path`` in ``error``'s traceback, if the file is in it."""
    target = path.resolve()
    line: Optional[int] = None
    for frame in traceback.extract_tb(error.__traceback__):
        if Path(frame.filename).resolve() == target:
            line = frame.lineno
    return line
