"""Lesson 7's grader: is the task queue safe for many producers and one consumer?

It runs the student's queue with real threads, as a node's loops and its
thread use SNR's own: producers that ``put``, a consumer that ``wait``\\ s and
``take``\\ s. Every call of the student's runs on a thread of its own with a
time limit, so a call that never returns fails its check instead of hanging
the grade; while it grades, Python switches threads every microsecond or so
(``sys.setswitchinterval``), which makes races show, and puts the interval
back after. What it checks, never how the class is written:

* it is a class with ``put``, ``take``, ``wait``, ``close`` and ``__len__``,
  made with ``cls(capacity=..., max_wait_s=...)``; its calls raise nothing;
* one thread's tasks come back in the order put, then None; ``len`` counts them;
* a high-priority task (terminate) jumps ahead, even when the queue is full;
* ``wait`` sleeps while the queue is empty and returns as soon as a task comes,
  and at once when one is there;
* an idle consumer, in ``wait``, uses no CPU (its thread's CPU time);
* ``put`` waits while the queue is full and goes on when there is room, and
  gives up (False) after ``max_wait_s``;
* ``close`` wakes the consumer sleeping in ``wait`` and a producer in ``put``;
* eight producers, 250 tasks each, against one consumer: every task taken
  once, none lost, each producer's in its order;
* 72 tasks handed over one at a time, each put at another moment of the
  consumer's ``wait`` (`_Handover`): no wake-up is lost (the consumer never
  sleeps to its timeout with a task in the queue).

SNR's own ``TaskQueue`` passes every check, through ``snr_queue.SnrTaskQueue``
(tests/test_lesson_assignments.py). A grade takes two or three seconds.

Example::

    for check in grade(Path("task_queue.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from snr import Task, TaskType, tasks
from snr.extras.lessons.grading import Check, _line_in, load_submission
from snr.extras.lessons.probe import find_class, method_line

__all__ = ["METHODS", "grade", "grade_queue", "is_task_queue"]

METHODS = ("put", "take", "wait", "close", "__len__")
"""What a lesson 7 queue has (docs/assignments.md)."""
CAPACITY = 8
"""The capacity of the queues of the single checks."""
PRODUCERS, EACH = 8, 250
"""The many-producers check: this many threads put this many tasks each."""
STRESS_CAPACITY = 64
"""The many-producers check's capacity: producers wait for room often, never long."""
ROUNDS = 72
"""Tasks handed over one at a time in the lost wake-up check."""
SPREAD = 24
"""The lost wake-up check puts each task at one of the first this many calls of ``wait``."""
NAP_S = 0.4
"""The consumer's ``wait`` timeout in the lost wake-up check: a lost wake-up costs this much."""
SWITCH_S = 1e-6
"""``sys.setswitchinterval`` while grading: threads switch as often as Python lets them."""
IDLE_S = 0.4
"""How long the idle consumer waits, for the CPU check."""
IDLE_CPU_S = 0.05
"""The most CPU time the idle consumer may use in `IDLE_S` (sleeping uses about none)."""
SOON_S = 0.3
"""How soon a waiting thread must wake once it has cause (a task, room, close)."""
LIMIT_S = 3.0
"""How long any call may take before the grade gives up on it."""


def is_task_queue(cls: type) -> bool:
    """True for a class with lesson 7's five methods.

    Example::

        is_task_queue(SnrTaskQueue)    # True
    """
    return all(callable(getattr(cls, name, None)) for name in METHODS)


def grade(path: Path) -> List[Check]:
    """The checks of lesson 7 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no task queue class.

    Example::

        all(check.passed for check in grade(Path("task_queue.py")))
    """
    module = load_submission(path)
    what = "task queue class (with put, take, wait, close, __len__)"
    return grade_queue(find_class(module, is_task_queue, what), path)


def grade_queue(make: Callable[..., Any], path: Path) -> List[Check]:
    """The checks of lesson 7 for the queues ``make(capacity=..., max_wait_s=...)`` makes.

    Example::

        grade_queue(SnrTaskQueue, Path("snr"))    # SNR's own queue: every check passes
    """
    name = getattr(make, "__qualname__", repr(make))
    first = Check(
        "the queue",
        True,
        happened=f"{name}, made with {name}(capacity=N, max_wait_s=S) for each check",
        line=method_line(make, "__init__"),
    )
    grader = _Grader(make, path)
    checks: List[Check] = []
    previous = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_S)
    try:
        for step in (
            grader.in_order,
            grader.urgent_first,
            grader.wakes,
            grader.idle,
            grader.waits_for_room,
            grader.gives_up,
            grader.close_wakes,
            grader.many_producers,
            grader.no_lost_wake_up,
        ):
            check = step()
            if grader.error is not None:
                return [first, grader.error, *checks]
            checks.append(check)
    finally:
        sys.setswitchinterval(previous)
    return [first, Check("runs without an exception", True), *checks]


def _task(producer: int, number: int) -> Task:
    """Task ``number`` of ``producer``: an event that says whose and which it is."""
    return Task(TaskType.event, f"p{producer}", [number])


def _words(task: Any) -> str:
    """A task taken back, in a few words: ``p0 #3``, ``terminate``, or what it is instead."""
    if isinstance(task, Task):
        if task.type is TaskType.terminate:
            return "terminate"
        number = task.val_list[0] if task.val_list else "?"
        return f"{task.name} #{number}"
    return repr(task)


class _Call:
    """One call of the student's queue, on a thread of its own: what it gave, and when.

    Example::

        call = _Call(lambda: queue.put(task), grader, "put")
        call.join(1.0)           # True once it returned
        call.result, call.took_s
    """

    def __init__(self, run: Callable[[], Any], grader: _Grader, what: str) -> None:
        self.grader = grader
        self.what = what
        self.result: Any = None
        self.ended: Optional[float] = None
        self.cpu_s = 0.0
        self.started = time.monotonic()
        self.thread = threading.Thread(
            target=self._run, args=(run,), daemon=True, name=f"lesson 7: {what}"
        )
        self.thread.start()

    def _run(self, run: Callable[[], Any]) -> None:
        cpu = time.thread_time()
        try:
            self.result = run()
        except Exception as error:
            self.grader.raised(error, self.what)
        finally:
            self.cpu_s = time.thread_time() - cpu
            self.ended = time.monotonic()

    def join(self, timeout_s: float = LIMIT_S) -> bool:
        """Wait up to ``timeout_s`` for the call to return; True if it has."""
        self.thread.join(timeout_s)
        return self.ended is not None

    def returned(self) -> bool:
        """True once the call has returned."""
        return self.ended is not None

    def after(self, moment: float) -> float:
        """How long after ``moment`` (``time.monotonic()``) it returned; inf while it has not."""
        return float("inf") if self.ended is None else self.ended - moment

    @property
    def took_s(self) -> float:
        """How long the call took (so far, if it has not returned)."""
        return (self.ended or time.monotonic()) - self.started


class _Grader:
    """The checks, each on fresh queues of the student's class."""

    def __init__(self, make: Callable[..., Any], path: Path) -> None:
        self.make = make
        self.path = path
        self.error: Optional[Check] = None
        self.basics = False
        """True once one thread's tasks come back in order: the threaded checks need it."""
        self.lines: Dict[str, Optional[int]] = {
            name: method_line(make, name) for name in (*METHODS, "__init__")
        }

    def raised(self, error: Exception, what: str) -> None:
        """Note the first exception the student's code raised (any thread)."""
        if self.failed():
            return
        line = _line_in(error, self.path)
        if line is None:
            line = self.lines.get(what.split("(")[0], self.lines["__init__"])
        self.error = Check(
            "runs without an exception",
            False,
            expected="every call of the queue returns, on every thread",
            happened=f"{type(error).__name__}: {error} (in {what}); the grade stopped there",
            hint="read the line named here: an empty or a full queue is no error (take "
            "gives None; put waits, then returns False)",
            line=line,
        )

    def failed(self) -> bool:
        """True once the student's code raised an exception (on any thread)."""
        return self.error is not None

    def call(self, what: str, run: Callable[[], Any]) -> _Call:
        """Start ``run`` (a call of the queue, named ``what``) on a thread of its own."""
        return _Call(run, self, what)

    def queue(self, capacity: int = CAPACITY, max_wait_s: float = 1.0) -> Any:
        """A new queue of the student's class, made on a thread (its ``__init__`` may hang)."""
        made = self.call("__init__", lambda: self.make(capacity=capacity, max_wait_s=max_wait_s))
        if not made.join():
            self.raised(TimeoutError(f"__init__ did not return in {LIMIT_S:g} s"), "__init__")
        return made.result

    def fill(self, queue: Any, count: int) -> Optional[str]:
        """Put ``count`` tasks of producer 0 into ``queue``; what went wrong, or None."""
        for number in range(count):
            put = self.call("put(task)", lambda n=number: queue.put(_task(0, n)))  # type: ignore[misc]
            if not put.join(1.5):
                return f"put of task {number + 1} of {count} waited, with room in the queue"
            if put.result is not True:
                return f"put of task {number + 1} of {count} returned {put.result!r}"
        return None

    def release(self, queue: Any) -> None:
        """Try to end a call of ``queue``'s that never returned: close it, and put a task.

        A ``wait`` that spins until a task comes (``while not self.normal:
        pass``) would otherwise keep a core busy for the rest of the grade.
        """
        self.call("close()", queue.close)
        self.call("put(task)", lambda: queue.put(_task(9, 0)))
        self.call("put(terminate)", lambda: queue.put(tasks.terminate("the grade")))

    def untried(self, name: str, expected: str, hint: str, line: Optional[int]) -> Check:
        """``name``, failed as not tried: one thread's tasks do not come back yet."""
        return Check(
            name,
            False,
            expected=expected,
            happened="not tried: the queue does not yet give back what one thread puts "
            "(see 'gives back one thread's tasks in the order put')",
            hint=hint,
            line=line,
        )

    # -- the checks ---------------------------------------------------------
    def in_order(self) -> Check:
        name = "gives back one thread's tasks in the order put"
        expected = "5 puts return True; len() is 5; take() gives them back in order, then None"
        hint = (
            "put appends the task to self.normal; take pops the oldest (popleft), or "
            "returns None when there is none (step 1)"
        )
        queue = self.queue()
        if self.failed():
            return Check(name, False)

        def one_thread() -> Tuple[List[Any], Any, List[Any], Any]:
            puts = [queue.put(_task(0, n)) for n in range(5)]
            count = len(queue)
            taken = [queue.take() for _ in range(6)]
            return puts, count, taken, len(queue)

        run = self.call("put, len() and take() on one thread", one_thread)
        if not run.join():
            return Check(
                name,
                False,
                expected,
                f"it did not return in {LIMIT_S:g} s",
                hint,
                self.lines["put"],
            )
        if self.failed():
            return Check(name, False)
        puts, count, taken, after = run.result
        wanted = [f"p0 #{n}" for n in range(5)] + ["None"]
        got = [_words(task) for task in taken]
        line = self.lines["take"]
        if any(result is not True for result in puts):
            happened = f"put returned {puts}"
            hint = "put returns True when it queued the task, False only when it gave up (step 1)"
            line = self.lines["put"]
        elif got != wanted:
            kept = sum(word.startswith("p0") for word in got)
            happened = f"{kept} of 5 taken back: take() gave {', '.join(got)}"
            line = self.lines["take"] if kept else self.lines["put"]  # none: put keeps nothing
        elif count != 5 or after != 0:
            happened = f"len() was {count!r} with 5 tasks queued, {after!r} with none"
            hint = "__len__ counts the tasks in both lanes (step 1)"
            line = self.lines["__len__"]
        else:
            self.basics = True
            return Check(name, True)
        return Check(name, False, expected, happened, hint, line)

    def urgent_first(self) -> Check:
        name = "a high-priority task jumps ahead, even when the queue is full"
        expected = (
            f"with {CAPACITY} tasks queued (full), put(terminate) returns True at once and "
            "take() gives it first"
        )
        hint = (
            "put appends a task with task.priority to self.urgent, without waiting for "
            "room; take pops self.urgent first (step 2)"
        )
        queue = self.queue(max_wait_s=1.0)
        if self.failed():
            return Check(name, False)
        problem = self.fill(queue, CAPACITY)
        if self.failed():
            return Check(name, False)
        if problem is not None:
            return Check(name, False, expected, problem, hint, self.lines["put"])
        put = self.call("put(terminate)", lambda: queue.put(tasks.terminate("stop")))
        returned = put.join(2.0)
        if self.failed():
            return Check(name, False)
        if not returned or put.took_s > SOON_S:
            said = "did not return" if not returned else f"returned after {put.took_s:.2f} s"
            happened = f"put(terminate) {said}: it waited for room"
            return Check(name, False, expected, happened, hint, self.lines["put"])
        take = self.call("take()", queue.take)
        take.join()
        if self.failed():
            return Check(name, False)
        if put.result is not True or _words(take.result) != "terminate":
            happened = f"put(terminate) returned {put.result!r}; take() gave {_words(take.result)}"
            return Check(name, False, expected, happened, hint, self.lines["take"])
        return Check(name, True)

    def wakes(self) -> Check:
        name = "wait sleeps until a task comes, and returns as soon as one does"
        expected = (
            "wait(1.0) returns at once with a task queued; with none, it sleeps until "
            f"another thread puts one 0.2 s later, and returns within {SOON_S:g} s of it"
        )
        hint = (
            "wait sleeps on the condition (self.changed.wait) while the queue is empty; "
            "put calls self.changed.notify_all() after appending, to wake it (step 3)"
        )
        queue = self.queue()
        if self.failed():
            return Check(name, False)
        ready = self.call("put(task)", lambda: queue.put(_task(0, 0)))
        ready.join()
        waited = self.call("wait(1.0)", lambda: queue.wait(1.0))
        returned = waited.join(2.5)
        if self.failed():
            return Check(name, False)
        if not returned or waited.took_s > SOON_S:
            if not returned:
                self.release(queue)
            said = "did not return" if not returned else f"returned after {waited.took_s:.2f} s"
            happened = f"with a task queued, wait(1.0) {said}"
            hint = "wait returns at once when a task is queued: it checks before it sleeps (step 3)"
            return Check(name, False, expected, happened, hint, self.lines["wait"])
        self.call("take()", queue.take).join()
        waiting = self.call("wait(1.0)", lambda: queue.wait(1.0))
        time.sleep(0.2)
        if waiting.returned():
            happened = "with nothing queued, wait(1.0) returned at once, before any task came"
            hint = (
                "wait sleeps (self.changed.wait(left)) while the queue is empty, until "
                "its timeout is over (step 3)"
            )
            return Check(name, False, expected, happened, hint, self.lines["wait"])
        put = self.call("put(task)", lambda: queue.put(_task(0, 1)))
        put.join()
        put_at = put.ended or time.monotonic()
        returned = waiting.join(2.5)
        if self.failed():
            return Check(name, False)
        if not returned or waiting.after(put_at) > SOON_S:
            if not returned:
                self.release(queue)
            late = "" if not waiting.returned() else f"{waiting.after(put_at):.2f} s after it"
            happened = f"a task was put while wait(1.0) slept; wait returned {late or 'never'}" + (
                " (at its timeout: nothing woke it)" if waiting.took_s > 0.95 else ""
            )
            return Check(name, False, expected, happened, hint, self.lines["put"])
        return Check(name, True)

    def idle(self) -> Check:
        name = "an idle consumer uses no CPU"
        expected = (
            f"wait({IDLE_S:g}) with nothing queued sleeps about {IDLE_S:g} s, using less "
            f"than {IDLE_CPU_S:g} s of CPU"
        )
        queue = self.queue()
        if self.failed():
            return Check(name, False)
        waited = self.call(f"wait({IDLE_S:g})", lambda: queue.wait(IDLE_S))
        returned = waited.join(IDLE_S + 2.0)
        if self.failed():
            return Check(name, False)
        line = self.lines["wait"]
        if not returned:
            self.release(queue)
            happened = f"wait({IDLE_S:g}) did not return in {IDLE_S + 2:g} s"
            hint = "wait returns when its timeout is over, even if nothing came (step 3)"
        elif waited.took_s < IDLE_S * 0.75:
            happened = (
                f"wait({IDLE_S:g}) returned at once, with nothing queued: a consumer "
                "that calls it in a loop spins, using a whole core"
            )
            hint = (
                "wait sleeps (self.changed.wait(left)) until a task comes or its timeout "
                "is over (step 3)"
            )
        elif waited.cpu_s > IDLE_CPU_S:
            happened = (
                f"wait({IDLE_S:g}) used {waited.cpu_s:.2f} s of CPU in {waited.took_s:.2f} s: "
                "it checks again and again (busy waiting)"
            )
            hint = (
                "sleep on the condition, self.changed.wait(left): the thread uses no CPU "
                "until put wakes it; a loop that only checks keeps a core busy (step 3)"
            )
        else:
            return Check(name, True)
        return Check(name, False, expected, happened, hint, line)

    def waits_for_room(self) -> Check:
        name = "put waits while the queue is full, and goes on when there is room"
        expected = (
            f"with {CAPACITY} tasks queued (full), put waits; once the consumer takes "
            f"them, it returns True within {SOON_S:g} s, and its task is taken next"
        )
        hint = (
            "put waits on the condition while len(self.normal) >= self.capacity; take "
            "calls self.changed.notify_all() after popping, to wake it (step 4)"
        )
        if not self.basics:
            return self.untried(name, expected, hint, self.lines["put"])
        queue = self.queue(max_wait_s=2.0)
        problem = self.fill(queue, CAPACITY)
        if problem is not None or self.failed():
            return Check(name, False, expected, problem or "", hint, self.lines["put"])
        put = self.call("put(task)", lambda: queue.put(_task(1, 0)))
        time.sleep(0.15)
        if put.returned():
            happened = f"put returned {put.result!r} at once, with the queue full"
            hint = (
                "put waits (self.changed.wait(left)) while len(self.normal) >= "
                "self.capacity (step 4)"
            )
            return Check(name, False, expected, happened, hint, self.lines["put"])
        room_at = time.monotonic()
        taken = self.call("take()", lambda: [queue.take() for _ in range(CAPACITY)])
        taken.join()
        returned = put.join(2.5)
        if self.failed():
            return Check(name, False)
        if not returned or put.after(room_at) > SOON_S:
            said = "never" if not put.returned() else f"{put.after(room_at):.2f} s after"
            happened = f"the consumer took the {CAPACITY} tasks; put returned {said}" + (
                f", with {put.result!r}" if put.returned() else ""
            )
            return Check(name, False, expected, happened, hint, self.lines["take"])
        last = self.call("take()", queue.take)
        last.join()
        if put.result is not True or _words(last.result) != "p1 #0":
            happened = f"put returned {put.result!r}; then take() gave {_words(last.result)}"
            return Check(name, False, expected, happened, hint, self.lines["put"])
        return Check(name, True)

    def gives_up(self) -> Check:
        name = "put gives up after max_wait_s"
        expected = (
            f"with {CAPACITY} tasks queued and no consumer, put returns False after "
            f"max_wait_s = 0.3 s, and the task is not queued"
        )
        hint = (
            "put waits at most max_wait_s in all (a deadline, and self.changed.wait(left) "
            "with what is left of it), then returns False (step 4)"
        )
        if not self.basics:
            return self.untried(name, expected, hint, self.lines["put"])
        queue = self.queue(max_wait_s=0.3)
        problem = self.fill(queue, CAPACITY)
        if problem is not None or self.failed():
            return Check(name, False, expected, problem or "", hint, self.lines["put"])
        put = self.call("put(task)", lambda: queue.put(_task(1, 0)))
        returned = put.join(2.0)
        if self.failed():
            return Check(name, False)
        count = self.call("len()", lambda: len(queue))
        count.join()
        if not returned:
            happened = "put did not return in 2 s: it waits past max_wait_s"
        elif put.result is not False or count.result != CAPACITY:
            happened = (
                f"put returned {put.result!r} after {put.took_s:.2f} s; len() is then "
                f"{count.result!r}"
            )
        elif put.took_s < 0.25:
            happened = f"put returned False after {put.took_s:.2f} s, before max_wait_s"
        elif put.took_s > 1.0:
            happened = f"put returned False after {put.took_s:.2f} s, long after max_wait_s"
        else:
            return Check(name, True)
        return Check(name, False, expected, happened, hint, self.lines["put"])

    def close_wakes(self) -> Check:
        name = "close wakes the consumer in wait and a producer in put"
        expected = (
            f"close() ends a wait(5.0) on an empty queue, and a put on a full one "
            f"(max_wait_s = 5), each within {SOON_S:g} s"
        )
        hint = (
            "close sets self.closed and calls self.changed.notify_all(); wait and put "
            "stop waiting once self.closed is set (step 5)"
        )
        if not self.basics:
            return self.untried(name, expected, hint, self.lines["close"])
        empty = self.queue(max_wait_s=5.0)
        full = self.queue(max_wait_s=5.0)
        problem = self.fill(full, CAPACITY)
        if problem is not None or self.failed():
            return Check(name, False, expected, problem or "", hint, self.lines["put"])
        waiting = self.call("wait(5.0)", lambda: empty.wait(5.0))
        putting = self.call("put(task)", lambda: full.put(_task(1, 0)))
        time.sleep(0.15)
        if waiting.returned() or putting.returned():
            happened = "not tried: before close, " + (
                "wait(5.0) returned at once" if waiting.returned() else "put did not wait"
            )
            return Check(name, False, expected, happened, hint, self.lines["wait"])
        closed_at = time.monotonic()
        for queue in (empty, full):
            self.call("close()", queue.close).join()
        waiting.join(max(0.0, closed_at + 2.0 - time.monotonic()))
        putting.join(max(0.0, closed_at + 2.0 - time.monotonic()))
        if self.failed():
            return Check(name, False)
        late = [
            (what, call)
            for what, call in (("wait", waiting), ("put", putting))
            if call.after(closed_at) > SOON_S
        ]
        if late:
            said = [
                f"{what} "
                + (
                    "still waits"
                    if not call.returned()
                    else f"returned {call.after(closed_at):.2f} s after"
                )
                for what, call in late
            ]
            happened = f"after close(): {'; '.join(said)}"
            line = self.lines["close"] if len(late) == 2 else self.lines[late[0][0]]
            return Check(name, False, expected, happened, hint, line)
        return Check(name, True)

    def many_producers(self) -> Check:
        name = "many producers: every task taken once, each producer's in order"
        total = PRODUCERS * EACH
        expected = (
            f"{PRODUCERS} threads put {EACH} tasks each (capacity {STRESS_CAPACITY}) while "
            f"one consumer waits and takes: all {total} taken, none twice, each thread's in "
            "the order it put them"
        )
        hint = (
            "put and take change the lanes while holding self.changed, and wait checks "
            "the lanes under it too (steps 1, 3, 4)"
        )
        if not self.basics:
            return self.untried(name, expected, hint, self.lines["put"])
        queue = self.queue(capacity=STRESS_CAPACITY, max_wait_s=2.0)
        if self.failed():
            return Check(name, False)
        refused: List[int] = []

        def produce(producer: int) -> None:
            for number in range(EACH):
                if queue.put(_task(producer, number)) is not True:
                    refused.append(producer)

        producers = [
            self.call("put(task)", lambda p=p: produce(p))  # type: ignore[misc]
            for p in range(PRODUCERS)
        ]
        taken: List[Any] = []

        def consume() -> None:
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline:
                queue.wait(0.2)
                task = queue.take()
                while task is not None:
                    taken.append(task)
                    task = queue.take()
                if all(one.returned() for one in producers) and len(queue) == 0:
                    return

        consumer = self.call("wait(0.2)", consume)
        ended = consumer.join(3.0) and all(one.join(0.5) for one in producers)
        if self.failed():
            return Check(name, False)
        seen: Dict[str, List[Any]] = {}
        for task in taken:
            if isinstance(task, Task) and task.val_list:
                seen.setdefault(task.name, []).append(task.val_list[0])
        problems = []
        for producer in range(PRODUCERS):
            numbers = seen.get(f"p{producer}", [])
            twice = len(numbers) - len(set(numbers))
            lost = EACH - len(set(numbers)) - refused.count(producer)
            order = next((i for i in range(1, len(numbers)) if numbers[i] <= numbers[i - 1]), None)
            if lost > 0 and ended:
                problems.append(f"{lost} of thread p{producer}'s lost")
            if twice:
                problems.append(f"{twice} of p{producer}'s taken twice")
            if order is not None:
                problems.append(f"p{producer} #{numbers[order]} taken after #{numbers[order - 1]}")
        happened = f"{len(taken)} of {total} taken"
        if refused:
            happened += f"; {len(refused)} puts returned False, though the consumer kept taking"
        if not ended:
            happened += " in 2 s, when the grade stopped waiting: the consumer was too slow"
        if problems:
            happened += f"; {', '.join(problems[:3])}" + (", ..." if len(problems) > 3 else "")
        if problems or refused or not ended or len(taken) != total:
            return Check(name, False, expected, happened, hint, self.lines["put"])
        return Check(name, True)

    def no_lost_wake_up(self) -> Check:
        name = "no wake-up is lost"
        expected = (
            f"{ROUNDS} tasks put one at a time, each at another moment of the consumer's "
            f"wait({NAP_S:g}): the consumer wakes for each, never sleeping to its timeout "
            "with a task queued"
        )
        hint = (
            "check that the queue is empty and go to sleep under one lock: wait holds "
            "self.changed from its check to self.changed.wait, so a put cannot slip in "
            "between (step 3)"
        )
        if not self.basics:
            return self.untried(name, expected, hint, self.lines["wait"])
        queue = self.queue(capacity=CAPACITY, max_wait_s=1.0)
        if self.failed():
            return Check(name, False)
        handover = _Handover(queue)
        producer = self.call("put(task)", handover.produce)
        consumer = self.call(f"wait({NAP_S:g})", handover.consume)
        consumer.join(6.0)
        handover.stop = True
        handover.go.set()
        producer.join(1.0)
        if self.failed():
            return Check(name, False)
        if handover.lost:
            number, late = handover.lost[0]
            happened = (
                f"task {number + 1} was put as the consumer went to sleep, and it slept "
                f"on for {late:.2f} s, to its timeout"
            )
            if len(handover.lost) > 1:
                happened += f"; {len(handover.lost)} lost in {handover.lost[-1][0] + 1} tasks"
            return Check(name, False, expected, happened, hint, self.lines["wait"])
        if not consumer.returned() or handover.taken < ROUNDS:
            happened = f"{handover.taken} of {ROUNDS} tasks taken in 6 s"
            return Check(name, False, expected, happened, hint, self.lines["wait"])
        return Check(name, True)


class _Handover:
    """The lost wake-up check: a producer puts each task at a chosen moment of the consumer's wait.

    Round ``n``, the consumer calls ``wait``; a profile function on its
    thread counts the calls and returns it makes, and at the ``n % SPREAD``-th
    it stops there and has the producer put task ``n`` (waiting for it at
    most 5 ms: a producer that cannot get the queue's lock goes on by itself
    later). Round after round the put lands between each two calls of
    ``wait``, so a wait that checks the queue and then goes to sleep without
    holding one lock throughout loses a wake-up, every time, and the same one.
    A moment that comes only once the wait has slept (to its timeout: nothing
    was put) is not tried again: the rounds keep to the moments before it.
    """

    def __init__(self, queue: Any) -> None:
        self.queue = queue
        self.go = threading.Event()
        self.done = threading.Event()
        self.stop = False
        self.number = 0
        self.put_at: Dict[int, float] = {}
        self.events = 0
        self.fire_at = -1
        self.spread = SPREAD
        self.started = 0.0
        self.taken = 0
        self.lost: List[Tuple[int, float]] = []

    def produce(self) -> None:
        """The producer: puts task ``number`` each time it is told to go."""
        while True:
            self.go.wait()
            self.go.clear()
            if self.stop:
                return
            self.queue.put(_task(0, self.number))
            self.put_at[self.number] = time.monotonic()
            self.done.set()

    def fire(self) -> None:
        """Have the producer put the round's task now; wait for it 5 ms at most."""
        self.fire_at = -1
        self.done.clear()
        self.go.set()
        self.done.wait(0.005)

    def profile(self, frame: Any, event: str, arg: Any) -> None:
        """On the consumer's thread, in its wait: at the chosen call or return, fire."""
        self.events += 1
        if self.events == self.fire_at:
            if time.monotonic() - self.started > NAP_S / 2:  # it slept before this moment
                self.spread = max(1, self.events - 1)
            self.fire()

    def consume(self) -> None:
        """The consumer: ``ROUNDS`` rounds of wait, then take."""
        deadline = time.monotonic() + 5.0
        for number in range(ROUNDS):
            self.number = number
            self.events, self.fire_at = 0, 1 + number % self.spread
            self.started = time.monotonic()
            sys.setprofile(self.profile)
            try:
                self.queue.wait(NAP_S)
            finally:
                sys.setprofile(None)
            woke = time.monotonic()
            if self.fire_at != -1:  # the wait ended before its chosen moment: put now
                self.fire()
            elif woke - self.put_at.get(number, woke) > 0.75 * NAP_S:
                self.lost.append((number, woke - self.put_at[number]))
                if len(self.lost) == 2 or time.monotonic() > deadline:
                    return
            task = self.queue.take()
            while task is None and time.monotonic() < deadline:
                self.queue.wait(NAP_S)  # the put may still be on its way
                task = self.queue.take()
            if task is None:
                return
            self.taken += 1


def _lines(checks: Sequence[Check]) -> List[str]:
    """The checks, one line each: for ``python -m ...grader FILE`` while writing the lesson."""
    return [f"{'passed' if one.passed else 'FAILED'}  {one.name}: {one.happened}" for one in checks]


if __name__ == "__main__":
    for said in _lines(grade(Path(sys.argv[1]))):
        print(said)
