"""`StepMode`: pause a node, run its tasks one at a time, look around, resume.

After a console's ``pause`` the node runs only urgent tasks (a terminate, the
console's own commands: `console_priority`); the rest wait in order, and
``step`` runs the oldest through its handlers and says what they returned.
Loops keep running (the drop log then says the node is paused). The run loop
calls `run_paused` while ``paused``.

Example::

    node.step_mode.pause()                       # on the node's thread (a handler)
    node.step_mode.step(1, lambda steps: print(steps[0].task))
    node.step_mode.resume()
"""

from __future__ import annotations

import collections
import itertools
from dataclasses import dataclass, field
from typing import Any, Callable, Deque, List, Optional, Tuple

from snr.core.dispatch import HandlerRunner
from snr.core.task_queue import TaskQueue
from snr.prelude import AbstractNode, Task, TaskPriority, TaskType

__all__ = ["MAX_STEPS", "Step", "StepMode", "console_priority"]

MAX_STEPS = 100
"""The most tasks one ``step N`` runs, and the most step requests waiting at once."""

_PAUSED_WHY = (
    "the node is paused (step mode): only `step` runs its tasks; type `resume` in the "
    "console to let it run on"
)


@dataclass
class Step:
    """What one step did: the task, the handlers it went to, what they returned.

    Attributes:
        task: the task that ran, or None if the queue had none.
        handlers: ``component.method`` of each handler it went to, in order.
        returned: the tasks those handlers returned (now at the back of the queue).
        next_tasks: the first few tasks waiting after it, urgent ones first.
        waiting: how many tasks wait in the queue after it.

    Example::

        Step(task=(store_page, 'range'), handlers=['wanderer.steer'],
             returned=[(store_page, 'wheel_cmd')], next_tasks=[...], waiting=12)
    """

    task: Optional[Task]
    handlers: List[str] = field(default_factory=list)
    returned: List[Task] = field(default_factory=list)
    next_tasks: List[Task] = field(default_factory=list)
    waiting: int = 0


@dataclass
class _StepRequest:
    left: int
    report: Callable[[List[Step]], None]
    done: List[Step] = field(default_factory=list)


class StepMode:
    """Pauses its node's run loop; runs held tasks one at a time on request (node's thread).

    Args:
        queue: the node's task queue.
        runner: the node's `HandlerRunner`.
        lookup: a task's ``(handler, key, component, cell)`` entries.
        stopping: True once the node is stopping.

    Example::

        node.step_mode.paused      # False: the node runs freely

    Attributes:
        paused: True between `pause` and `resume`.
    """

    def __init__(
        self,
        queue: TaskQueue,
        runner: HandlerRunner,
        lookup: Callable[[Task], List[Any]],
        stopping: Callable[[], bool],
    ) -> None:
        self.queue = queue
        self.runner = runner
        self.lookup = lookup
        self.stopping = stopping
        self.paused = False
        self._requests: Deque[_StepRequest] = collections.deque()
        self._running_why = queue.loss.why
        self._at_pause = (0, 0)  # the queue's waits and drops when paused

    def pause(self) -> None:
        """Hold every task but urgent ones after the current task (no-op if paused)."""
        if self.paused:
            return
        self.paused = True
        self.runner.running = False  # run_queued returns after the task running now
        self._at_pause = (self.queue.waits, self.queue.loss.total)
        self.queue.loss.why = _PAUSED_WHY

    def resume(self) -> None:
        """Run freely again; steps still waiting are reported with what they did."""
        if not self.paused:
            return
        self.paused = False
        self.queue.loss.why = self._running_why
        # A node stopping meanwhile keeps running=False.
        self.runner.running = not self.stopping()
        while self._requests:
            request = self._requests.popleft()
            request.report(request.done)

    def step(self, count: int, report: Callable[[List[Step]], None]) -> None:
        """Run the next ``count`` held tasks, one per turn, then ``report`` what each did.

        Raises:
            ValueError: not paused, ``count`` not from 1 to `MAX_STEPS`, or too many waiting.
        """
        if not self.paused:
            raise ValueError("The node is running: pause it first.")
        if not 1 <= count <= MAX_STEPS:
            raise ValueError(f"A step runs 1 to {MAX_STEPS} tasks, not {count}.")
        if len(self._requests) >= MAX_STEPS:
            raise ValueError(f"{MAX_STEPS} step requests already wait; wait for their replies.")
        self._requests.append(_StepRequest(count, report))

    def since_pause(self) -> Tuple[int, int]:
        """(times loops waited for room in the queue, tasks dropped) since the pause.

        Example::

            waits, dropped = node.step_mode.since_pause()   # (0, 0): nothing lost
        """
        waits, drops = self._at_pause
        return self.queue.waits - waits, self.queue.loss.total - drops

    def run_paused(self, idle_s: Optional[float]) -> None:
        """One turn of the node's run loop while paused: urgent tasks, then a step, else sleep."""
        queue = self.queue
        if queue.urgent:
            self.runner.run_queued(max_tasks=1)  # a console command, or a terminate
        elif self._requests:
            self._step_once(self._requests[0])
        else:
            queue.wait(idle_s, urgent_only=True)

    def _step_once(self, request: _StepRequest) -> None:
        normal = self.queue.normal
        task = normal.popleft() if normal else None
        step = Step(task)
        if task is not None:
            store = self.runner.store_page
            if task.type is TaskType.store_page and store is not None:
                step.handlers.append(_handler_name(store, getattr(store, "__self__", None)))
                stored = self.runner.store_first(task)
                if stored is not None:
                    step.returned.append(stored)
            entries = self.lookup(task)
            if not entries and task.type is TaskType.event and self.runner.on_unhandled:
                self.runner.on_unhandled(task)  # DEBUG: as when running
            for handler, key, component, cell in entries:
                step.handlers.append(_handler_name(handler, component))
                returned = self.runner.run(handler, task, key, component, cell)
                if returned:
                    step.returned += returned
                    self.runner.queue_all(returned)
        step.next_tasks = self.next_tasks()
        step.waiting = len(self.queue)
        request.done.append(step)
        request.left -= 1
        if request.left == 0 or task is None or self.stopping():
            self._requests.popleft()
            request.report(request.done)

    def next_tasks(self, count: int = 3) -> List[Task]:
        """The first ``count`` tasks waiting, urgent ones first.

        Example::

            node.step_mode.next_tasks(1)   # [the task `step` would run], or []
        """
        # deque.copy() runs in C holding the GIL: a snapshot even while loops append.
        lanes = (self.queue.urgent.copy(), self.queue.normal.copy())
        return list(itertools.islice(itertools.chain(*lanes), count))


def _handler_name(handler: Any, component: Any) -> str:  # "wanderer.steer"
    name = getattr(handler, "__name__", repr(handler))
    owner = getattr(component, "name", None)
    return f"{owner}.{name}" if owner else name


def console_priority(node: AbstractNode) -> TaskPriority:
    """The priority of a console's own tasks: high while ``node`` is paused, so they run.

    Example::

        Task(TaskType.event, "console_command:c", [line, session],
             priority=console_priority(node))
    """
    step_mode: Optional[StepMode] = getattr(node, "step_mode", None)  # a mock node has none
    paused = step_mode is not None and step_mode.paused
    return TaskPriority.high if paused else TaskPriority.normal
