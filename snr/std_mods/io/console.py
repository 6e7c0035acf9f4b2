"""Consoles for a running node: over TCP (`CommandReceiverFactory`) or on stdin.

Add ``CommandReceiverFactory()`` to a role, run the node, and type commands
into ``snr-console 127.0.0.1:9123`` from another terminal (thesis 6.4.3).
`LocalConsoleFactory` reads the same commands from the node's own terminal.
Both only turn lines into tasks; a `CommandProcessorEndpoint` runs them on
the node's thread. The commands and the protocol are in ``docs/console.md``.

Example::

    config = Config({"robot": [MotorFactory(), CommandReceiverFactory(port=9123)]})
"""

from __future__ import annotations

import codecs
import errno
import os
import select
import selectors
import socket
import sys
import threading
from typing import IO, Any, Dict, List, Optional, Tuple

from snr.core import LoopFactory
from snr.prelude import AbstractNode, CommsError, ComponentName, Mode
from snr.std_mods.io.console_commands import ConsoleLoop, ConsoleSession
from snr.std_mods.io.console_protocol import (
    DEFAULT_CONSOLE_PORT,
    MAX_LINE_BYTES,
    TOKEN_ENV_VAR,
    Reply,
    Status,
    check_listen_policy,
    tokens_match,
)

__all__ = [
    "CommandReceiverFactory",
    "CommandReceiverLoop",
    "LocalConsole",
    "LocalConsoleFactory",
]

MAX_CONSOLES = 8
"""How many remote consoles may be connected to one receiver at once."""

_SEND_TIMEOUT_S = 2.0  # a console that does not read its replies for this long is dropped
_GOODBYE_TIMEOUT_S = 0.2  # per console, when the node stops
_POLL_S = 0.5  # the selector wakes at least this often (halt() wakes it at once)
_READ_CHUNK = 4096


class _RemoteSession:
    """One TCP console, served by the receiver loop's thread.

    Every request line gets a numbered `_ReplySlot`; whoever answers it (the
    node's thread for commands, the loop's thread for a refused line) fills
    the slot, and replies go out in request order, so a console always knows
    which reply answers which line.
    """

    def __init__(self, sock: socket.socket, peer: str, wake: socket.socket) -> None:
        self.sock = sock
        self.peer = peer
        self.authenticated = False
        self.closed = False
        self.leaving = False  # a BYE is due: run no more of this console's lines
        self._inbox = bytearray()
        self._skipping_long_line = False
        self._next_slot = 0  # numbers handed to requests (loop thread)
        self._next_to_send = 0  # the reply the console waits for next (loop thread)
        self._ready: Dict[int, Reply] = {}  # filled from any thread
        self._wake = wake

    def slot(self) -> _ReplySlot:
        """A place for the reply to the next request, in order."""
        slot = _ReplySlot(self, self._next_slot)
        self._next_slot += 1
        return slot

    def answer(self, reply: Reply) -> None:
        """Answer the next request here, on the loop's thread."""
        self.slot().send(reply)

    def fill(self, number: int, reply: Reply) -> None:
        """Store the reply for request ``number`` (any thread; never blocks)."""
        if self.closed:
            return  # the console has gone; nobody waits for this reply
        if reply.status is Status.BYE:
            self.leaving = True
        self._ready[number] = reply
        try:
            self._wake.send(b"\0")
        except OSError:
            pass  # the receiver is shutting down (it sends what is ready then)

    def take_lines(self, data: bytes) -> List[Optional[bytes]]:
        """The complete lines in ``data``, in order; None stands for a line too long."""
        self._inbox += data
        lines: List[Optional[bytes]] = []
        while True:
            newline = self._inbox.find(b"\n")
            if newline < 0:
                if len(self._inbox) > MAX_LINE_BYTES:
                    self._inbox.clear()
                    if not self._skipping_long_line:
                        lines.append(None)
                    self._skipping_long_line = True
                return lines
            line = bytes(self._inbox[:newline])
            del self._inbox[: newline + 1]
            if self._skipping_long_line:  # the tail of a line already refused
                self._skipping_long_line = False
            else:
                lines.append(line if len(line) <= MAX_LINE_BYTES else None)

    def flush(self, timeout_s: float) -> bool:
        """Send the replies that are ready, in order; False once the console is done."""
        self.sock.settimeout(timeout_s)
        while self._next_to_send in self._ready:
            reply = self._ready.pop(self._next_to_send)
            self._next_to_send += 1
            self.sock.sendall(reply.encode())
            if reply.status is Status.BYE:
                return False
        return not self.closed

    def goodbye(self, reply: Reply, timeout_s: float) -> None:
        """Send what is ready, then ``reply`` even if other replies never came."""
        try:
            if self.flush(timeout_s):
                self.sock.sendall(reply.encode())
        except OSError:
            pass  # it had gone already

    def close(self) -> None:
        self.closed = True
        self.sock.close()

    def __repr__(self) -> str:
        return f"console {self.peer}"


class _ReplySlot(ConsoleSession):
    """Where the reply to one request of a remote console goes."""

    def __init__(self, session: _RemoteSession, number: int) -> None:
        self.session = session
        self.number = number

    def send(self, reply: Reply) -> None:
        self.session.fill(self.number, reply)

    def __repr__(self) -> str:
        return repr(self.session)


class CommandReceiverLoop(ConsoleLoop):
    """Accepts console connections over TCP and submits their commands.

    Built by `CommandReceiverFactory`. It listens from ``begin()`` (so a port
    in use is reported at start-up), serves up to `MAX_CONSOLES` consoles with
    one ``selectors`` loop on its own thread, and says goodbye to every
    console when the node stops. A console that hangs up, sends garbage or
    stops reading is dropped; the node never notices.

    Example::

        CommandReceiverFactory(port=9123)   # the config entry that builds this loop
    """

    factory: CommandReceiverFactory

    def __init__(self, factory: CommandReceiverFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.host = factory.host
        self.port = factory.port
        self._token = factory.token
        self._selector: Optional[selectors.BaseSelector] = None
        self._listener: Optional[socket.socket] = None
        self._wake_in: Optional[socket.socket] = None
        self._wake_out: Optional[socket.socket] = None
        self._sessions: Dict[socket.socket, _RemoteSession] = {}

    # -- life cycle (node thread) -------------------------------------------
    def begin(self) -> None:
        """Listen on ``host:port`` and add the command processor."""
        try:
            listener = socket.create_server((self.host, self.port))
        except OSError as error:
            self._cannot_listen(error)
            return
        self._listener = listener
        self._wake_in, self._wake_out = socket.socketpair()
        self._wake_out.setblocking(False)  # a wake-up must never block the node's thread
        self._selector = selectors.DefaultSelector()
        self._selector.register(listener, selectors.EVENT_READ, None)
        self._selector.register(self._wake_in, selectors.EVENT_READ, None)
        host, port = listener.getsockname()[:2]
        self.factory._now_listening(host, port)
        self.info("Console receiver listening on %s:%d", host, port)
        super().begin()

    def _cannot_listen(self, error: OSError) -> None:
        in_use = error.errno in (errno.EADDRINUSE, getattr(errno, "WSAEADDRINUSE", None))
        hint = (
            "Another program (or another node) already uses this port: stop it, or give "
            "this node another one, e.g. CommandReceiverFactory(port=9124)."
            if in_use
            else "Check that the host is an address of this machine."
        )
        message = (
            f"Console receiver {self.name!r} cannot listen on {self.host}:{self.port}: "
            f"{error.strerror or error}. {hint}"
        )
        if self.parent.mode is Mode.DEPLOYED:
            self.err("%s The node runs on without a console.", message)
            self.set_terminate_flag("cannot listen")
            return
        raise CommsError(message) from error

    def halt(self) -> None:
        """Wake the loop's thread so it sees it must stop."""
        self._poke()

    def terminate(self) -> None:
        """Send what is queued and a goodbye to every console, then close all sockets."""
        for session in list(self._sessions.values()):
            session.goodbye(
                Reply(Status.BYE, f"Node {self.parent.role!r} is stopping."), _GOODBYE_TIMEOUT_S
            )
            session.close()
        self._sessions.clear()
        for closable in (self._selector, self._listener, self._wake_in, self._wake_out):
            if closable is not None:
                closable.close()
        self._listener = None

    def _poke(self) -> None:
        if self._wake_out is not None:
            try:
                self._wake_out.send(b"\0")
            except OSError:
                pass

    # -- the loop (its own thread) -------------------------------------------
    def loop(self) -> None:
        """Wait for connections, lines and replies; handle what arrived."""
        selector = self._selector
        if selector is None:  # begin() could not listen
            self.set_terminate_flag("not listening")
            return
        for key, _ in selector.select(timeout=_POLL_S):
            sock: Any = key.fileobj
            if sock is self._listener:
                self._accept()
            elif sock is self._wake_in:
                self._drain_wakeups()
            elif sock in self._sessions:
                self._read(self._sessions[sock])
        for session in list(self._sessions.values()):
            self._flush(session)

    def _accept(self) -> None:
        assert self._listener is not None and self._wake_out is not None
        try:
            sock, address = self._listener.accept()
        except OSError:
            return  # the client gave up before we accepted
        session = _RemoteSession(sock, f"{address[0]}:{address[1]}", self._wake_out)
        if len(self._sessions) >= MAX_CONSOLES:
            self.warn("Turned away console %s: %d are connected.", session.peer, MAX_CONSOLES)
            session.answer(Reply(Status.BYE, f"Too many consoles ({MAX_CONSOLES}) are open."))
            self._flush(session)
            return
        self._sessions[sock] = session
        assert self._selector is not None
        self._selector.register(sock, selectors.EVENT_READ, None)
        self.info("Console %s connected", session.peer)
        if self._token is None:
            session.authenticated = True
            session.answer(Reply(Status.HELLO, self._greeting()))
        else:
            session.answer(
                Reply(Status.AUTH, "This node needs a console token: send `auth <token>`.")
            )

    def _greeting(self) -> str:
        return (
            f"Connected to node {self.parent.role!r}. "
            "Type 'help' for the commands, 'exit' to stop the node."
        )

    def _drain_wakeups(self) -> None:
        assert self._wake_in is not None
        try:
            self._wake_in.recv(_READ_CHUNK)
        except OSError:
            pass

    def _read(self, session: _RemoteSession) -> None:
        try:
            data = session.sock.recv(_READ_CHUNK)
        except OSError:
            data = b""
        if not data:
            self._drop(session, "disconnected")
            return
        for raw in session.take_lines(data):
            self._on_line(session, raw)

    def _on_line(self, session: _RemoteSession, raw: Optional[bytes]) -> None:
        if session.leaving:
            return  # after `exit` or a refused token, later lines are not run
        if raw is None:
            message = f"Ignored a line longer than {MAX_LINE_BYTES} bytes."
            session.answer(Reply(Status.ERROR, message))
            return
        try:
            line = raw.decode("utf-8").strip()
        except UnicodeDecodeError:
            session.answer(Reply(Status.ERROR, "Ignored a line that is not UTF-8 text."))
            return
        if not session.authenticated:
            self._authenticate(session, line)
        elif not line:
            session.answer(Reply(Status.OK, ""))
        else:
            self.submit(line, session.slot())

    def _authenticate(self, session: _RemoteSession, line: str) -> None:
        assert self._token is not None
        word, _, given = line.partition(" ")
        if word == "auth" and tokens_match(self._token, given.strip()):
            session.authenticated = True
            session.answer(Reply(Status.HELLO, self._greeting()))
            return
        self.warn("Console %s gave a wrong or no token; disconnected it.", session.peer)
        session.answer(
            Reply(
                Status.BYE,
                "Wrong or missing console token. Give the node's token with "
                f"`snr-console HOST:PORT --token ...` or {TOKEN_ENV_VAR}.",
            )
        )

    def _flush(self, session: _RemoteSession) -> None:
        try:
            still_open = session.flush(_SEND_TIMEOUT_S)
        except OSError:  # reset, broken pipe, or it stopped reading
            self._drop(session, "connection lost")
            return
        if not still_open:
            self._drop(session, "closed")

    def _drop(self, session: _RemoteSession, why: str) -> None:
        if self._sessions.pop(session.sock, None) is not None and self._selector is not None:
            self._selector.unregister(session.sock)
        session.close()
        self.info("Console %s %s", session.peer, why)


class CommandReceiverFactory(LoopFactory):
    """Lets consoles control this node over TCP (thesis 6.4.3).

    Adds a `CommandReceiverLoop` and, when it begins, a
    `CommandProcessorEndpoint` that runs the commands. Connect with
    ``snr-console HOST:PORT``.

    Args:
        host: address to listen on. The default, ``"127.0.0.1"``, accepts
            consoles on this machine only. Any other address needs a token.
        port: TCP port; ``0`` lets the system pick a free one (see `address`).
        token: shared secret consoles must present; defaults to the
            ``SNR_CONSOLE_TOKEN`` environment variable.
        name: the loop's component name.

    Raises:
        ConfigError: a non-loopback host without a token, or a malformed token.

    Example::

        CommandReceiverFactory()                                # 127.0.0.1:9123
        CommandReceiverFactory(host="0.0.0.0", token="long-random-word")
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_CONSOLE_PORT,
        token: Optional[str] = None,
        name: ComponentName = "command_receiver",
    ) -> None:
        super().__init__()
        if token is None:
            token = os.environ.get(TOKEN_ENV_VAR) or None
        check_listen_policy(host, token)
        self.host = host
        self.port = port
        self.token = token
        self.name = name
        self.address: Optional[Tuple[str, int]] = None
        self._listening = threading.Event()

    def get(self, parent: AbstractNode) -> CommandReceiverLoop:
        return CommandReceiverLoop(self, parent)

    def _now_listening(self, host: str, port: int) -> None:
        self.address = (host, port)
        self._listening.set()

    def wait_until_listening(self, timeout_s: float = 5.0) -> Tuple[str, int]:
        """The ``(host, port)`` the receiver listens on, once it does.

        Handy with ``port=0`` in tests: start the node in a thread, then ask.

        Raises:
            CommsError: the receiver was not listening within ``timeout_s``.
        """
        if not self._listening.wait(timeout_s) or self.address is None:
            raise CommsError(
                f"The console receiver {self.name!r} was not listening within {timeout_s} s. "
                "Is the node running (node.loop() called), and did it start without errors?"
            )
        return self.address

    # An Event cannot be pickled; configs are pickled for spawned processes.
    def __getstate__(self) -> Dict[str, Any]:
        state = super().__getstate__()
        del state["_listening"]
        return state

    def __setstate__(self, state: Dict[str, Any]) -> None:
        super().__setstate__(state)
        self._listening = threading.Event()

    def __repr__(self) -> str:
        return f"CommandReceiverFactory(host={self.host!r}, port={self.port})"


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
    stdin ends (Ctrl-D) the console stops and the node keeps running.

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
        self._decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")
        self._pending = ""
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
        line = self._next_line()
        if line is None:
            self.info("stdin closed: the local console stops; the node keeps running.")
            self.set_terminate_flag("end of input")
        elif line.strip():
            self.submit(line.strip(), self.session)

    def _next_line(self) -> Optional[str]:
        """A line, "" when none arrived yet, or None at the end of input."""
        if self._fd is None:  # an in-memory stream (tests) never blocks
            line = self.stream.readline(MAX_LINE_BYTES)
            return line if line else None
        if "\n" not in self._pending:
            # Wait until a line comes or halt() writes to the wake-up pipe.
            # (select.select, unlike epoll, also accepts a plain file as stdin.)
            waiting = [self._fd] + ([self._wake_pipe[0]] if self._wake_pipe else [])
            readable, _, _ = select.select(waiting, [], [], _POLL_S)
            if self._fd not in readable:
                return ""
            chunk = os.read(self._fd, _READ_CHUNK)
            if not chunk:
                rest, self._pending = self._pending, ""
                return rest or None
            self._pending += self._decoder.decode(chunk)
        line, newline, self._pending = self._pending.partition("\n")
        if not newline:
            self._pending = line
            if len(line) > MAX_LINE_BYTES:  # not a command: binary data piped in?
                self._pending = ""
                self.session.send(Reply(Status.ERROR, "Ignored an over-long line."))
            return ""
        return line[:MAX_LINE_BYTES]


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
