"""`Profiler`: how often each handler and loop ran and how long it took.

The node times every handler when a profiler is present (DEBUG mode, or
``Config(profile=True)``) and ``dump()`` prints the table of thesis
listing 5.2::

    Times called,          Avg runtime, Task/Loop type,
    149878 x     2.317 us -> 17.281%: TaskType.event(stress):__main__
"""

from __future__ import annotations

import threading
import time
from typing import Dict, List, Tuple

from snr.prelude import AbstractProfiler, ComponentName, TaskId, TaskType

__all__ = ["Profiler", "format_task_id"]


def format_task_id(task_id: TaskId) -> str:
    """``TaskType.event(stress)`` for a tuple id, ``TaskType.terminate`` for a type."""
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
        self._stats: Dict[str, List[float]] = {}
        self._lock = threading.Lock()  # loops record from their own threads

    def log_task(self, task_id: TaskId, where: str, runtime_s: float) -> None:
        """Record one handler run (called by the node's thread)."""
        self._add(f"{format_task_id(task_id)}:{where}", runtime_s)

    def log_loop(self, name: ComponentName, runtime_s: float) -> None:
        """Record one pass of a loop (called from the loop's thread)."""
        self._add(f"Loop({name})", runtime_s)

    def _add(self, label: str, runtime_s: float) -> None:
        with self._lock:
            entry = self._stats.get(label)
            if entry is None:
                self._stats[label] = [1, runtime_s]
            else:
                entry[0] += 1
                entry[1] += runtime_s

    def rows(self) -> List[Tuple[str, int, float]]:
        """``(label, times_called, total_s)`` rows, busiest first."""
        with self._lock:
            rows = [(label, int(n), total) for label, (n, total) in self._stats.items()]
        return sorted(rows, key=lambda row: row[2], reverse=True)

    def dump(self) -> str:
        """The profile as a table, busiest first; share is of wall time so far."""
        elapsed = max(time.perf_counter() - self._start_s, 1e-9)
        lines = ["Times called,          Avg runtime, Task/Loop type,"]
        for label, count, total in self.rows():
            avg_us = total / count * 1e6
            share = total / elapsed * 100
            lines.append(f"{count:>12} x {avg_us:>10.3f} us -> {share:7.3f}%: {label}")
        return "\n".join(lines)
