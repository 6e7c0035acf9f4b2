"""`Watchdog`: in DEBUG mode, says why a node is stuck when nothing else would.

Some mistakes hang a node without a word. A daemon thread samples the stacks of
the node's thread and its loops' threads every ``every_s`` and says, once each,
as a warning, with the line it is on and the rule it breaks (docs/design.md,
"The watchdog"; docs/errors.md, 17):

1. a handler that has not returned after ``stuck_s``;
2. a student's ``loop()`` inside a ``while`` of its own for ``stuck_s``
   (one long blocking call, e.g. ``accept()``, is not reported);
3. a student's loop that had to wait for room while the node was behind for
   ``stuck_s`` (a queue a tenth full, or a wait since the last look, counts as
   behind for ``FLOOD_GRACE_S``); 3b. a loop with no ``max_tick_rate_hz`` whose
   ``loop()`` stores or schedules, running ``spin_hz`` passes a second for
   ``2 * stuck_s`` (the profiler's counts);
4. a node with an empty queue, no handler running, no loop alive and no other
   thread for ``idle_s``: only Ctrl+C can end it.

A look that finds nothing to watch makes the next one wait ``stuck_s``; if
besides the node's thread sleeps with an empty queue and no student's loop
runs, the watchdog sleeps until the node gets work (an idle node is not stuck),
or ``dozing_s`` at most.

Example::

    node = Node("robot", config)        # DEBUG: node.watchdog is a Watchdog
    node.watchdog.stuck_s = 5.0         # be more patient
    node.watchdog = None                # or switch it off (before node.loop())
"""

from __future__ import annotations

import ast
import linecache
import sys
import threading
import time
from types import CodeType, FrameType
from typing import TYPE_CHECKING, Dict, Iterable, List, Optional, Protocol, Set, Tuple

from snr.core import tasks
from snr.core.checks.student_code import (
    code_name,
    describe_callable,
    describe_class,
    frame_location,
    line_with_code,
    running_line,
    source_node,
    walk_own,
)
from snr.core.dispatch import HandlerRunner
from snr.core.loop import ThreadLoop
from snr.core.task_queue import TaskQueue
from snr.prelude import (
    AbstractComponent,
    AbstractLoop,
    AbstractProfiler,
    ComponentName,
    DataKey,
    Page,
    Role,
    Task,
    TaskType,
)
from snr.prelude.task import format_task

if TYPE_CHECKING:
    import logging

    from snr.core.checks.key_hints import MissingKeyHints
    from snr.core.checks.step_mode import StepMode

__all__ = ["Watchdog", "WatchedNode", "queued_page_keys"]

_HANDLER_CALLERS = frozenset({HandlerRunner.run_queued.__code__, HandlerRunner.run.__code__})
_LOOP_CALLER = frozenset({ThreadLoop._run.__code__})
_PARENT_WATCH = "snr-parent-watch"  # MultiProcRunner's: it stops the node only on Ctrl+C
_STORES = frozenset({"store_data", "store_page", "schedule"})
_Calls = Dict[Optional[ThreadLoop], Tuple[FrameType, float]]
_FOOTER = "(This shows once, in DEBUG mode only; node.watchdog = None turns the watchdog off.)"


class WatchedNode(Protocol):
    """What the watchdog reads of its node: a `Node` (not imported: ``node.py`` imports this).

    Example::

        watched: WatchedNode = Node("robot", config)
    """

    role: Role
    log: logging.Logger
    queue: TaskQueue
    components: Dict[ComponentName, AbstractComponent]
    key_hints: Optional[MissingKeyHints]
    step_mode: StepMode
    profiler: Optional[AbstractProfiler]


class Watchdog:
    """Watches a running node from its own thread and says when it is stuck.

    Args:
        node: the node to watch (it calls `start` and `stop`).

    Example::

        node.watchdog.stuck_s = 0.5   # say it sooner (before node.loop())

    Attributes:
        every_s: seconds between two looks at the node (0.5).
        dozing_s: the longest an idle node goes unlooked at (20 s; it is
            looked at as soon as it gets work).
        stuck_s: how long before a stuck handler, loop or flood is reported (2 s).
        idle_s: how long before a node nothing can stop is reported (3 s).
        spin_hz: passes a second at which a loop with no rate that stores or
            schedules is reported (1,000; rule 3b).
        dozing: True while it sleeps until the node gets work (`wake` then rings).
        handler_stuck: True while the node's thread has been in one handler
            call for at least one look.
        said: one line per report made so far, e.g. ``"handler Waiter.on_go"``.
    """

    every_s: float = 0.5
    stuck_s: float = 2.0
    idle_s: float = 3.0
    spin_hz: float = 1000.0
    dozing_s: float = 20.0
    FLOOD_GRACE_S = 1.0
    """A node that was behind less than this long ago still counts as behind."""

    def __init__(self, node: WatchedNode) -> None:
        self.node = node
        self.handler_stuck = self.dozing = False
        self.said: List[str] = []
        self._said_about: Set[object] = set()
        self._bell = threading.Event()  # set: look now (the node got work, or stop)
        self._stopping = False
        self._theirs_alive = False  # a student's loop was running at the last look
        self._quiet = False  # the last look found nothing to watch: the next comes later
        self._thread: Optional[threading.Thread] = None
        self._node_thread = -1
        self._ignored: Set[Optional[int]] = set()
        # The call each thread was in at the last look (None: the node's), since when:
        # the very same frame object look after look is the same call still running.
        self._calls: _Calls = {}
        self._waits = 0  # the queue's count of producers' waits, at the last look
        self._loop_waits: Dict[ThreadLoop, int] = {}  # the same for each loop's thread
        self._flood_since: Optional[float] = None
        self._behind_s = 0.0  # the last look at which the node was behind
        self._flooders: List[ThreadLoop] = []
        self._idle_since: Optional[float] = None
        self._passes: Dict[ThreadLoop, Tuple[float, float]] = {}  # (passes, when) at a look

    def start(self, node_thread: int, ignore: Iterable[threading.Thread] = ()) -> None:
        """Start watching; ``node_thread`` runs the node, ``ignore`` can give it no task."""
        self._node_thread = node_thread
        self._ignored = {node_thread, *(thread.ident for thread in ignore)}
        self._waits = self.node.queue.waits
        self._thread = threading.Thread(
            target=self._run, name=f"snr-{self.node.role}-watchdog", daemon=True
        )
        self._thread.start()
        self._ignored.add(self._thread.ident)

    def stop(self) -> None:
        """Stop watching (the node is stopping); waits for the thread, briefly."""
        self._stopping = True
        self._bell.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(1.0)
        self._calls.clear()  # let go of the frames (and their locals)
        self._flooders = []

    def wake(self) -> None:
        """The node's thread left its idle wait with work: look now if dozing (node thread).

        Example::

            if watchdog.dozing:
                watchdog.wake()
        """
        self.dozing = False
        self._bell.set()

    def _run(self) -> None:
        while True:
            self._bell.wait(self._wait_s())
            self._bell.clear()
            self.dozing = False
            if self._stopping:
                return
            try:
                self.check()
            except Exception:
                self.node.log.exception("The watchdog failed and stops; the node runs on.")
                return

    def _wait_s(self) -> float:
        """Until the next look: ``every_s``, ``stuck_s`` if nothing was found, ``dozing_s`` idle."""
        if not self._quiet:
            return self.every_s
        if self._theirs_alive:
            return self.stuck_s  # a student's loop may be stuck in a while of its own
        # Say we doze first, then see whether the node's thread sleeps with nothing
        # queued: a thread leaving its wait after that sees `dozing` and rings.
        self.dozing = True
        queue = self.node.queue
        if not queue.sleeping or len(queue):
            self.dozing = False
            return self.stuck_s
        return self.dozing_s

    def check(self) -> None:
        """Look at the node once: sample its threads' stacks and apply the four rules."""
        now = time.monotonic()
        frames = sys._current_frames()
        loops = [c for c in list(self.node.components.values()) if isinstance(c, ThreadLoop)]
        # SNR's own loops are written to the rules; only a student's are judged.
        theirs = [loop for loop in loops if not type(loop).__module__.startswith("snr.")]
        self._theirs_alive = any(loop.is_alive() for loop in theirs)
        calls: _Calls = {}
        handler = _called_by(frames.get(self._node_thread), _HANDLER_CALLERS)
        held_s = self._held_s(calls, None, handler, now)
        self.handler_stuck = held_s is not None  # the same call as at the last look
        if handler is not None and held_s is not None and held_s >= self.stuck_s:
            self._say_stuck(handler)
        for loop in theirs:
            frame = _called_by(frames.get(loop.thread_id or -1), _LOOP_CALLER)
            if frame is None or frame.f_code is not getattr(type(loop).loop, "__code__", None):
                continue  # between two passes, in setup(), or waiting for its tick
            held_s = self._held_s(calls, loop, frame, now)
            if held_s is not None and held_s >= self.stuck_s:
                self._say_endless(loop, frame)
        self._calls = calls
        self._check_flood(theirs, now)
        self._check_spin(theirs, now)
        self._check_idle(handler is None, loops, now)
        self._quiet = (
            not calls and self._idle_since is None and now - self._behind_s > self.FLOOD_GRACE_S
        )

    def _held_s(
        self, calls: _Calls, key: Optional[ThreadLoop], frame: Optional[FrameType], now: float
    ) -> Optional[float]:
        """Seconds ``frame`` has been ``key``'s call; None if it is new since the last look."""
        if frame is None:
            return None
        seen = self._calls.get(key)
        if seen is not None and seen[0] is frame:
            calls[key] = seen
            return now - seen[1]
        calls[key] = (frame, now)
        return None

    def _say(self, about: object, label: str, text: str) -> None:
        if about not in self._said_about:
            self._said_about.add(about)
            self.said.append(label)
            self.node.log.warning("%s %s", text, _FOOTER)

    # 1. a handler that does not return
    def _say_stuck(self, frame: FrameType) -> None:
        names = frame.f_back.f_locals if frame.f_back is not None else {}
        handler, task, component = (names.get(name) for name in ("handler", "task", "component"))
        who = describe_callable(handler) if handler is not None else frame_location(frame)
        if isinstance(component, AbstractComponent):
            kind = "loop" if isinstance(component, AbstractLoop) else "endpoint"
            who += f" of {kind} {component.name!r}"
        doing = f" handling {format_task(task, values='none')}" if isinstance(task, Task) else ""
        text = (
            f"Task handler {who} has been running for {self.stuck_s:g} s{doing}, and has "
            f"not returned: it is at {running_line(self._node_thread) or frame_location(frame)}."
            " A handler must return quickly: while one runs, the node runs no other task "
            "and stores no page."
        )
        hints = self.node.key_hints
        key = hints.last_missed.get(self._node_thread) if hints is not None else None
        if key is not None and key in queued_page_keys(self.node.queue):
            text += (
                f" It waits for data key {key!r}, and the page for {key!r} is in the "
                "queue behind this handler: it can only be stored once the handler returns. "
                "Return instead, and react when the page is stored: a handler for "
                f"(TaskType.store_page, {key!r}) runs then. Move waiting or blocking work "
                "into a ThreadLoop."
            )
        else:
            text += (
                " Move waiting or blocking work (a loop waiting for data, time.sleep, "
                "a read from a device) into a ThreadLoop, and react to data when it comes: a "
                "handler for (TaskType.store_page, key) runs each time a page is stored."
            )
        name = code_name(frame.f_code, frame.f_code.co_name)
        self._say(frame.f_code, f"handler {name}", text)

    # 2. a loop() that never returns (one long blocking call, e.g. accept(), is not reported)
    def _say_endless(self, loop: ThreadLoop, frame: FrameType) -> None:
        tree, line = source_node(frame.f_code), frame.f_lineno
        whiles = [
            n.lineno
            for n in (walk_own(tree) if tree is not None else ())
            if isinstance(n, ast.While) and n.lineno <= line <= (n.end_lineno or n.lineno)
        ]
        if not whiles:
            return
        code = linecache.getline(frame.f_code.co_filename, min(whiles)).strip()
        text = (
            f"Loop {loop.name!r} ({describe_class(type(loop))}): loop() has not returned "
            f"for {self.stuck_s:g} s. It is inside `{code}` "
            f"({frame_location(frame, min(whiles))}), now at "
            f"{running_line(loop.thread_id) or frame_location(frame)}. loop() should do one "
            "pass and return: SNR calls it again and again, at most max_tick_rate_hz times "
            "a second, and can stop the loop only between two passes, so this loop cannot "
            "be stopped. Take out the `while` and keep its body in loop(); instead of "
            "sleeping, pass max_tick_rate_hz to super().__init__(), e.g. "
            "max_tick_rate_hz=10 for ten passes a second."
        )
        self._say((loop, "loop"), f"loop {loop.name}", text)

    # 3. a loop that had to wait for room while the node was behind
    def _check_flood(self, loops: List[ThreadLoop], now: float) -> None:
        queue = self.node.queue
        counts = {loop: queue.waits_by_thread.get(loop.thread_id or -1, 0) for loop in loops}
        # The loops that had to wait for room since the last look (fewer: counts were reset).
        waited = [loop for loop in loops if counts[loop] > self._loop_waits.get(loop, counts[loop])]
        behind = len(queue.normal) >= queue.high_water // 10 or queue.waits != self._waits
        self._loop_waits, self._waits = counts, queue.waits
        if (
            self.handler_stuck
            or self.node.step_mode.paused
            or (not behind and now - self._behind_s > self.FLOOD_GRACE_S)
        ):
            # Keeping up, or held by a handler (rule 1) or a console: loops wait for it.
            self._flood_since = None
            self._flooders = []
            return
        if behind:
            self._behind_s = now
        if self._flood_since is None:
            self._flood_since = now
        self._flooders += [loop for loop in waited if loop not in self._flooders]
        if now - self._flood_since < self.stuck_s:
            return
        for loop in self._flooders:
            place = queue.waited_at.get(loop.thread_id or -1)
            where = running_line(loop.thread_id) if place is None else line_with_code(*place)
            rate = loop.max_tick_rate_hz
            if rate > 0:
                fix = (
                    f"It runs loop() up to {rate:,.10g} times a second, more than the node can "
                    "handle: lower max_tick_rate_hz, or make the handlers of what it stores "
                    "faster (node.profiler.dump() shows the slow ones)."
                )
            else:
                fix = "It has no max_tick_rate_hz, so loop() runs again the moment it returns. "
                fix += _give_rate(loop)
            text = (
                f"Loop {loop.name!r} ({describe_class(type(loop))}) stores data faster than the "
                f"node can handle it: for {self.stuck_s:g} s the node's queue kept filling up "
                f"to its limit ({queue.high_water:,} tasks) and the loop had to wait "
                f"for room{f' (at {where})' if where else ''}. {fix}"
            )
            self._say((loop, "flood"), f"flood {loop.name}", text)

    # 3b. a loop with no rate whose loop() stores or schedules, spin_hz passes a second
    def _check_spin(self, loops: List[ThreadLoop], now: float) -> None:
        profiler = self.node.profiler
        if profiler is None:
            return
        if self.handler_stuck or self.node.step_mode.paused:
            self._passes.clear()  # the node's thread is held: rule 1 (or a console) speaks
            return
        for loop in loops:
            code = getattr(type(loop).loop, "__code__", None)
            # Rule 3 speaks for a loop that waited for room; it has stuck_s to do so.
            if loop.max_tick_rate_hz > 0 or loop in self._flooders or code is None:
                continue
            if _STORES.isdisjoint(code.co_names):
                continue
            passes = profiler.loop_cell(loop.name)[0]
            first, since = self._passes.setdefault(loop, (passes, now))
            if now - since < 2 * self.stuck_s:
                continue
            rate = (passes - first) / (now - since)
            if rate >= self.spin_hz:
                text = (
                    f"Loop {loop.name!r} ({describe_class(type(loop))}) has no max_tick_rate_hz, "
                    f"so loop() runs again the moment it returns: for {2 * self.stuck_s:g} s "
                    f"{describe_callable(type(loop).loop)} ran about "
                    f"{float(f'{rate:.2g}'):,.0f} times a second, storing or scheduling each "
                    "time. That is far faster than any sensor needs, keeps a core busy, and "
                    f"makes every other task wait behind its own. {_give_rate(loop)}"
                )
                self._say((loop, "flood"), f"spin {loop.name}", text)
            self._passes[loop] = (passes, now)

    # 4. a node nothing will ever stop
    def _check_idle(self, no_handler: bool, loops: List[ThreadLoop], now: float) -> None:
        idle = (
            no_handler
            and len(self.node.queue) == 0
            and not any(loop.is_alive() for loop in loops)
            and not any(  # a thread that could still give the node a task
                thread.ident not in self._ignored and thread.name != _PARENT_WATCH
                for thread in threading.enumerate()
            )
        )
        if not idle:
            self._idle_since = None
            return
        if self._idle_since is None:
            self._idle_since = now
        if now - self._idle_since < self.idle_s:
            return
        finished = ", ".join(repr(loop.name) for loop in loops)
        self._say(
            "idle",
            "idle",
            f"Node {self.node.role!r} has had nothing to do for {self.idle_s:g} s, and "
            "nothing can give it anything to do: its queue is empty, "
            f"{f'its loops ({finished}) have finished' if loops else 'it has no loops'}, and "
            "no other thread (a comms link, a console, a timer) is running that could "
            "schedule a task. So nothing will ever schedule tasks.terminate, and the node "
            "waits until you press Ctrl+C. To make it stop by itself, add "
            "TimeoutLoopFactory(seconds=...) to its components, or have a handler return "
            'tasks.terminate("done") once the work is done.',
        )


def queued_page_keys(queue: TaskQueue) -> Set[DataKey]:
    """The data keys of the pages waiting in ``queue`` to be stored (any thread).

    Example::

        "depth" in queued_page_keys(node.queue)   # a page for 'depth' is on its way
    """
    # deque.copy() runs in C holding the GIL: a snapshot even while loops append.
    keys: Set[DataKey] = set()
    for task in queue.normal.copy():
        if task.type is TaskType.store_page:
            keys.add(task.name)
        elif task.type is TaskType.event and task.name == tasks.STORE_PAGES:
            keys.update(page.key for page in task.val_list if isinstance(page, Page))
    return keys


def _called_by(frame: Optional[FrameType], callers: frozenset[CodeType]) -> Optional[FrameType]:
    """The frame on ``frame``'s stack that a function in ``callers`` called, innermost first."""
    for _ in range(200):  # frames looked at per stack
        if frame is None or frame.f_back is None:
            return None
        if frame.f_back.f_code in callers:
            return frame
        frame = frame.f_back
    return None


def _give_rate(loop: ThreadLoop) -> str:
    return (
        f"Give it a rate: super().__init__(factory, parent, {loop.name!r}, max_tick_rate_hz=50) "
        "runs loop() at most 50 times a second."
    )
