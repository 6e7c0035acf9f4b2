"""Small components and waits shared by the tests (not part of the library)."""

from __future__ import annotations

import contextlib
import gc
import os
import socket
import sys
import time
import unittest
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple, TypeVar

from snr import (
    AbstractNode,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    tasks,
)

Log = List[Tuple[str, Any]]
T = TypeVar("T")


@contextlib.contextmanager
def no_pygame() -> Iterator[None]:
    """Within the block, ``import pygame`` fails as if it were not installed."""
    saved = sys.modules.get("pygame")
    sys.modules["pygame"] = None  # type: ignore[assignment]
    try:
        yield
    finally:
        if saved is None:
            del sys.modules["pygame"]
        else:
            sys.modules["pygame"] = saved


def wait_until(condition: Callable[[], T], timeout_s: float = 5.0) -> T:
    """Poll ``condition`` every 5 ms until it is truthy or ``timeout_s`` has passed; its last value.

    Tests wait on what they need to see, never for a fixed time: the wait ends
    as soon as the condition holds, and the deadline only bounds a failure.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        value = condition()
        if value or time.monotonic() > deadline:
            return value
        time.sleep(0.005)


def catches_signal(pid: int, signum: int, timeout_s: float = 10.0) -> Optional[bool]:
    """Wait until process ``pid`` has a handler for ``signum``: True, or False after ``timeout_s``.

    Reads ``SigCgt`` in ``/proc/PID/status``; None where there is no /proc (macOS).
    """
    status_path = f"/proc/{pid}/status"
    if not os.path.exists(status_path):
        return None
    deadline = time.monotonic() + timeout_s
    while True:
        with open(status_path) as status:
            caught = next(line for line in status if line.startswith("SigCgt:"))
        if int(caught.split()[1], 16) & (1 << (signum - 1)):
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.005)


def settle_the_heap(test: unittest.TestCase) -> None:
    """Collect, then keep what earlier tests left out of later collections, for ``test``.

    In one long run (``python -m unittest discover``) earlier tests leave a big heap; a
    full collection over it while a test measures CPU, or while a loop allocates a page
    every pass, holds the GIL for many milliseconds. ``gc.freeze`` keeps those objects
    out of collections until the test ends.

    Example::

        def setUp(self) -> None:
            settle_the_heap(self)
    """
    gc.collect()
    gc.freeze()
    test.addCleanup(gc.unfreeze)


def free_port() -> int:
    """A TCP port that was free a moment ago on 127.0.0.1 (bound, then released)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class FactoryOf(EndpointFactory):
    """Builds whatever ``build(factory, parent)`` returns: one factory for many components."""

    def __init__(self, build: Callable[[Any, AbstractNode], Any]) -> None:
        super().__init__()
        self.build = build

    def get(self, parent: AbstractNode) -> Any:
        return self.build(self, parent)


class LoopFactoryOf(LoopFactory):
    """`FactoryOf` for loops: builds whatever ``build(factory, parent)`` returns."""

    def __init__(self, build: Callable[[Any, AbstractNode], Any]) -> None:
        super().__init__()
        self.build = build

    def get(self, parent: AbstractNode) -> Any:
        return self.build(self, parent)


class Recorder(Endpoint):
    """Appends ``(endpoint name, task id or key)`` to a shared log per task."""

    def __init__(
        self,
        factory: RecorderFactory,
        parent: AbstractNode,
        name: str,
        keys: List[TaskId],
        log: Log,
        reply: Optional[Callable[[Task, TaskId], SomeTasks]],
    ) -> None:
        super().__init__(factory, parent, name)
        self.log_list = log
        self.reply = reply
        self.task_handlers = {key: self.record for key in keys}

    def record(self, task: Task, key: TaskId) -> SomeTasks:
        self.log_list.append((self.name, (task.type, task.name, key)))
        return self.reply(task, key) if self.reply else None


class RecorderFactory(EndpointFactory):
    def __init__(
        self,
        name: str,
        keys: List[TaskId],
        log: Log,
        reply: Optional[Callable[[Task, TaskId], SomeTasks]] = None,
    ) -> None:
        super().__init__()
        self.name, self.keys, self.log, self.reply = name, keys, log, reply
        self.built: Dict[str, Recorder] = {}

    def get(self, parent: AbstractNode) -> Recorder:
        endpoint = Recorder(self, parent, self.name, self.keys, self.log, self.reply)
        self.built[self.name] = endpoint
        return endpoint


class StopWhen(Endpoint):
    """Stops the node once ``when(task)`` has held for ``count`` tasks with ``task_id``.

    List it after the components whose handling of that task the test checks:
    every handler of a task runs before the terminate task it returns.
    """

    def __init__(self, factory: StopWhenFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.spec = factory
        self.matched = 0
        self.task_handlers = {factory.task_id: self.check}

    def check(self, task: Task, key: TaskId) -> SomeTasks:
        if not self.spec.when(task):
            return None
        self.matched += 1
        if self.matched == self.spec.count:
            return tasks.terminate(self.spec.reason)
        return None


class StopWhenFactory(EndpointFactory):
    """E.g. ``StopWhenFactory((TaskType.store_page, "depth"), count=2)``."""

    def __init__(
        self,
        task_id: TaskId,
        when: Callable[[Task], bool] = lambda task: True,
        count: int = 1,
        reason: str = "test work done",
    ) -> None:
        super().__init__()
        self.task_id, self.when, self.count, self.reason = task_id, when, count, reason
        self.name = "stop_when"

    def get(self, parent: AbstractNode) -> StopWhen:
        return StopWhen(self, parent)


class StopWhenTrue(ThreadLoop):
    """Stops the node as soon as ``condition()`` holds, or once ``within_s`` have passed.

    For a test that waits on something no task marks (a loop's count, a
    thread's state): it checks every 2 ms. Past the bound it stops the node
    with the reason "condition not met within ... s", which the test's
    assertions then show.
    """

    def __init__(self, factory: StopWhenTrueFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stop_when_true", max_tick_rate_hz=500)
        self.spec = factory

    def loop(self) -> None:
        if self.spec.condition():
            reason = self.spec.reason
        elif self.parent.get_time_s() > self.spec.within_s:
            reason = f"condition not met within {self.spec.within_s:g} s"
        else:
            return
        self.schedule(tasks.terminate(reason))
        self.set_terminate_flag(reason)


class StopWhenTrueFactory(LoopFactory):
    """E.g. ``StopWhenTrueFactory(lambda: ticker.ticks >= 3, within_s=0.3)``."""

    def __init__(
        self, condition: Callable[[], object], within_s: float, reason: str = "test work done"
    ) -> None:
        super().__init__()
        self.condition, self.within_s, self.reason = condition, within_s, reason

    def get(self, parent: AbstractNode) -> StopWhenTrue:
        return StopWhenTrue(self, parent)


DRAINED = (TaskType.process_data, "test_queue_drained")
"""The marker task of `StopWhenDrained`: no test endpoint handles process_data."""


class StopWhenDrained(Endpoint):
    """Schedules ``first``, then stops the node once the queue has run dry.

    A marker task goes to the back of the queue ``rounds`` times, so the tasks
    that ``first`` caused (up to ``rounds`` levels of returned tasks) all run
    before the node stops with the reason "queue drained".
    """

    def __init__(self, factory: StopWhenDrainedFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stop_when_drained")
        self.spec = factory
        self.rounds_left = factory.rounds
        self.task_handlers = {DRAINED: self.round_done}

    def begin(self) -> None:
        self.schedule([*self.spec.first, Task(*DRAINED)])

    def round_done(self, task: Task, key: TaskId) -> SomeTasks:
        self.rounds_left -= 1
        if self.rounds_left > 0:
            return Task(*DRAINED)
        return tasks.terminate("queue drained")


class StopWhenDrainedFactory(EndpointFactory):
    def __init__(self, first: Sequence[Task] = (), rounds: int = 3) -> None:
        super().__init__()
        self.first, self.rounds = list(first), rounds

    def get(self, parent: AbstractNode) -> StopWhenDrained:
        return StopWhenDrained(self, parent)
