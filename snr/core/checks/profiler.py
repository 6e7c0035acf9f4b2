"""`Profiler`: how often each handler and loop ran and how long it took.

On in DEBUG and TEST mode (and with ``Config(profile=True)``). Each handler
and loop gets one *cell*, ``[times_called, total_s]``, when it is registered;
its one writer adds to it after each run, without a lock (docs/performance.md).

Example::

    print(node.profiler.dump())
"""

from __future__ import annotations

import threading
import time
from typing import Callable, Dict, List, Tuple

from snr.prelude import AbstractProfiler, ComponentName, StatsCell, TaskId
from snr.prelude.task import format_task

__all__ = ["Profiler"]

Row = Tuple[str, int, float]  # (label, times_called, total_s)


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
        # Only creating a cell takes the lock (loops ask from their own threads).
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
        return self.cell(f"{format_task(task_id)}:{where}")

    def loop_cell(self, name: ComponentName) -> StatsCell:
        """The cell of the loop called ``name``."""
        return self.cell(f"Loop({name})")

    def add_report(self, name: str, report: Callable[[], str]) -> None:
        """Add a section to `dump`: ``report()``'s text under ``name`` (a newer one replaces it).

        Example::

            profiler.add_report("sockets_client_9000", lambda: "1 link: sent 120, dropped 0")
        """
        with self._lock:
            self._reports[name] = report

    def rows(self) -> List[Row]:
        """``(label, times_called, total_s)`` rows, busiest first; unused cells left out."""
        with self._lock:
            cells = list(self._cells.items())
        rows = [(label, int(cell[0]), float(cell[1])) for label, cell in cells if cell[0]]
        return sorted(rows, key=lambda row: row[2], reverse=True)

    def dump(self) -> str:
        """The profile as text: one section per thread, each adding up to 100% of the time since
        the node was made (thesis listing 5.2's table, per thread), then the added reports.

        Example::

            print(node.profiler.dump())
            # Times called,          Avg runtime, Task/Loop type,
            # (share: of the 0.501 s since the node was made; each thread's lines add up ...)
            # node thread:
            #            1 x      8.383 us ->   0.002%: (store_page):snr.core.node
            #                              ->  99.998%: (outside handlers: the node's own ...)
            # loop thread timeout_loop:
            #            1 x 499281.445 us ->  99.739%: Loop(timeout_loop)
            #                              ->   0.261%: (outside loop(): waiting between passes)
        """
        elapsed = max(time.perf_counter() - self._start_s, 1e-9)
        rows = self.rows()
        lines = [
            "Times called,          Avg runtime, Task/Loop type,",
            f"(share: of the {elapsed:.3f} s since the node was made; "
            "each thread's lines add up to 100%)",
            "node thread:",
            *_section(
                [row for row in rows if not row[0].startswith("Loop(")],
                elapsed,
                "(outside handlers: the node's own work, waiting for tasks)",
            ),
        ]
        for row in rows:
            if row[0].startswith("Loop("):
                lines.append(f"loop thread {row[0][5:-1]}:")
                lines += _section([row], elapsed, "(outside loop(): waiting between passes)")
        with self._lock:
            reports = list(self._reports.items())
        for name, report in reports:
            try:
                text = report()
            except Exception as error:  # a report must never break the profile
                text = f"(could not be made: {type(error).__name__}: {error})"
            lines.append(f"\n{name}:\n{text}")
        return "\n".join(lines)


def _section(rows: List[Row], elapsed_s: float, rest_label: str) -> List[str]:
    """One thread's rows, then the time outside them: shares adding up to 100% (unless nested)."""
    lines = [
        f"{count:>12} x {total / count * 1e6:>10.3f} us -> {total / elapsed_s * 100:7.3f}%: {label}"
        for label, count, total in rows
    ]
    busy_s = sum(row[2] for row in rows)
    rest_share = max(0.0, elapsed_s - busy_s) / elapsed_s * 100
    lines.append(f"{'':>28} -> {rest_share:7.3f}%: {rest_label}")  # under the " -> " above
    if busy_s > elapsed_s:
        lines.append("(these add up to more than 100%: some ran inside others, so times nest)")
    return lines
