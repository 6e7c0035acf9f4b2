"""``python task_queue.py``: lesson 7's queue in a running program, between loops and a node.

The node's own queue is SNR's (there is no ``Config`` option for it:
docs/assignments.md says why), so your queue goes *in front of* it: loops
put tasks into your queue, and one more loop, the feeder, waits on it and
hands each task it takes to the node with ``self.schedule``. An endpoint
counts what arrives. Many producers, one consumer: the lesson's queue, in a
program.

Example::

    run_demo(MyTaskQueue, seconds=3.0, producers=4)
"""

from __future__ import annotations

import threading
from typing import Any, Callable, Dict, List

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
)
from snr.core import TestRunner

__all__ = ["Tally", "run_demo"]

BATCH = 50
"""Tasks a producer puts each pass of its loop."""


class Tally:
    """What went through the queue: what each producer put, and what the node handled.

    Example::

        tally = Tally(queue)
        tally.handled["p0"]    # [0, 1, 2, ...]: producer p0's tasks, as the node got them
    """

    def __init__(self, queue: Any) -> None:
        self.queue = queue
        self.lock = threading.Lock()  # producers count from their own threads
        self.put = 0
        self.refused = 0
        self.fed = 0
        self.handled: Dict[str, List[int]] = {}


class _Producer(ThreadLoop):
    """Puts numbered tasks into the queue, as fast as the queue takes them."""

    def __init__(self, factory: _ProducerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, f"producer_{factory.name}")
        self.tally = factory.tally
        self.task_name = factory.name
        self.count = 0

    def loop(self) -> None:
        put = refused = 0
        for _ in range(BATCH):
            if self.is_terminated():
                break
            if self.tally.queue.put(Task(TaskType.event, self.task_name, [self.count])):
                put += 1
            else:
                refused += 1
            self.count += 1
        with self.tally.lock:
            self.tally.put += put
            self.tally.refused += refused

    def halt(self) -> None:
        self.tally.queue.close()  # wakes a producer waiting for room, and the feeder


class _ProducerFactory(LoopFactory):
    def __init__(self, tally: Tally, name: str) -> None:
        super().__init__()
        self.tally = tally
        self.name = name

    def get(self, parent: AbstractNode) -> _Producer:
        return _Producer(self, parent)


class _Feeder(ThreadLoop):
    """The queue's one consumer: waits for tasks and hands each to the node."""

    def __init__(self, factory: _FeederFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "feeder")
        self.tally = factory.tally
        self.queue = factory.tally.queue

    def loop(self) -> None:
        self.queue.wait(0.1)  # sleeps, using no CPU, until a task comes (or 0.1 s)
        task = self.queue.take()
        while task is not None:
            self.schedule(task)  # into the node's own queue
            self.tally.fed += 1
            task = self.queue.take()

    def halt(self) -> None:
        self.queue.close()


class _FeederFactory(LoopFactory):
    def __init__(self, tally: Tally) -> None:
        super().__init__()
        self.tally = tally

    def get(self, parent: AbstractNode) -> _Feeder:
        return _Feeder(self, parent)


class _Counter(Endpoint):
    """Keeps the number of each task the node handles, by producer."""

    def __init__(self, factory: _CounterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "counter")
        self.handled = factory.tally.handled
        self.task_handlers = {(TaskType.event, name): self.count for name in factory.names}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        self.handled.setdefault(task.name, []).append(task.val_list[0])
        return None


class _CounterFactory(EndpointFactory):
    def __init__(self, tally: Tally, names: List[str]) -> None:
        super().__init__()
        self.tally = tally
        self.names = names

    def get(self, parent: AbstractNode) -> _Counter:
        return _Counter(self, parent)


def run_demo(make: Callable[..., Any], seconds: float, producers: int) -> Tally:
    """Run ``producers`` loops putting tasks into ``make()``'s queue, fed into a node, ``seconds``.

    It prints how many tasks were put, refused and handled, and whether any
    producer's tasks reached the node twice or out of order.

    Example::

        tally = run_demo(MyTaskQueue, seconds=3.0, producers=4)
        tally.put, tally.refused
    """
    tally = Tally(make(capacity=100, max_wait_s=1.0))
    names = [f"p{number}" for number in range(producers)]
    components = [
        *(_ProducerFactory(tally, name) for name in names),
        _FeederFactory(tally),
        _CounterFactory(tally, names),
        TimeoutLoopFactory(seconds=seconds),
    ]
    TestRunner("queue_demo", Config({"queue_demo": components}), timeout_s=seconds + 10).run()
    handled = sum(len(numbers) for numbers in tally.handled.values())
    wrong = [
        name
        for name, numbers in tally.handled.items()
        if any(b <= a for a, b in zip(numbers, numbers[1:]))
    ]
    print(
        f"{producers} loops put {tally.put:,} tasks into a {type(tally.queue).__name__} in "
        f"{seconds:g} s; {tally.refused:,} refused (no room within max_wait_s)."
    )
    order = f"{', '.join(wrong)}'s twice or out of order" if wrong else "each loop's once, in order"
    queued = len(tally.queue)
    print(
        f"The feeder took {tally.fed:,} out, {queued:,} are still queued; the node handled "
        f"{handled:,}, {order}."
    )
    lost = tally.put - tally.fed - queued
    if lost > 0:
        print(f"{lost:,} tasks were put (put returned True) but never came out of the queue.")
    return tally
