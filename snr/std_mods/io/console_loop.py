"""`ConsoleLoop`: the base of every console transport of a node (TCP, stdin, Zenoh).

A console only turns the lines a user types into tasks; the command
processor it adds to the node runs them on the node's thread and sends each
reply to the line's `ConsoleSession`. Each console adds its own processor
when it begins, so several consoles never run one command twice. (How to
write one: `ConsoleLoop`'s example.)
"""

from __future__ import annotations

from typing import Sequence

from snr.core import ThreadLoop, tasks
from snr.core.checks.step_mode import console_priority
from snr.prelude import AbstractFactory, AbstractNode, ComponentName, DataKey, Task, TaskType
from snr.std_mods.io.command_processor import CommandProcessorFactory
from snr.std_mods.io.console_protocol import ConsoleSession

__all__ = ["ConsoleLoop"]


class ConsoleLoop(ThreadLoop):
    """Base of the consoles: adds a processor at ``begin`` and submits lines to it.

    Subclasses read lines in ``loop()`` and call ``self.submit(line, session)``.

    Example::

        class MyConsole(ConsoleLoop):
            def loop(self) -> None:
                self.submit(read_a_line(), self.session)
    """

    # For the graph: a console stores only what its user types (`task store_page ...`).
    produces: Sequence[DataKey] = ()
    reads: Sequence[DataKey] = ()

    def __init__(self, factory: AbstractFactory, parent: AbstractNode, name: ComponentName) -> None:
        super().__init__(factory, parent, name)
        self.processor_name = f"{name}_commands"
        self.command_task_name = f"console_command:{name}"

    def begin(self) -> None:
        """Ask the node to add this console's processor (if it has none yet).

        The add task is queued before any command this loop can submit, so
        the processor exists by the time the first command runs.
        """
        if self.processor_name not in self.parent.components:
            factory = CommandProcessorFactory(
                self.processor_name, self.command_task_name, console=self.name
            )
            self.schedule(tasks.add_component(factory))

    def submit(self, line: str, session: ConsoleSession) -> None:
        """Queue a command line; the processor replies to ``session``.

        While the node is paused (``pause``) the command is urgent, so it
        runs although the node's other tasks wait.
        """
        priority = console_priority(self.parent)
        self.schedule(Task(TaskType.event, self.command_task_name, [line, session], priority))

    def greeting(self, how: str = "") -> str:
        """The text of the ``hello`` a console gets; ``how`` says how it reached the node.

        Example::

            loop.greeting(" over Zenoh")   # "Connected to node 'urov' over Zenoh. Type 'help'..."
        """
        return (
            f"Connected to node {self.parent.role!r}{how}. "
            "Type 'help' for the commands, 'exit' to stop the node."
        )
