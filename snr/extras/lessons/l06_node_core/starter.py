"""Lesson 6: a node core of your own: your file (docs/lessons.md, "Lesson 6: a node core").

Every node's first component is its core endpoint: it stores each page in
the datastore, then sends the page's ``process_data`` task when the page asks
for one; it stores the bursts of pages other nodes send; it adds, removes and
reloads components, and stops the node on a terminate task. Write
`MyNodeCore`'s handlers. As it is, it does none of that: pages are never
stored, and the node never stops by itself.

Run it (lesson 1's robot drives with your core in its node), and grade it::

    python node_core.py --seconds 30
    python -m snr lesson grade 6
"""

from __future__ import annotations

import sys

from snr import AbstractFactory, AbstractNode, EndpointFactory, SomeTasks, Task, TaskId, TaskType
from snr import tasks as snr_tasks
from snr.core import NodeCore
from snr.extras.lessons.l06_node_core.solution import main

__all__ = ["MyNodeCore", "MyNodeCoreFactory"]


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
        # TODO (step 1): the page is task.val_list[0]: put it in the datastore,
        #                self.pages, under page.key.
        # TODO (step 2): if page.process, return Task(TaskType.process_data, page.key, [page]).
        return None

    def store_pages(self, task: Task, key: TaskId) -> SomeTasks:
        """A burst of pages (from another node): a ``store_page`` task each, in order."""
        # TODO (step 3): return a list: snr_tasks.store_page(page) for each page
        #                of task.val_list, in order.
        return None

    def add(self, task: Task, key: TaskId) -> SomeTasks:
        """Build the component of the factory in the task, and add it to the node."""
        # TODO (step 4): component = self.parent.build_component(task.val_list[0]);
        #                if it is not None, self.parent.add_component(component).
        return None

    def remove(self, task: Task, key: TaskId) -> SomeTasks:
        """Remove the components the task names."""
        # TODO (step 4): self.parent.remove_component(name) for each name in task.val_list.
        return None

    def reload(self, task: Task, key: TaskId) -> SomeTasks:
        """Reload the component the task names (all of them: ``"all"``, or no name)."""
        # TODO (step 4): self.parent.reload_component(task.name or "all").
        return None

    def stop(self, task: Task, key: TaskId) -> SomeTasks:
        """Stop the node, with the task's name as the reason."""
        # TODO (step 5): self.parent.set_terminate_flag(task.name).
        return None


class MyNodeCoreFactory(EndpointFactory):
    """Builds a `MyNodeCore`: ``Config(..., node_core=MyNodeCoreFactory())``.

    Example::

        Config({"robot": [...]}, node_core=MyNodeCoreFactory())
    """

    def get(self, parent: AbstractNode) -> MyNodeCore:
        return MyNodeCore(self, parent)


if __name__ == "__main__":
    main(sys.argv, MyNodeCoreFactory())
