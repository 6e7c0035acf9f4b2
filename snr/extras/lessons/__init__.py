"""The course's lessons: a starter file, a reference solution and a grader each.

``python -m snr lesson`` (`snr.extras.lessons.command`) lists them, writes a
lesson's starter file into your folder and grades your file by what the robot
does in the simulator. The lessons' text is docs/lessons.md.

* ``l01_wall_follower``: lesson 1, a proportional wall follower;
* ``l02_go_to_goal``: lesson 2, go to a goal round a crate;
* ``l03_scan_follower``: lesson 3, lesson 1's wall follower seeing by lidar;
* ``l04_depth_filter``: lesson 4, a filter for a noisy depth sensor;
* ``l05_datastore``: lesson 5, a datastore of your own (a hash table);
* ``l06_node_core``: lesson 6, a node core endpoint of your own;
* ``l07_task_queue``: lesson 7, a task queue safe for many producers.

Lessons 5 to 7 have students write a part of SNR itself: 5 and 6 plug in
where SNR's own goes (``Config(datastore=..., node_core=...)``,
docs/assignments.md), and ``probe`` runs them in real nodes for their
graders; lesson 7's grader runs the queue with threads of its own.

Example::

    from snr.extras.lessons import lesson

    lesson(1).title        # 'a wall follower: keep a wall 0.35 m on the right'
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Tuple

__all__ = ["LESSONS", "Lesson", "lesson"]


@dataclass(frozen=True)
class Lesson:
    """One lesson: its number, title, package and the file ``lesson start`` writes.

    Example::

        Lesson(1, "a wall follower", "l01_wall_follower", "wall_follower.py", "lesson-1")
    """

    number: int
    title: str
    package: str
    """The lesson's folder in this package, e.g. ``"l01_wall_follower"``."""
    file_name: str
    """The student's file: what ``start`` writes and ``grade`` grades by default."""
    anchor: str
    """The lesson's section of docs/lessons.md."""

    @property
    def folder(self) -> Path:
        """The lesson's folder: ``starter.py``, ``solution.py``, ``grader.py``."""
        return Path(__file__).parent / self.package

    def module(self, name: str) -> ModuleType:
        """The lesson's ``starter``, ``solution`` or ``grader`` module."""
        return importlib.import_module(f"{__name__}.{self.package}.{name}")


LESSONS: Tuple[Lesson, ...] = (
    Lesson(
        1,
        "a wall follower: keep a wall 0.35 m on the right, all round a room",
        "l01_wall_follower",
        "wall_follower.py",
        "lesson-1-a-wall-follower",
    ),
    Lesson(
        2,
        "go to a goal: drive by odometry to a goal behind a crate",
        "l02_go_to_goal",
        "go_to_goal.py",
        "lesson-2-go-to-a-goal",
    ),
    Lesson(
        3,
        "a perception-based controller: lesson 1's wall follower, seeing by lidar",
        "l03_scan_follower",
        "scan_follower.py",
        "lesson-3-a-perception-based-controller",
    ),
    Lesson(
        4,
        "a filter: smooth a noisy depth sensor, without lagging behind",
        "l04_depth_filter",
        "depth_filter.py",
        "lesson-4-a-filter",
    ),
    Lesson(
        5,
        "a datastore: keep each key's newest page, in a hash table of your own",
        "l05_datastore",
        "datastore.py",
        "lesson-5-a-datastore",
    ),
    Lesson(
        6,
        "a node core: store pages, run process_data, manage components, stop the node",
        "l06_node_core",
        "node_core.py",
        "lesson-6-a-node-core",
    ),
    Lesson(
        7,
        "a task queue: many producers, one consumer, nothing lost, no CPU spent waiting",
        "l07_task_queue",
        "task_queue.py",
        "lesson-7-a-task-queue",
    ),
)
"""Every lesson, in order."""


def lesson(number: int) -> Lesson:
    """The lesson numbered ``number``.

    Raises:
        KeyError: no such lesson; the message lists the ones there are.

    Example::

        lesson(2).file_name    # 'go_to_goal.py'
    """
    for found in LESSONS:
        if found.number == number:
            return found
    numbers = ", ".join(str(one.number) for one in LESSONS)
    raise KeyError(f"there is no lesson {number}; the lessons are {numbers}")
