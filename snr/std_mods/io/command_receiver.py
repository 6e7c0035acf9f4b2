"""The node's end of the console: `ConsoleLoop`, the core of every transport, and TCP's.

A console turns the lines a user types into tasks; its command processor
(``command_processor.py``) runs each on the node's thread and sends the reply
to the line's `ConsoleSession`. `CommandReceiverFactory` serves ``snr-console
HOST:PORT`` over TCP, a thread per connected console (thesis 6.4.3). Limits
and security: docs/console.md.

Example::

    config = Config({"robot": [MotorFactory(), CommandReceiverFactory(port=9123)]})
"""

from __future__ import annotations

import logging
import queue
import selectors
import socket
import threading
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

from snr.core import LoopFactory, ThreadLoop, tasks
from snr.core.checks.os_errors import explain_os_error
from snr.core.checks.step_mode import console_priority
from snr.core.logs import RepeatFilter
from snr.prelude import (
    AbstractFactory,
    AbstractNode,
    CommsError,
    ComponentName,
    ConfigError,
    DataKey,
    Mode,
    Task,
    TaskType,
)
from snr.std_mods.io.command_processor import CommandProcessorFactory
from snr.std_mods.io.console_protocol import (
    DEFAULT_CONSOLE_PORT,
    TOKEN_ENV_VAR,
    ConsoleSession,
    LineReader,
    Reply,
    Status,
    check_listen_policy,
    default_token,
    tokens_match,
)

__all__ = [
    "DEFAULT_AUTH_TIMEOUT_S",
    "DEFAULT_IDLE_TIMEOUT_S",
    "MAX_CONSOLES",
    "MAX_WAITING_CONSOLES",
    "CommandReceiverFactory",
    "CommandReceiverLoop",
    "ConsoleLoop",
]

MAX_CONSOLES = 8
"""How many remote consoles may be connected (with their token given) at once.

Example::

    [RemoteConsole(port=9123).connect() for _ in range(MAX_CONSOLES + 1)]  # the last: refused
"""

MAX_WAITING_CONSOLES = 32
"""How many consoles may wait to give their token; a new one pushes out the oldest.

Example::

    MAX_WAITING_CONSOLES   # 32: idle sockets beyond that cannot lock anyone out
"""

DEFAULT_AUTH_TIMEOUT_S = 5.0
"""Seconds a console may take to give its token before it is disconnected.

Example::

    CommandReceiverFactory(token="long-random-word", auth_timeout_s=2.0)
"""

DEFAULT_IDLE_TIMEOUT_S = 600.0
"""Seconds a connected console may send no command before it is disconnected.

Example::

    CommandReceiverFactory(idle_timeout_s=None)   # never close an idle console
"""

_SEND_TIMEOUT_S = 2.0  # a console that takes none of a reply for this long is dropped
_GOODBYE_TIMEOUT_S = 0.5  # for all consoles together, when the node stops
_MAX_ADDRESSES = 1024  # the token throttle remembers at most so many addresses
_READ_CHUNK = 4096

# What the receiver logs, by key: the summary of its repeats, and its level.
_REPORTS = {
    "slow reader": ("Consoles dropped for not reading their replies", logging.WARNING),
    "waiting full": ("Consoles pushed out while waiting to give their token", logging.WARNING),
    "full": ("Consoles turned away (too many connected)", logging.WARNING),
    "no token": ("Consoles disconnected for giving no token in time", logging.INFO),
    "idle": ("Idle consoles disconnected", logging.INFO),
    "too early": (
        "Console tokens refused unchecked (too soon after wrong ones)",
        logging.WARNING,
    ),
    "wrong token": ("Consoles that gave a wrong token", logging.WARNING),
    "no auth": ("Consoles that sent a command instead of their token", logging.WARNING),
}


class ConsoleLoop(ThreadLoop):
    """Base of the consoles: adds a processor at ``begin`` and submits lines to it.

    Subclasses read lines (in ``loop()`` or threads of their own) and call
    ``self.submit(line, session)``. Each console adds its own processor, so
    several consoles never run one command twice.

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


class _TokenThrottle:
    """Wrong tokens from one address make it wait longer and longer before the next try.

    After the n-th wrong token in a row, the address's next token is checked
    only after ``first_delay_s * 2 ** (n - 1)`` seconds (at most
    ``max_delay_s``); earlier tries are refused unchecked. A right token, or
    ``forget_after_s`` without a wrong one, starts the address afresh. At
    most ``max_addresses`` are remembered (the longest-quiet is forgotten),
    so a flood from many addresses costs bounded memory.
    """

    def __init__(
        self, first_delay_s: float = 0.25, max_delay_s: float = 30.0, forget_after_s: float = 600.0
    ) -> None:
        self.first_delay_s, self.max_delay_s = first_delay_s, max_delay_s
        self.forget_after_s = forget_after_s
        self._failures: Dict[str, Tuple[int, float]] = {}  # host -> (in a row, last), oldest first
        self._lock = threading.Lock()  # each console's thread checks its own token

    def _in_a_row(self, host: str, now: float) -> Tuple[int, float]:
        failures, last = self._failures.get(host, (0, 0.0))
        return (failures, last) if now - last <= self.forget_after_s else (0, 0.0)

    def _delay_s(self, failures: int) -> float:
        return min(self.max_delay_s, self.first_delay_s * 2.0 ** min(failures - 1, 30))

    def wait_s(self, host: str, now: float) -> float:
        """How long ``host`` must still wait before its next token is checked."""
        failures, last = self._in_a_row(host, now)
        return max(0.0, last + self._delay_s(failures) - now) if failures else 0.0

    def failed(self, host: str, now: float) -> Tuple[int, float]:
        """Count a wrong token; the failures in a row and the wait before the next try."""
        with self._lock:
            failures = self._in_a_row(host, now)[0] + 1
            self._failures.pop(host, None)
            if len(self._failures) >= _MAX_ADDRESSES:
                del self._failures[next(iter(self._failures))]
            self._failures[host] = (failures, now)
        return failures, self._delay_s(failures)

    def succeeded(self, host: str) -> None:
        """A right token: ``host`` starts afresh."""
        with self._lock:
            self._failures.pop(host, None)


class _Gone(Exception):
    """The console's connection ends; the message says how (for the log)."""


class _RemoteConsole(ConsoleSession):
    """One TCP console, served by a thread of the receiver's while it is connected.

    The thread reads a line, has it answered, writes the reply, and only then
    reads the next: lines sent ahead wait in the socket, so a flood of
    commands costs the node nothing. Replies reach the thread through `send`.
    """

    def __init__(
        self, receiver: CommandReceiverLoop, sock: socket.socket, address: Tuple[Any, ...]
    ) -> None:
        self.receiver = receiver
        self.sock = sock
        self.host = str(address[0])
        self.peer = f"{address[0]}:{address[1]}"
        self.authenticated = False
        self.connected_at = time.monotonic()
        self.replies: queue.Queue[Reply] = queue.Queue()
        self.lines = LineReader()
        self.done = threading.Event()  # set once the connection is closed

    def send(self, reply: Reply) -> None:
        """Queue ``reply`` for the console's thread to write (any thread; never blocks)."""
        self.replies.put(reply)

    def interrupt(self, goodbye: Reply) -> None:
        """Have the console's thread write ``goodbye`` (a BYE) at once, whatever it waits for."""
        self.send(goodbye)
        _shut(self.sock, socket.SHUT_RD)  # ends a wait in recv()

    def serve(self) -> None:
        """The console's thread: greet, then answer line after line until a BYE or a hang-up."""
        why = "closed"
        try:
            reply = self.receiver.greet(self)
            while self.write(reply):
                reply = self.next_reply()
        except _Gone as gone:
            why = str(gone)
        except OSError:  # reset or broken pipe
            why = "connection lost"
        finally:
            self.receiver.forget(self, why)

    def next_reply(self) -> Reply:
        """The reply to the next request line (a goodbye from elsewhere goes first)."""
        while self.replies.empty():
            request = self.lines.next_request()
            if isinstance(request, Reply):
                return request  # a line that cannot be run
            if request is not None:
                return self.receiver.answer(self, request)
            self.sock.settimeout(self.receiver.time_left_s(self))
            try:
                data = self.sock.recv(_READ_CHUNK)
            except socket.timeout:
                return self.receiver.timed_out(self)
            if not data and self.replies.empty():
                raise _Gone("disconnected")
            self.lines.feed(data)
        return self.replies.get()

    def write(self, reply: Reply) -> bool:
        """Send ``reply``; False when it says bye.

        Raises:
            _Gone: the console took none of it for `_SEND_TIMEOUT_S`.
        """
        data = memoryview(reply.encode())
        self.sock.settimeout(_SEND_TIMEOUT_S)
        while data:
            try:
                data = data[self.sock.send(data) :]
            except socket.timeout:
                self.receiver.report(
                    "slow reader",
                    f"Dropped console {self.peer}: it did not read its replies ({len(data)} "
                    f"bytes waiting, none taken for {_SEND_TIMEOUT_S:.1f} s).",
                )
                raise _Gone("dropped") from None
        return reply.status is not Status.BYE

    def __repr__(self) -> str:
        return f"console {self.peer}"


def _shut(sock: Optional[socket.socket], how: int) -> None:
    try:
        if sock is not None:
            sock.shutdown(how)
    except OSError:
        pass  # closed already


class CommandReceiverLoop(ConsoleLoop):
    """Accepts console connections over TCP; each console's thread submits its commands.

    Built by `CommandReceiverFactory`; it listens from ``begin()`` (so a port
    in use is reported at start-up). Its limits (`MAX_CONSOLES`,
    `MAX_WAITING_CONSOLES`, the time limits, wrong tokens, consoles that do
    not read) are in docs/console.md, "Several consoles"; each refusal is
    said to the console and logged (repeats are counted).

    Example::

        CommandReceiverFactory(port=9123)   # the config entry that builds this loop
    """

    factory: CommandReceiverFactory

    def __init__(self, factory: CommandReceiverFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self._listener: Optional[socket.socket] = None
        self._selector: Optional[selectors.BaseSelector] = None  # the listener, the wake-up
        self._wake_in: Optional[socket.socket] = None  # with _wake_out: halt() ends a wait
        self._wake_out: Optional[socket.socket] = None
        self._sessions: List[_RemoteConsole] = []  # the oldest first
        self._lock = threading.Lock()
        self._throttle = _TokenThrottle()
        self._repeats = RepeatFilter(self.log)
        self._last_summary = time.monotonic()

    def report(self, key: str, message: str) -> None:
        """Log ``message`` (repeats of ``key`` are counted, then summed up)."""
        with self._lock:
            self._repeats.report(key, *_REPORTS[key], message)

    def _bye(self, key: str, message: str, text: str) -> Reply:
        self.report(key, message)
        return Reply(Status.BYE, text)

    # -- life cycle ---------------------------------------------------------
    def begin(self) -> None:
        """Listen on ``host:port`` and add the command processor."""
        factory = self.factory
        try:
            self._listener = socket.create_server((factory.host, factory.port))
        except OSError as error:
            message = explain_os_error(
                error,
                action="listen",
                target=f"{factory.host}:{factory.port}",
                who=f"Console receiver {self.name!r}",
                setting="CommandReceiverFactory(port=...)",
            )
            if self.parent.mode is not Mode.DEPLOYED:
                raise CommsError(message) from error
            self.err("%s The node runs on without a console.", message)
            self.set_terminate_flag("cannot listen")
            return
        self._wake_in, self._wake_out = socket.socketpair()
        self._selector = selectors.DefaultSelector()  # not select(): any fd number works
        self._selector.register(self._listener, selectors.EVENT_READ)
        self._selector.register(self._wake_in, selectors.EVENT_READ)
        factory.address = self._listener.getsockname()[:2]
        self.info("Console receiver listening on %s:%d", *factory.address)
        super().begin()

    def loop(self) -> None:
        """Accept the next console and start its thread."""
        if self._listener is None or self._selector is None:  # begin() could not listen
            self.set_terminate_flag("not listening")
            return
        ready = [key.fileobj for key, _ in self._selector.select(self._repeats.every_s)]
        if self._wake_in in ready:
            self._wake_in.recv(_READ_CHUNK)  # halt() woke it
        elif self._listener in ready:
            try:
                self._start(_RemoteConsole(self, *self._listener.accept()))
            except OSError:
                pass  # the client gave up before we accepted
        if time.monotonic() - self._last_summary >= self._repeats.every_s:
            self._last_summary = time.monotonic()
            with self._lock:
                self._repeats.flush()  # counts of repeated warnings, even when they stopped

    def halt(self) -> None:
        """Wake the loop's thread so it sees it must stop."""
        try:
            if self._wake_out is not None:
                self._wake_out.send(b"\0")
        except OSError:
            pass

    def terminate(self) -> None:
        """Say goodbye to every console, then close all sockets.

        The goodbyes share one short deadline, so consoles that do not read
        cannot hold up the node's shutdown.
        """
        goodbye = Reply(Status.BYE, f"Node {self.parent.role!r} is stopping.")
        with self._lock:
            consoles = list(self._sessions)
        for console in consoles:
            console.interrupt(goodbye)
        deadline = time.monotonic() + _GOODBYE_TIMEOUT_S
        for console in consoles:
            if not console.done.wait(max(0.0, deadline - time.monotonic())):
                _shut(console.sock, socket.SHUT_RDWR)  # too slow to take its goodbye
        self._repeats.flush()
        for closable in (self._selector, self._listener, self._wake_in, self._wake_out):
            if closable is not None:
                closable.close()

    # -- the consoles (each on its own thread) --------------------------------
    def _start(self, console: _RemoteConsole) -> None:
        with self._lock:
            waiting = [c for c in self._sessions if not c.authenticated]
            full = self.factory.token is not None and len(waiting) >= MAX_WAITING_CONSOLES
            if full:
                self._sessions.remove(waiting[0])
            self._sessions.append(console)
        if full:
            self.report(
                "waiting full",
                f"{MAX_WAITING_CONSOLES} consoles are waiting to give their token, the most "
                f"this receiver keeps; disconnected the oldest, {waiting[0].peer}, to make room.",
            )
            text = "Too many consoles are waiting to give their token."
            waiting[0].interrupt(Reply(Status.BYE, text))
        name = f"snr-{self.parent.role}-{self.name}-consoles"
        threading.Thread(target=console.serve, name=name, daemon=True).start()

    def greet(self, console: _RemoteConsole) -> Reply:
        """The first reply: a request for the token, or the greeting."""
        if self.factory.token is None:
            return self._let_in(console)
        self.dbg("Console %s connected", console.peer)
        return Reply(Status.AUTH, "This node needs a console token: send `auth <token>`.")

    def _let_in(self, console: _RemoteConsole) -> Reply:
        """The greeting, or a BYE if `MAX_CONSOLES` are connected."""
        with self._lock:
            full = sum(c.authenticated for c in self._sessions) >= MAX_CONSOLES
            console.authenticated = not full
        if full:
            return self._bye(
                "full",
                f"Turned away console {console.peer}: {MAX_CONSOLES} are connected, the most "
                "this receiver serves.",
                f"Too many consoles ({MAX_CONSOLES}) are open.",
            )
        self.info("Console %s connected", console.peer)
        return Reply(Status.HELLO, self.greeting())

    def answer(self, console: _RemoteConsole, line: str) -> Reply:
        """Check the token, or run the command and wait for its reply."""
        if not console.authenticated:
            return self._authenticate(console, line)
        if not line:
            return Reply(Status.OK, "")
        self.submit(line, console)
        return console.replies.get()

    def time_left_s(self, console: _RemoteConsole) -> Optional[float]:
        """How long ``console`` may still send nothing (None: for ever)."""
        if not console.authenticated:
            return max(0.001, console.connected_at + self.factory.auth_timeout_s - time.monotonic())
        return self.factory.idle_timeout_s

    def timed_out(self, console: _RemoteConsole) -> Reply:
        """The goodbye of a console that gave no token, or no command, in time."""
        auth_s, idle_s = self.factory.auth_timeout_s, self.factory.idle_timeout_s
        if not console.authenticated:
            return self._bye(
                "no token",
                f"Console {console.peer} gave no token within {auth_s:g} s; disconnected it.",
                f"No console token within {auth_s:g} s: disconnected.",
            )
        return self._bye(
            "idle",
            f"Console {console.peer} sent no command for {idle_s:g} s; disconnected it.",
            f"Closed this console after {idle_s:g} s without a command. Connect again to carry on.",
        )

    def _authenticate(self, console: _RemoteConsole, line: str) -> Reply:
        word, _, given = line.partition(" ")
        host, peer, now = console.host, console.peer, time.monotonic()
        wait_s = self._throttle.wait_s(host, now) if word == "auth" else 0.0
        if wait_s > 0:
            return self._bye(
                "too early",
                f"Console {peer} gave a token {wait_s:.1f} s too soon after wrong ones "
                f"from {host}; refused it unchecked.",
                f"Too many wrong console tokens from {host}: the next one is checked "
                f"in {wait_s:.1f} s (each wrong token doubles the wait, up to "
                f"{self._throttle.max_delay_s:g} s).",
            )
        token = self.factory.token  # never None here: without one, `greet` lets consoles in
        if word == "auth" and token is not None and tokens_match(token, given.strip()):
            self._throttle.succeeded(host)
            return self._let_in(console)
        if word == "auth":
            failures, delay_s = self._throttle.failed(host, now)
            self.report(
                "wrong token",
                f"Console {peer} gave a wrong token ({failures} in a row from {host}); "
                f"disconnected it. The next token from there is checked after {delay_s:.2f} s.",
            )
        else:
            self.report(
                "no auth", f"Console {peer} sent a command before its token; disconnected it."
            )
        return Reply(
            Status.BYE,
            "Wrong or missing console token. Give the node's token with "
            f"`snr-console HOST:PORT --token ...` or {TOKEN_ENV_VAR}, or, if the node "
            "has a secret, run the console with the same secret ($SNR_SECRET or "
            "the secret file; see docs/console.md).",
        )

    def forget(self, console: _RemoteConsole, why: str) -> None:
        """``console``'s connection ended (``why``): close it and free its place."""
        with self._lock:
            if console in self._sessions:
                self._sessions.remove(console)
        if console.authenticated:
            self.info("Console %s %s", console.peer, why)
        else:
            self.dbg("Console %s %s before giving its token", console.peer, why)
        console.sock.close()
        console.done.set()


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
            ``SNR_CONSOLE_TOKEN`` environment variable, else a word made from
            the node's secret (``SNR_SECRET`` or the secret file; see
            `default_token`), else none.
        name: the loop's component name.
        auth_timeout_s: seconds a console may take to give its token
            (default `DEFAULT_AUTH_TIMEOUT_S`, 5 s).
        idle_timeout_s: seconds a console may send no command before it is
            disconnected (default `DEFAULT_IDLE_TIMEOUT_S`, 10 minutes);
            None never disconnects an idle console.

    Raises:
        ConfigError: a non-loopback host without a token, a malformed token,
            or a time limit that is not a positive number.

    Example::

        CommandReceiverFactory()                                # 127.0.0.1:9123
        CommandReceiverFactory(host="0.0.0.0", token="long-random-word")
        CommandReceiverFactory(idle_timeout_s=60)               # close idle consoles sooner
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_CONSOLE_PORT,
        token: Optional[str] = None,
        name: ComponentName = "command_receiver",
        auth_timeout_s: float = DEFAULT_AUTH_TIMEOUT_S,
        idle_timeout_s: Optional[float] = DEFAULT_IDLE_TIMEOUT_S,
    ) -> None:
        super().__init__()
        token = default_token(token, "CommandReceiverFactory")
        check_listen_policy(host, token)
        for what, seconds in (
            ("auth_timeout_s", auth_timeout_s),
            ("idle_timeout_s", idle_timeout_s),
        ):
            if seconds is not None and not seconds > 0:
                raise ConfigError(
                    f"CommandReceiverFactory({what}={seconds!r}): a time limit must be a "
                    "positive number of seconds"
                    + (" (or None for no limit)." if what == "idle_timeout_s" else ".")
                )
        self.host = host
        self.port = port
        self.token = token
        self.name = name
        self.auth_timeout_s = auth_timeout_s
        self.idle_timeout_s = idle_timeout_s
        self.address: Optional[Tuple[str, int]] = None
        """The ``(host, port)`` it listens on, once it does."""

    def get(self, parent: AbstractNode) -> CommandReceiverLoop:
        return CommandReceiverLoop(self, parent)

    def wait_until_listening(self, timeout_s: float = 5.0) -> Tuple[str, int]:
        """The ``(host, port)`` the receiver listens on, once it does.

        Handy with ``port=0`` in tests: start the node in a thread, then ask.

        Raises:
            CommsError: the receiver was not listening within ``timeout_s``.
        """
        deadline = time.monotonic() + timeout_s
        while self.address is None and time.monotonic() < deadline:
            time.sleep(0.005)
        if self.address is None:
            raise CommsError(
                f"The console receiver {self.name!r} was not listening within {timeout_s} s. "
                "Is the node running (node.loop() called), and did it start without errors?"
            )
        return self.address

    def __repr__(self) -> str:
        return f"CommandReceiverFactory(host={self.host!r}, port={self.port})"
