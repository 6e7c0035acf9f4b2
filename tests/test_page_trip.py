"""A page's trip from store_data to another node's handler crosses the files design.md names.

The walk in docs/design.md ("A page's trip from one node to a handler on
another") is a promise to a student: open these files, in this order, and you
have read the whole path. This test follows a real page over TCP with a
profiling hook and lists the kernel files whose functions ran on the way, so
the path cannot grow a file without the walk (and this list) saying so.
"""

from __future__ import annotations

import os
import sys
import threading
import unittest
from types import FrameType
from typing import Any, Dict, List, Optional, Set

import snr
from snr import (
    AbstractFactory,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    Node,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)
from snr.std_mods.comms.comms_loop import LinkState
from tests.helpers import free_port
from tests.quiet import captured_logs

SNR_ROOT = os.path.dirname(snr.__file__)

# The six files of the walk, and the Task's own accessor for its page (the cargo's
# class, not the machinery that carries it).
THE_WALK = {
    "core/node.py",
    "core/task_queue.py",
    "core/dispatch.py",
    "std_mods/comms/comms_loop.py",
    "std_mods/codec.py",
    "std_mods/comms/io_loop.py",
}
THE_CARGO = {"prelude/task.py"}


class Arrived(Endpoint):
    """The topside's handler: ends the trace when the page is there."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode, done: threading.Event):
        super().__init__(factory, parent, "arrived")
        self.done = done
        self.task_handlers = {(TaskType.store_page, "depth"): self.arrived}

    def arrived(self, task: Task, key: TaskId) -> SomeTasks:
        self.done.set()
        return None


class ArrivedFactory(EndpointFactory):
    def __init__(self, done: threading.Event) -> None:
        super().__init__()
        self.done = done

    def get(self, parent: AbstractNode) -> Arrived:
        return Arrived(self, parent, self.done)


def files_on_the_trip(mode: Mode, trips: int = 3) -> Set[str]:
    """The kernel files whose functions ran between store_data and the other node's handler.

    The page makes ``trips`` trips, each traced on its own, and a file counts if
    every trip crossed it: a timer of either node (a beat, a DEBUG check) that
    fires during one trip is not the page's path.
    """
    arrived = threading.Event()
    pair = SocketsPair(("127.0.0.1", free_port()), system=None, secret=None)
    roles: Dict[str, List[AbstractFactory]] = {
        "topside": [pair.server(), ArrivedFactory(arrived)],
        "rov": [pair.client("depth")],
    }
    topside, rov = Node("topside", Config(roles, mode=mode)), Node("rov", Config(roles, mode=mode))
    files: Set[str] = set()
    tracing = threading.Event()

    def profile(frame: FrameType, event: str, arg: Any) -> Optional[Any]:
        if event == "call" and tracing.is_set() and not arrived.is_set():
            name = frame.f_code.co_filename
            if name.startswith(SNR_ROOT) and os.sep + "extras" + os.sep not in name:
                files.add(os.path.relpath(name, SNR_ROOT).replace(os.sep, "/"))
        return None

    crossed: List[Set[str]] = []
    threads = [threading.Thread(target=node.loop, daemon=True) for node in (topside, rov)]
    with captured_logs("snr"):
        threading.setprofile(profile)
        sys.setprofile(profile)
        try:
            for thread in threads:
                thread.start()
            for _ in range(300):  # until both ends have said hello (at most 3 s)
                if _open(rov) and _open(topside):
                    break
                arrived.wait(0.01)
            for trip in range(trips):
                arrived.clear()
                files.clear()
                tracing.set()
                rov.store_data("depth", 3.2 + trip)
                got_there = arrived.wait(5.0)
                tracing.clear()
                assert got_there, f"page {trip + 1} never arrived"
                crossed.append(set(files))
        finally:
            sys.setprofile(None)
            threading.setprofile(None)
            for node in (topside, rov):
                node.set_terminate_flag("done")
            for thread in threads:
                thread.join(5.0)
    return set.intersection(*crossed)


def _open(node: Node) -> bool:
    """True once the node's comms component has an open link (its hello done)."""
    for component in node.components.values():
        for link in getattr(component, "links", ()):
            if link.state is LinkState.OPEN:
                return True
    return False


class TestAPagesTrip(unittest.TestCase):
    def test_deployed_crosses_the_six_files_of_the_walk(self) -> None:
        self.assertEqual(files_on_the_trip(Mode.DEPLOYED), THE_WALK | THE_CARGO)

    def test_debug_adds_only_checks_that_explain_or_protect(self) -> None:
        files = files_on_the_trip(Mode.DEBUG)
        self.assertEqual(
            {f for f in files if not f.startswith("core/checks/")}, THE_WALK | THE_CARGO
        )


if __name__ == "__main__":
    unittest.main()
