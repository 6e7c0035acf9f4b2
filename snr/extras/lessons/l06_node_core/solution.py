"""Lesson 6: a node core of your own (docs/lessons.md), the reference solution.

Every node's first component is its core endpoint (thesis 4.3.2, 6.3.2): it
stores each page in the datastore and then, when the page asks for it,
sends the page's ``process_data`` task; it stores the bursts of pages that
come from other nodes; it adds, removes and reloads components, and stops
the node on a terminate task. SNR's own is `snr.core.NodeCoreEndpoint`.
`MyNodeCore` is one written from scratch on `snr.core.NodeCore`, the
interface, and ``Config(node_core=MyNodeCoreFactory())`` gives every node
one in place of SNR's.

Run it: lesson 1's wall follower drives its room for a while, in simulated
time as fast as the computer goes, with this core in its node::

    python node_core.py --seconds 30

To write it yourself, ``python -m snr lesson start 6`` writes the starter
file into your folder, and ``python -m snr lesson grade 6`` grades it.
"""

from __future__ import annotations

import argparse
import sys
from typing import List, Optional

from snr import AbstractFactory, AbstractNode, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr import tasks as snr_tasks
from snr.core import NodeCore

__all__ = ["MyNodeCore", "MyNodeCoreFactory", "main"]


class MyNodeCore(NodeCore):
    """Stores pages, manages components and stops its node.

    Example (what it does, as SNR's own does)::

        node.schedule(tasks.store_data("depth", 3.0))   # -> datastore["depth"], then
                                                        #    (process_data, "depth")
        node.schedule(tasks.terminate("done"))          # -> the node stops
    """

    def __init__(self, factory: AbstractFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent)  # named "node_core"; SNR's own two events
        self.task_handlers.update(
            {
                (TaskType.event, snr_tasks.STORE_PAGES): self.store_pages,
                (TaskType.event, snr_tasks.ADD_COMPONENT): self.add,
                (TaskType.event, snr_tasks.REMOVE_COMPONENT): self.remove,
                TaskType.reload: self.reload,
                TaskType.terminate: self.stop,
            }
        )

    def store_page_handler(self, task: Task, key: TaskId) -> SomeTasks:
        """Store the task's page; then its ``process_data`` task, if the page asks for one."""
        page = task.val_list[0]
        self.pages[page.key] = page
        if page.process:
            return Task(TaskType.process_data, page.key, [page])
        return None

    def store_pages(self, task: Task, key: TaskId) -> SomeTasks:
        """A burst of pages (from another node): a ``store_page`` task each, in order."""
        return [snr_tasks.store_page(page) for page in task.val_list]

    def add(self, task: Task, key: TaskId) -> SomeTasks:
        """Build the component of the factory in the task, and add it to the node."""
        component = self.parent.build_component(task.val_list[0])
        if component is not None:
            self.parent.add_component(component)
        return None

    def remove(self, task: Task, key: TaskId) -> SomeTasks:
        """Remove the components the task names."""
        for name in task.val_list:
            self.parent.remove_component(name)
        return None

    def reload(self, task: Task, key: TaskId) -> SomeTasks:
        """Reload the component the task names (all of them: ``"all"``, or no name)."""
        self.parent.reload_component(task.name or "all")
        return None

    def stop(self, task: Task, key: TaskId) -> SomeTasks:
        """Stop the node, with the task's name as the reason."""
        self.parent.set_terminate_flag(task.name)
        return None


class MyNodeCoreFactory(EndpointFactory):
    """Builds a `MyNodeCore`: ``Config(..., node_core=MyNodeCoreFactory())``.

    Example::

        Config({"robot": [...]}, node_core=MyNodeCoreFactory())
    """

    def get(self, parent: AbstractNode) -> MyNodeCore:
        return MyNodeCore(self, parent)


def main(argv: List[str], node_core: Optional[AbstractFactory] = None) -> None:
    """``python node_core.py [--seconds S]``: lesson 1's robot, S simulated seconds.

    ``node_core``: the factory of the node's core (this file's by default).
    """
    from snr.extras.lessons.probe import demo

    parser = argparse.ArgumentParser(prog=argv[0], description="Lesson 6: a node core.")
    parser.add_argument(
        "--seconds", type=float, default=10.0, help="how long the robot drives (simulated)"
    )
    options = parser.parse_args(argv[1:])
    if options.seconds <= 0:
        parser.error(f"--seconds {options.seconds:g}: give more than 0")
    demo(options.seconds, node_core=node_core or MyNodeCoreFactory())


if __name__ == "__main__":
    main(sys.argv)
