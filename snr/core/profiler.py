"""`Profiler`: how often each handler and loop ran and how long it took.

The node times every handler in DEBUG and TEST mode (and with
``Config(profile=True)``); ``dump()`` prints the table of thesis
listing 5.2::

    Times called,          Avg runtime, Task/Loop type,
    149878 x     2.317 us -> 17.281%: TaskType.event(stress):__main__

Timing must be cheap enough to leave on while students develop, so the
profiler hands out one *cell* per handler (and per loop) when the handler is
registered: a two-item list ``[times_called, total_seconds]``. The node adds
to the cell after each run — two additions, no lock, no string — and the
profiler reads the cells when asked for a table. Each cell has one writer
(the node's thread for handlers, the loop's own thread for a loop), so no
lock is needed; a reader may see a count one run behind, which a profile
can live with.
"""

from __future__ import annotations

import threading
import time
from typing import Callable, Dict, List, Tuple

from snr.prelude import AbstractProfiler, ComponentName, StatsCell, TaskId, TaskType

__all__ = ["Profiler", "format_task_id"]


def format_task_id(task_id: TaskId) -> str:
    """``TaskType.event(stress)`` for a tuple id, ``TaskType.terminate`` for a type.

    Example::

        format_task_id((TaskType.event, "beep"))   # 'TaskType.event(beep)'
    """
    if isinstance(task_id, TaskType):
        return f"TaskType.{task_id.name}"
    return f"TaskType.{task_id[0].name}({task_id[1]})"


class Profiler(AbstractProfiler):
    """Counts and times handler runs (per task id and module) and loop passes.

    Example::

        node = Node("robot", Config({...}, mode=Mode.DEBUG))
        node.loop()
        print(node.profiler.dump())
    """

    def __init__(self) -> None:
        self._start_s = time.perf_counter()
        self._cells: Dict[str, StatsCell] = {}
        self._reports: Dict[str, Callable[[], str]] = {}
        # Only creating a cell takes the lock: loops ask for theirs from
        # their own threads. Adding to a cell needs none (one writer each).
        self._lock = threading.Lock()

    def cell(self, label: str) -> StatsCell:
        """The ``[times_called, total_s]`` cell for ``label``, made on first use.

        Example::

            cell = profiler.cell("Loop(clock)")
            cell[0] += 1; cell[1] += 0.002     # one pass that took 2 ms
        """
        cell = self._cells.get(label)
        if cell is None:
            with self._lock:
                cell = self._cells.setdefault(label, [0, 0.0])
        return cell

    def task_cell(self, task_id: TaskId, where: str) -> StatsCell:
        """The cell of the handlers for ``task_id`` in module ``where``."""
        return self.cell(f"{format_task_id(task_id)}:{where}")

    def loop_cell(self, name: ComponentName) -> StatsCell:
        """The cell of the loop called ``name``."""
        return self.cell(f"Loop({name})")

    def log_task(self, task_id: TaskId, where: str, runtime_s: float) -> None:
        """Record one handler run (the node's thread)."""
        cell = self.task_cell(task_id, where)
        cell[0] += 1
        cell[1] += runtime_s

    def log_loop(self, name: ComponentName, runtime_s: float) -> None:
        """Record one pass of a loop (the loop's own thread)."""
        cell = self.loop_cell(name)
        cell[0] += 1
        cell[1] += runtime_s

    def add_report(self, name: str, report: Callable[[], str]) -> None:
        """Add a section to `dump`: ``report()``'s text under ``name`` (a newer one replaces it).

        Comms components add their links' counters this way, so the profile
        also says what was sent, received and dropped.

        Example::

            profiler.add_report("sockets_client_9000", lambda: "1 link: sent 120, dropped 0")
        """
        with self._lock:
            self._reports[name] = report

    def rows(self) -> List[Tuple[str, int, float]]:
        """``(label, times_called, total_s)`` rows, busiest first; unused cells left out."""
        with self._lock:
            cells = list(self._cells.items())
        rows = [(label, int(cell[0]), float(cell[1])) for label, cell in cells if cell[0]]
        return sorted(rows, key=lambda row: row[2], reverse=True)

    def dump(self) -> str:
        """The profile as a table, busiest first; share is of wall time so far."""
        elapsed = max(time.perf_counter() - self._start_s, 1e-9)
        lines = ["Times called,          Avg runtime, Task/Loop type,"]
        for label, count, total in self.rows():
            avg_us = total / count * 1e6
            share = total / elapsed * 100
            lines.append(f"{count:>12} x {avg_us:>10.3f} us -> {share:7.3f}%: {label}")
        with self._lock:
            reports = list(self._reports.items())
        for name, report in reports:
            try:
                text = report()
            except Exception as error:  # a report must never break the profile
                text = f"(could not be made: {type(error).__name__}: {error})"
            lines.append(f"\n{name}:\n{text}")
        return "\n".join(lines)
