"""The 2021 console programs: a script builds one and calls ``run()``.

In the 2021 release a console was a program of its own: it read commands
from stdin (or a list), sent each to a node's `CommandReceiverFactory` over
TCP and printed the replies. ``RemoteConsole(server_tuple)`` reached any
host, ``LocalConsole(port)`` this one. Both are today's client,
`snr.std_mods.io.RemoteConsole`, with the 2021 arguments and ``run()``.

Today's ``snr-console HOST:PORT`` is the same program from the shell. (A
console in the node's own terminal is `LocalConsoleFactory`, whose loop
class is ``snr.extras.console_tools.LocalConsole``.)

Example::

    from snr import *

    if __name__ == "__main__":
        LocalConsole(9123).run()      # type commands; 'exit' stops the node
"""

from __future__ import annotations

import sys
from typing import IO, List, Optional, Sequence, Tuple, Union

from snr.std_mods.io import DEFAULT_CONSOLE_PORT, remote_console

__all__ = ["LocalConsole", "RemoteConsole"]


class RemoteConsole(remote_console.RemoteConsole):
    """The 2021 console program for a node's `CommandReceiverFactory` over TCP.

    Today's `snr.std_mods.io.RemoteConsole` (its ``send()`` and ``with``
    work too), made the 2021 way, ``RemoteConsole((host, port), commands)``,
    or today's, ``RemoteConsole(host, port)``.

    Args:
        server_tuple: the node's ``(host, port)``; or its host, today's way.
        commands: the commands to send, in order, instead of reading stdin;
            or, today's way, the port.
        retry_wait_s: accepted for 2021 code; the console connects once and
            says why it could not.
        name: the console's name.
        token: the node's console token, if it needs one.
        timeout_s: how long to wait to connect, and for each reply.

    Example::

        RemoteConsole(("192.168.1.20", 9123), ["list endpoints", "exit"]).run()
    """

    def __init__(
        self,
        server_tuple: Union[Tuple[str, int], str] = ("127.0.0.1", DEFAULT_CONSOLE_PORT),
        commands: Union[Sequence[str], int, None] = None,
        retry_wait_s: float = 0.5,
        name: str = "remote_console",
        token: Optional[str] = None,
        timeout_s: float = 10.0,
    ) -> None:
        if isinstance(server_tuple, str):  # today's call: RemoteConsole(host, port)
            port = commands if isinstance(commands, int) else DEFAULT_CONSOLE_PORT
            host, commands = server_tuple, None
        else:
            host, port = server_tuple
        if isinstance(commands, (int, str)):
            raise TypeError(
                f"{type(self).__name__}({server_tuple!r}, {commands!r}): give the commands "
                "as a list of lines, e.g. ['list endpoints', 'exit'], or leave them out "
                "to read stdin."
            )
        super().__init__(host, port, token, timeout_s)
        self.commands: Optional[List[str]] = None if commands is None else list(commands)
        self.retry_wait_s = retry_wait_s
        self.name = name

    @property
    def server_tuple(self) -> Tuple[str, int]:
        """The node's ``(host, port)``."""
        return self.host, self.port

    # The 2021 signature, run(output), not today's ConsoleClient.run(commands, stdin,
    # ...): 2021 scripts call run() or run(output), and nothing calls it as today's.
    def run(self, output: Optional[IO[str]] = None) -> int:  # type: ignore[override]
        """Connect, send the commands (or what stdin gives), print each reply, hang up.

        ``exit`` stops the node; ``quit`` or the end of input leaves it
        running. Returns an exit code: 0, or 1 if a command failed or the
        node went away unasked.

        Raises:
            ConsoleConnectionError: the node could not be reached; the
                message says what to check.
        """
        out = output if output is not None else sys.stdout
        try:
            if not self.is_connected():
                remote_console.say(out, self.connect().text)
            if self.commands is None:
                return self.interact(output=out)
            code = remote_console.EXIT_OK
            for line in (line.strip() for line in self.commands):
                if line:
                    code = max(code, self.run_command(line, out))
                if not self.is_connected():
                    break
            return code
        finally:
            self.close()


class LocalConsole(RemoteConsole):
    """The 2021 console program for a node on this machine.

    ``LocalConsole(port)`` is ``RemoteConsole(("127.0.0.1", port))``.

    Args:
        server_port: the port of the node's `CommandReceiverFactory`.
        commands: the commands to send, in order, instead of reading stdin.
        retry_wait_s: accepted for 2021 code (see `RemoteConsole`).

    Example::

        LocalConsole(9123, ["task event beep", "exit"]).run()
    """

    def __init__(
        self,
        server_port: int = DEFAULT_CONSOLE_PORT,
        commands: Optional[Sequence[str]] = None,
        retry_wait_s: float = 0.5,
    ) -> None:
        super().__init__(("127.0.0.1", server_port), commands, retry_wait_s, "local_console")
