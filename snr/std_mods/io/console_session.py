"""`ConsoleSession`: where the reply to one console's command goes.

A console loop (`CommandReceiverLoop`, `LocalConsole`) hands each command
line to the node together with its session; the `CommandProcessorEndpoint`
runs the command on the node's thread and calls ``session.send(reply)``.

Example::

    class PrintSession(ConsoleSession):
        def send(self, reply: Reply) -> None:
            print(reply.text)
"""

from __future__ import annotations

from abc import ABC, abstractmethod

from snr.std_mods.io.console_protocol import Reply

__all__ = ["ConsoleSession"]


class ConsoleSession(ABC):
    """One console the node is talking to: where a command's reply goes.

    ``send`` is called on the node's thread, so it must be quick and must
    never block or raise, even when the console has gone away.

    Example::

        class PrintSession(ConsoleSession):
            def send(self, reply: Reply) -> None:
                print(reply.text)
    """

    @abstractmethod
    def send(self, reply: Reply) -> None:
        """Deliver ``reply`` to the console (a ``BYE`` reply also closes it)."""
