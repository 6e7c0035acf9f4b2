"""Grading a part of SNR a student wrote: their datastore or node core, in real nodes.

Lessons 5 and 6 (docs/assignments.md) have students write a part of the
kernel again: the datastore, the node core endpoint. Their part is plugged in
where SNR's own goes, ``Config(datastore=..., node_core=...)``, and this
module runs it in real nodes and writes down what happened, for the lesson's
grader to turn into `Check` rows:

1. `find_class` picks the student's class by what it has, not its name;
2. `probe` runs one node, in simulated time, with a probe endpoint that
   stores a seeded script of pages and reads the datastore back at each
   step (when each page's handlers run, when its ``process_data`` runs, a
   key never stored, 300 keys), then adds, removes and reloads a component
   and asks the node to stop (`Probe`);
3. `over_comms` runs two nodes linked in memory (`MemoryLinkPair`): the
   sender's pages reach the student's node as they do from another robot,
   many at once (`Received`).

The same runs grade SNR's own parts: ``Config()``'s defaults pass every check.

Example::

    run = probe(Config({"grade": []}, datastore=MyDatastore).datastore, None, path)
    run.unknown      # what get_page gave for a key never stored (None, if right)
"""

from __future__ import annotations

import contextlib
import inspect
import logging
import random
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

import snr
from snr import (
    AbstractFactory,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    Page,
    SimClock,
    SNRError,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)
from snr.core import TestRunner
from snr.extras.lessons.grading import Check, SubmissionError, _line_in
from snr.std_mods.comms import COMMS_CONNECTED
from snr.utils import MemoryLinkPair

__all__ = [
    "ALONE",
    "BURST",
    "MANY",
    "SCRIPT",
    "Probe",
    "Received",
    "error_check",
    "at_class_line",
    "demo",
    "find_class",
    "method_line",
    "over_comms",
    "page_words",
    "probe",
    "quiet",
    "stop",
]

SEED = 5
"""The seed of the script's values: the same file, the same grade."""
SENT = 200
"""Pages the other node sends over comms, under ``count``: 0, 1, 2, ..."""
MANY = 300
"""Keys stored once each, ``k000`` to ``k299``, after the script."""
BURST = 50
"""Pages under ``burst`` (0, 1, 2, ...) from node ``other`` stored as one ``store_pages``
event, as a comms component hands over what it read at once."""
UNKNOWN = "never_stored"
"""A key no page is ever stored under."""
ADDED = "probe_added"
"""The name of the component the probe asks the node core to add, then remove."""
DONE = "the probe is done"
"""The terminate task's reason: the node should stop with it."""
ALONE = ("alone", 42.5)
"""A page (key, value, process true) stored by itself: nothing newer comes before its
``process_data`` task."""
OVERTIME = "still running after its terminate task"
"""Why a node that did not stop on its terminate task was stopped."""


def _script() -> List[Tuple[str, float, bool]]:
    """Twelve pages under three keys: (key, value, process); seeded."""
    rng = random.Random(SEED)
    keys = ["depth", "speed", "depth", "heading", "depth", "speed"] * 2
    return [(key, round(rng.uniform(0, 10), 3), rng.random() < 0.7) for key in keys]


SCRIPT = _script()
"""The pages the probe stores first, in order: (key, value, process)."""


@contextlib.contextmanager
def quiet(*roles: str) -> Iterator[None]:
    """Within the block, the nodes ``roles`` log nothing: a grade says what happened in its checks.

    Example::

        with quiet("grade"):
            TestRunner("grade", config).run()
    """
    loggers = [logging.getLogger(f"snr.{role}") for role in roles]
    levels = [one.level for one in loggers]
    for one in loggers:
        one.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for one, level in zip(loggers, levels):
            one.setLevel(level)


def find_class(module: ModuleType, fits: Callable[[type], bool], what: str) -> type:
    """The class of ``module`` (defined in it) for which ``fits`` is true; the last of several.

    Raises:
        SubmissionError: there is none; ``what`` says what was looked for.

    Example::

        find_class(module, lambda cls: hasattr(cls, "get"), "a datastore class with get")
    """
    found = [
        value
        for value in vars(module).values()
        if inspect.isclass(value) and value.__module__ == module.__name__ and fits(value)
    ]
    if not found:
        raise SubmissionError(
            f"{module.__file__}: no {what} found. Keep the class the starter file "
            "defines (`python -m snr lesson start N` writes one) and fill in its TODOs."
        )
    return found[-1]


def error_check(error: BaseException, path: Path, when: str) -> Check:
    """The failed "runs without an exception" check for ``error``, at ``path``'s line if known.

    When SNR put the mistake into words (a datastore's wrong answer, say),
    those words are the ones shown.

    Example::

        error_check(ZeroDivisionError("division by zero"), Path("mine.py"), "storing a page")
    """
    said = error
    while said.__cause__ is not None:  # a failed handler: what it raised, and why
        said = said.__cause__
    if not isinstance(said, SNRError) or _line_in(said, path) is not None:
        said = error  # the student's own exception: the handler's report names it
    found = None
    for cause in (error, error.__cause__, said):
        if cause is not None and found is None:
            found = _line_in(cause, path)
    return Check(
        "runs without an exception",
        False,
        expected="the node runs the whole probe without an exception",
        happened=f"{type(said).__name__}: {str(said).splitlines()[0]} ({when}); the run "
        "stopped there",
        hint="read the line named here; run your file with `python FILE` for the traceback",
        line=found,
    )


def method_line(cls: Any, method: str) -> Optional[int]:
    """The line where ``cls.method`` starts in its file, or None (a builtin, say).

    Example::

        method_line(HashDatastore, "get")    # 76
    """
    try:
        return inspect.getsourcelines(getattr(cls, method))[1]
    except (OSError, TypeError, AttributeError):
        return None


def at_class_line(error: Check, cls: Any) -> Check:
    """``error``, naming the line of ``cls`` when no line of the file was in the traceback.

    Example::

        at_class_line(run.error, HashDatastore).line    # the `class HashDatastore:` line
    """
    if error.line is None:
        try:
            error.line = inspect.getsourcelines(cls)[1]
        except (OSError, TypeError):
            pass
    return error


def page_words(page: Any) -> str:
    """``page`` in a few words for a check: its key, data and origin; or what it is instead.

    Example::

        page_words(Page("count", 199, "sender", 0.0))   # "the 'count' page 199 from 'sender'"
        page_words(None)                                # 'None'
    """
    if isinstance(page, Page):
        return f"the {page.key!r} page {page.data!r} from {page.origin!r}"
    return repr(page)


@dataclass
class Probe:
    """What one probe run saw of the node's datastore and core.

    Example::

        run = probe(MyDatastore, None, Path("mine.py"))
        run.at_store[0]    # ('depth', 6.229, Page('depth', 6.229, ...)): it was stored
    """

    at_store: List[Tuple[str, Any, Any]] = field(default_factory=list)
    """For each ``store_page`` task's handler: key, value, and what ``get_page(key)`` gave."""
    at_process: List[Tuple[str, Any, Any]] = field(default_factory=list)
    """For each ``process_data`` task: key, value, and what ``get_data(key)`` gave."""
    unknown: Any = "not read"
    """``get_page`` of a key never stored."""
    keys: List[Any] = field(default_factory=list)
    """``list(node.datastore)`` after the script."""
    count: Any = None
    """``len(node.datastore)`` after the script."""
    many: Dict[str, Any] = field(default_factory=dict)
    """``get_data`` of each of the `MANY` keys, once all were stored."""
    all_keys: List[Any] = field(default_factory=list)
    """``list(node.datastore)`` at the end."""
    added: Optional[bool] = None
    """Whether the component the probe asked for was there after an ``ADD_COMPONENT``."""
    removed: Optional[bool] = None
    """Whether it was gone after a ``REMOVE_COMPONENT``."""
    reloaded: List[str] = field(default_factory=list)
    """What the node core asked the node to reload, after a ``reload`` task."""
    stop_reason: Optional[str] = None
    """Why the node stopped (`DONE`, if by the probe's terminate task)."""
    error: Optional[Check] = None
    """Set when the node raised: the run stopped there."""


class _Probe(Endpoint):
    """Stores the script, reads the datastore back at each step, then tries the core's tasks."""

    def __init__(self, factory: _ProbeFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "grader")
        self.run = factory.run
        self.task_handlers = {
            TaskType.store_page: self.stored,
            TaskType.process_data: self.processed,
            (TaskType.event, "probe_script"): self.script,
            (TaskType.event, "probe_many"): self.store_many,
            (TaskType.event, "probe_add"): self.add,
            (TaskType.event, "probe_remove"): self.remove,
            (TaskType.event, "probe_reload"): self.reload,
            (TaskType.event, "probe_stop"): self.stop,
        }

    def begin(self) -> None:
        self.parent.schedule(tasks.event("probe_script"))

    def stored(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        self.run.at_store.append((page.key, page.data, self.parent.get_page(page.key)))
        return None

    def processed(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        self.run.at_process.append((page.key, page.data, self.parent.get_data(page.key)))
        return None

    def script(self, task: Task, key: TaskId) -> SomeTasks:
        out = [self.store_data_task(k, value, process) for k, value, process in SCRIPT]
        return [*out, tasks.event("probe_many")]

    def store_many(self, task: Task, key: TaskId) -> SomeTasks:
        node = self.parent
        self.run.unknown = node.get_page(UNKNOWN)
        self.run.keys, self.run.count = list(node.datastore), len(node.datastore)
        out = [self.store_data_task(f"k{i:03d}", i, process=False) for i in range(MANY)]
        return [*out, tasks.event("probe_add")]

    def add(self, task: Task, key: TaskId) -> SomeTasks:
        node = self.parent
        self.run.many = {f"k{i:03d}": node.get_data(f"k{i:03d}") for i in range(MANY)}
        self.run.all_keys = list(node.datastore)
        adding = Task(TaskType.event, tasks.ADD_COMPONENT, [_AddedFactory()])
        now = node.get_time_s()
        burst = tasks.store_pages([Page("burst", i, "other", now, False) for i in range(BURST)])
        return [self.store_data_task(*ALONE), burst, adding, tasks.event("probe_remove")]

    def remove(self, task: Task, key: TaskId) -> SomeTasks:
        self.run.added = ADDED in self.parent.components
        if not self.run.added:  # added here, so that removing it is tried all the same
            self.parent.add_component(_AddedFactory().get(self.parent))
        removing = Task(TaskType.event, tasks.REMOVE_COMPONENT, [ADDED])
        return [removing, tasks.event("probe_reload")]

    def reload(self, task: Task, key: TaskId) -> SomeTasks:
        self.run.removed = ADDED not in self.parent.components
        reloaded = self.run.reloaded

        def keep(name: str = "all") -> List[str]:
            reloaded.append(name)  # what the core asked for; the node's own reload is not run
            return []

        self.parent.reload_component = keep  # type: ignore[method-assign]
        return [Task(TaskType.reload, "grader"), tasks.event("probe_stop")]

    def stop(self, task: Task, key: TaskId) -> SomeTasks:
        del self.parent.reload_component  # the node's own method again
        return tasks.terminate(DONE)


class _ProbeFactory(EndpointFactory):
    def __init__(self, run: Probe) -> None:
        super().__init__()
        self.run = run

    def get(self, parent: AbstractNode) -> _Probe:
        return _Probe(self, parent)


class _Deadline(ThreadLoop):
    """Stops the node itself, ``seconds`` after it started, if it is still running.

    A node core that ignores terminate tasks would keep its node running for
    ever; this stops it anyway (in simulated time, at once), saying why.
    """

    follows_clock = True  # it only waits on time: in simulated time, it takes turns

    def __init__(self, factory: _DeadlineFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "deadline")
        self.seconds = factory.seconds

    def loop(self) -> None:
        if not self.wait_s(self.seconds):
            self.parent.set_terminate_flag(OVERTIME)


class _DeadlineFactory(LoopFactory):
    def __init__(self, seconds: float) -> None:
        super().__init__()
        self.seconds = seconds

    def get(self, parent: AbstractNode) -> _Deadline:
        return _Deadline(self, parent)


class _AddedFactory(EndpointFactory):
    """Builds the endpoint the probe asks the node core to add."""

    def get(self, parent: AbstractNode) -> Endpoint:
        return Endpoint(self, parent, ADDED)


def probe(
    datastore: Optional[Callable[[], Any]], node_core: Optional[AbstractFactory], path: Path
) -> Probe:
    """Run the probe in one node built with ``Config(datastore=..., node_core=...)``.

    In TEST mode on a `SimClock`: a few hundred tasks, a fraction of a
    second; a node that does not stop on its terminate task is stopped a
    simulated minute later (at once), or after 3 s of wall clock.

    Example::

        run = probe(None, None, Path("x.py"))    # SNR's own parts: every check passes
    """
    run = Probe()
    components = [_ProbeFactory(run), TimeoutLoopFactory(seconds=60), _DeadlineFactory(61)]
    try:
        config = Config(
            {"grade": components},
            mode=Mode.TEST,
            clock=SimClock(),
            datastore=datastore,
            node_core=node_core,
        )
        runner = TestRunner("grade", config, timeout_s=3.0)
        with quiet("grade"):
            runner.run()
    except Exception as error:
        run.error = error_check(error, path, "in the probe's node")
        return run
    assert runner.node is not None
    run.stop_reason = runner.node.terminate_reason
    return run


@dataclass
class Received:
    """What a node with the student's part got from another node over comms.

    Example::

        got = over_comms(MyDatastore, None, Path("mine.py"))
        got.seen[:3]     # [0, 1, 2]: the 'count' values its handler saw, in order
    """

    seen: List[Any] = field(default_factory=list)
    """The ``count`` values the receiving node's handler saw, in order."""
    last: Any = None
    """``get_page("count")`` once the last was seen (or the time ran out)."""
    keys: List[Any] = field(default_factory=list)
    """``list(node.datastore)`` then."""
    error: Optional[Check] = None
    """Set when the receiving node raised."""


class _Sender(Endpoint):
    """Stores the pages once the link is up; says when the last has gone to the link."""

    def __init__(self, factory: _SenderFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sender")
        self.sent = factory.sent
        self.task_handlers = {
            (TaskType.event, COMMS_CONNECTED): self.send,
            (TaskType.store_page, "count"): self.stored,  # after the comms component's
        }

    def send(self, task: Task, key: TaskId) -> SomeTasks:
        return [self.store_data_task("count", i) for i in range(SENT)]

    def stored(self, task: Task, key: TaskId) -> SomeTasks:
        if task.val_list[0].data == SENT - 1:
            self.sent.set()
        return None


class _SenderFactory(EndpointFactory):
    def __init__(self, sent: threading.Event) -> None:
        super().__init__()
        self.sent = sent

    def get(self, parent: AbstractNode) -> _Sender:
        return _Sender(self, parent)


class _Receiver(Endpoint):
    def __init__(self, factory: _ReceiverFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "grader")
        self.got, self.done = factory.got, factory.done
        self.task_handlers = {(TaskType.store_page, "count"): self.count}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        self.got.seen.append(task.val_list[0].data)
        if task.val_list[0].data == SENT - 1:
            self.got.last = self.parent.get_page("count")
            self.got.keys = list(self.parent.datastore)
            self.done.set()
        return None


class _ReceiverFactory(EndpointFactory):
    def __init__(self, got: Received, done: threading.Event) -> None:
        super().__init__()
        self.got, self.done = got, done

    def get(self, parent: AbstractNode) -> _Receiver:
        return _Receiver(self, parent)


def over_comms(
    datastore: Optional[Callable[[], Any]], node_core: Optional[AbstractFactory], path: Path
) -> Received:
    """`SENT` pages under ``count`` from node ``sender`` to node ``receiver``, linked in memory.

    The receiver has the student's part; the sender SNR's own. Real threads
    and the wall clock (a link is real I/O): it waits for the last page, up to
    1.5 s after the sender sent it (3 s in all), then stops both nodes.

    Example::

        got = over_comms(None, None, Path("x.py"))
        got.seen == list(range(SENT))    # True: every page, in order
    """
    got, done, sent = Received(), threading.Event(), threading.Event()
    pair = MemoryLinkPair()
    factories: Dict[str, List[AbstractFactory]] = {
        "receiver": [pair.first(), _ReceiverFactory(got, done)],
        "sender": [pair.second(["count"]), _SenderFactory(sent)],
    }
    errors: List[BaseException] = []
    try:
        nodes = [
            Node(
                "receiver",
                Config(factories, Mode.TEST, datastore=datastore, node_core=node_core),
            ),
            Node("sender", Config(factories, Mode.TEST)),
        ]
    except Exception as error:
        pair.close()
        got.error = error_check(error, path, "as the receiving node was built")
        return got

    def run(node: Node) -> None:
        try:
            node.loop()
        except BaseException as error:  # reported below, as the grade's check
            errors.append(error)

    threads = [threading.Thread(target=run, args=(node,), daemon=True) for node in nodes]
    with quiet("receiver", "sender"):
        for thread in threads:
            thread.start()
        # Until the last page is handled: 1.5 s at most after it was sent, 3 s in all.
        deadline = time.monotonic() + 3.0
        if sent.wait(3.0):
            deadline = min(deadline, time.monotonic() + 1.5)
        if not done.wait(max(0.0, deadline - time.monotonic())):  # what got there, then
            try:
                got.keys, got.last = list(nodes[0].datastore), nodes[0].get_page("count")
            except Exception as error:
                errors.append(error)
        stop(nodes, threads)
    pair.close()
    if errors:
        got.error = error_check(errors[0], path, "in the receiving node")
    return got


def stop(nodes: List[Node], threads: List[threading.Thread]) -> None:
    """Ask each node to stop, and wait (3 s at most) for their threads.

    Example::

        stop([receiver, sender], threads)    # the threads running their loop()s
    """
    for node in nodes:
        node.set_terminate_flag("the grade is over")
    deadline = time.monotonic() + 3.0
    for thread in threads:
        thread.join(max(0.0, deadline - time.monotonic()))


def demo(
    seconds: float,
    datastore: Optional[Callable[[], Any]] = None,
    node_core: Optional[AbstractFactory] = None,
) -> Node:
    """Lesson 1's wall follower, for ``seconds`` of simulated time, with the given parts.

    What ``python datastore.py`` and ``python node_core.py`` run: the robot
    of lesson 1 (its solution) in its room, headless, as fast as the
    computer goes, in a node whose datastore or core is yours. It prints
    where the robot got to and what the datastore holds; a node that does
    not stop when the time is up is stopped a simulated second later, saying so.

    Example::

        node = demo(10.0, datastore=MyDatastore)
        sorted(node.datastore)   # ['bump', 'odometry', 'range', 'true_pose', 'wheel_cmd']
    """
    from snr.extras.lessons.l01_wall_follower.solution import WallFollowerFactory, make_world

    world = make_world()
    components: List[AbstractFactory] = [
        snr.SimRobotFactory(world, seed=1),
        WallFollowerFactory(),
        TimeoutLoopFactory(seconds=seconds),
        _DeadlineFactory(seconds + 1.0),
    ]
    clock = SimClock(speed=None)
    config = Config({"sim": components}, clock=clock, datastore=datastore, node_core=node_core)
    runner = TestRunner("sim", config, timeout_s=20.0)
    runner.run()
    node = runner.node
    assert node is not None
    if node.terminate_reason == OVERTIME:
        print(
            f"The node did not stop when the {seconds:g} s were up: its terminate task "
            "did nothing. It was stopped a simulated second later."
        )
    pose = node.get_data("true_pose")
    where = "nowhere: no 'true_pose' page"
    if pose is not None:
        where = f"({pose['x']:.2f}, {pose['y']:.2f})"
    print(f"The wall follower drove {seconds:g} s (simulated); the robot got to {where}.")
    keys = list(node.datastore)
    print(f"The datastore holds {len(keys)} keys: {', '.join(sorted(keys)) or 'none'}.")
    return node
