"""The local console: console commands typed in the node's own terminal (stdin).

`LocalConsoleFactory` (also ``snr.LocalConsoleFactory``) adds a `LocalConsole`,
a `ConsoleLoop` like the TCP receiver: it reads lines from stdin, and the
node's command processor answers each on stdout (docs/console.md, "The local
console").

Example::

    config = Config({"robot": [MotorFactory(), LocalConsoleFactory()]})
"""

from __future__ import annotations

import os
import select
import sys
import threading
from typing import IO, Any, Dict, Optional, Tuple

from snr.core import LoopFactory
from snr.prelude import AbstractNode, ComponentName
from snr.std_mods.io.command_receiver import ConsoleLoop
from snr.std_mods.io.console_protocol import ConsoleSession, LineReader, Reply, Status

__all__ = ["LocalConsole", "LocalConsoleFactory"]

_POLL_S = 0.5  # the reader wakes at least this often
_READ_CHUNK = 4096


class _LocalSession(ConsoleSession):
    """Prints replies on the node's terminal; a BYE stops the local console."""

    def __init__(self, console: LocalConsole, output: IO[str]) -> None:
        self.console = console
        self.output = output
        self._lock = threading.Lock()

    def send(self, reply: Reply) -> None:
        if reply.text:
            with self._lock:
                try:
                    self.output.write(reply.text + "\n")
                    self.output.flush()
                except (OSError, ValueError):
                    pass  # the terminal is gone; the node carries on
        if reply.status is Status.BYE:
            self.console.set_terminate_flag("console closed")

    def __repr__(self) -> str:
        return "local console"


class LocalConsole(ConsoleLoop):
    """Reads console commands from the node's own terminal (stdin).

    The same commands as `snr-console`; replies are printed on stdout. When
    stdin ends (Ctrl-D, or the end of a file fed with ``<``) the console
    stops and the node keeps running.

    Example::

        LocalConsoleFactory()     # in a role's factory list
    """

    def __init__(
        self,
        factory: LocalConsoleFactory,
        parent: AbstractNode,
        stream: IO[str],
        output: IO[str],
    ) -> None:
        super().__init__(factory, parent, factory.name)
        self.stream = stream
        self.session = _LocalSession(self, output)
        self._fd = _real_fd(stream)
        self._lines = LineReader()
        self._at_end = False  # stdin has ended: what is left is the last line
        self._wake_pipe: Optional[Tuple[int, int]] = None  # lets halt() end a wait at once

    def begin(self) -> None:
        """Add the command processor; make the pipe that wakes the reader."""
        if self._fd is not None:
            self._wake_pipe = os.pipe()
        super().begin()

    def halt(self) -> None:
        """Wake the reader if it is waiting for a line."""
        if self._wake_pipe is not None:
            try:
                os.write(self._wake_pipe[1], b"\0")
            except OSError:
                pass

    def terminate(self) -> None:
        """Close the wake-up pipe (stdin itself belongs to the program)."""
        if self._wake_pipe is not None:
            for fd in self._wake_pipe:
                os.close(fd)
            self._wake_pipe = None

    def setup(self) -> None:
        self.session.send(Reply(Status.OK, f"Console for node {self.parent.role!r}: type 'help'."))

    def loop(self) -> None:
        """Submit the next line typed, waiting at most a moment for it."""
        request = self._lines.next_request(self._at_end)
        if request is None and self._at_end:
            self.info("stdin closed: the local console stops; the node keeps running.")
            self.set_terminate_flag("end of input")
        elif request is None:
            self._at_end = not self._read()
        elif isinstance(request, Reply):
            self.session.send(request)  # a line that cannot be run
        elif request:
            self.submit(request, self.session)

    def _read(self) -> bool:
        """Take what stdin has, waiting at most `_POLL_S` for it; False at its end."""
        if self._fd is None:  # an in-memory stream (tests) never blocks
            data = self.stream.readline().encode("utf-8")
        else:
            # select.select, unlike epoll, also accepts a plain file as stdin.
            waiting = [self._fd] + ([self._wake_pipe[0]] if self._wake_pipe else [])
            if self._fd not in select.select(waiting, [], [], _POLL_S)[0]:
                return True
            data = os.read(self._fd, _READ_CHUNK)
        self._lines.feed(data)
        return bool(data)


def _real_fd(stream: IO[str]) -> Optional[int]:
    """The stream's file descriptor if we can wait on it with a timeout."""
    if sys.platform == "win32":  # select() works only on sockets there
        return None
    try:
        return stream.fileno()
    except (OSError, ValueError, AttributeError):  # io.UnsupportedOperation is an OSError
        return None


class LocalConsoleFactory(LoopFactory):
    """Builds a `LocalConsole`: console commands typed in the node's terminal.

    Args:
        stream: where commands come from (default: ``sys.stdin``).
        output: where replies go (default: ``sys.stdout``).
        name: the loop's component name.

    Example::

        config = Config({"robot": [MotorFactory(), LocalConsoleFactory()]})
    """

    def __init__(
        self,
        stream: Optional[IO[str]] = None,
        output: Optional[IO[str]] = None,
        name: ComponentName = "local_console",
    ) -> None:
        super().__init__()
        self.stream = stream
        self.output = output
        self.name = name

    def get(self, parent: AbstractNode) -> LocalConsole:
        stream = self.stream if self.stream is not None else sys.stdin
        output = self.output if self.output is not None else sys.stdout
        return LocalConsole(self, parent, stream, output)

    def __getstate__(self) -> Dict[str, Any]:
        state = super().__getstate__()
        state["stream"] = state["output"] = None  # streams stay in their process
        return state
