"""`CommandReceiverFactory`: the node's end of the remote console, over TCP.

Add ``CommandReceiverFactory()`` to a role, run the node, and type commands
into ``snr-console 127.0.0.1:9123`` from another terminal (thesis 6.4.3).
The receiver only turns lines into tasks; a `CommandProcessorEndpoint` runs
them on the node's thread. (`LocalConsoleFactory`, in ``local_console.py``,
reads the same commands from the node's own terminal.) The commands and the
protocol are in ``docs/console.md``.

Example::

    config = Config({"robot": [MotorFactory(), CommandReceiverFactory(port=9123)]})
"""

from __future__ import annotations

import logging
import selectors
import socket
import threading
import time
from collections import deque
from typing import Any, Callable, Deque, Dict, List, Optional, Tuple

from snr.core import LoopFactory
from snr.core.checks.os_errors import explain_os_error
from snr.core.logs import RepeatFilter
from snr.prelude import AbstractNode, CommsError, ComponentName, ConfigError, Mode
from snr.std_mods.io.console_loop import ConsoleLoop
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
    "MAX_SEND_BUFFER_BYTES",
    "MAX_UNANSWERED",
    "MAX_WAITING_CONSOLES",
    "CommandReceiverFactory",
    "CommandReceiverLoop",
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

MAX_UNANSWERED = 4
"""Requests of one console the node may hold at once; reading it pauses beyond that.

Example::

    sock.sendall(b"dump datastore\\n" * 1000)   # the node holds MAX_UNANSWERED at a time
"""

MAX_SEND_BUFFER_BYTES = 4 << 20
"""Reply bytes kept for one console that is slow to read them; beyond that it is dropped.

A console that takes none of its replies for 2 s is dropped as well.

Example::

    MAX_SEND_BUFFER_BYTES // (1 << 20)   # 4 (MiB)
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

_SEND_TIMEOUT_S = 2.0  # a console that takes none of its replies for this long is dropped
_PAUSE_OUT_BYTES = 64 * 1024  # stop taking a console's lines while this much waits to go
_GOODBYE_TIMEOUT_S = 0.5  # for all consoles together, when the node stops
_POLL_S = 0.5  # the selector wakes at least this often (halt() wakes it at once)
_READ_CHUNK = 4096


class _TokenThrottle:
    """Wrong tokens from one address make it wait longer and longer before the next try.

    After the n-th wrong token in a row, the address's next token is checked
    only after ``first_delay_s * 2 ** (n - 1)`` seconds (at most
    ``max_delay_s``); earlier tries are refused unchecked. A right token, or
    ``forget_after_s`` without a wrong one, starts the address afresh.
    """

    def __init__(
        self,
        first_delay_s: float = 0.25,
        max_delay_s: float = 30.0,
        forget_after_s: float = 600.0,
        max_addresses: int = 1024,
    ) -> None:
        self.first_delay_s = first_delay_s
        self.max_delay_s = max_delay_s
        self.forget_after_s = forget_after_s
        self.max_addresses = max_addresses
        # host -> (wrong tokens in a row, the last one's time), the longest-quiet host first
        self._failures: Dict[str, Tuple[int, float]] = {}

    def _in_a_row(self, host: str, now: float) -> Tuple[int, float]:
        failures, last = self._failures.get(host, (0, 0.0))
        return (failures, last) if now - last <= self.forget_after_s else (0, 0.0)

    def wait_s(self, host: str, now: float) -> float:
        """How long ``host`` must still wait before its next token is checked."""
        failures, last = self._in_a_row(host, now)
        return max(0.0, last + self.delay_s(failures) - now) if failures else 0.0

    def delay_s(self, failures: int) -> float:
        """The wait after ``failures`` wrong tokens in a row."""
        return min(self.max_delay_s, self.first_delay_s * 2.0 ** min(failures - 1, 30))

    def failed(self, host: str, now: float) -> Tuple[int, float]:
        """Count a wrong token; the failures in a row and the wait before the next try."""
        failures = self._in_a_row(host, now)[0] + 1
        self._failures.pop(host, None)
        if len(self._failures) >= self.max_addresses:  # forget the longest-quiet address
            del self._failures[next(iter(self._failures))]
        self._failures[host] = (failures, now)
        return failures, self.delay_s(failures)

    def succeeded(self, host: str) -> None:
        """A right token: ``host`` starts afresh."""
        self._failures.pop(host, None)


class _RemoteSession:
    """One TCP console, served by the receiver loop's thread.

    Every request line gets a `_ReplySlot` in `waiting`; whoever answers it
    (the node's thread for commands, the loop's thread for a refused line)
    fills the slot, and replies go out in request order, so a console always
    knows which reply answers which line. At most `MAX_UNANSWERED` requests
    wait for their replies; until some are sent, the console's lines wait in
    the socket (so a flood of commands costs the node nothing). Replies are
    sent without blocking from an output buffer that the loop thread drains.
    """

    def __init__(self, sock: socket.socket, address: Tuple[Any, ...], wake: socket.socket) -> None:
        self.sock = sock
        self.host = str(address[0])
        self.peer = f"{address[0]}:{address[1]}"
        self.wake = wake  # written to when a reply is filled in
        self.authenticated = False
        self.closed = False
        self.leaving = False  # a BYE is due: run no more of this console's lines
        self.connected_at = self.last_request = self.last_sent = time.monotonic()
        self.events = 0  # what the selector watches for (0: not registered)
        self.waiting: Deque[_ReplySlot] = deque()  # requests not yet in `out`, in order
        self.out = bytearray()  # encoded replies not yet taken by the socket
        self.bye_queued = False  # the BYE is in `out`: close once it is sent
        self.lines = LineReader()

    def slot(self) -> _ReplySlot:
        """A place for the reply to the next request, in order."""
        slot = _ReplySlot(self)
        self.waiting.append(slot)
        return slot

    def takes_lines(self) -> bool:
        """True while this console may have another line run."""
        return (
            not self.leaving
            and len(self.waiting) < MAX_UNANSWERED
            and len(self.out) < _PAUSE_OUT_BYTES
        )

    def wants_to_read(self) -> bool:
        """True when the socket should be read: lines are taken, none is waiting."""
        return self.takes_lines() and not self.lines.has_line()

    def collect(self) -> None:
        """Move the replies that are ready, in order, to the output buffer."""
        while self.waiting and not self.bye_queued:
            reply = self.waiting[0].reply
            if reply is None:
                return
            self.waiting.popleft()
            if not self.out:
                self.last_sent = time.monotonic()  # the send clock starts now
            self.out += reply.encode()
            self.bye_queued = reply.status is Status.BYE

    def write(self) -> None:
        """Send what the socket takes now, never waiting.

        Raises:
            OSError: the console hung up or reset the connection.
        """
        while self.out:
            try:
                sent = self.sock.send(self.out[:65536])
            except (BlockingIOError, InterruptedError):
                return
            del self.out[:sent]
            self.last_sent = time.monotonic()

    def __repr__(self) -> str:
        return f"console {self.peer}"


class _ReplySlot(ConsoleSession):
    """Where the reply to one request of a remote console goes."""

    def __init__(self, session: _RemoteSession) -> None:
        self.session = session
        self.reply: Optional[Reply] = None

    def send(self, reply: Reply) -> None:
        """Fill the slot (any thread; never blocks) and wake the receiver to send it."""
        if self.session.closed:
            return  # the console has gone; nobody waits for this reply
        if reply.status is Status.BYE:
            self.session.leaving = True
        self.reply = reply
        try:
            self.session.wake.send(b"\0")
        except OSError:
            pass  # the receiver is shutting down, or already has wake-ups to read

    def __repr__(self) -> str:
        return repr(self.session)


class CommandReceiverLoop(ConsoleLoop):
    """Accepts console connections over TCP and submits their commands.

    Built by `CommandReceiverFactory`. It listens from ``begin()`` (so a port
    in use is reported at start-up) and serves its consoles with one
    ``selectors`` loop on its own thread, never blocking on a socket. It
    serves up to `MAX_CONSOLES` consoles that gave their token, plus up to
    `MAX_WAITING_CONSOLES` that have yet to (they are disconnected after the
    factory's ``auth_timeout_s``); a console idle for ``idle_timeout_s`` is
    disconnected; wrong tokens make their address wait longer and longer; a
    console that stops reading its replies is dropped. It says goodbye to
    every console when the node stops. The node never notices any of it.

    Example::

        CommandReceiverFactory(port=9123)   # the config entry that builds this loop
    """

    factory: CommandReceiverFactory

    def __init__(self, factory: CommandReceiverFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.auth_timeout_s = factory.auth_timeout_s
        self.idle_timeout_s = factory.idle_timeout_s
        self._selector: Optional[selectors.BaseSelector] = None
        self._listener: Optional[socket.socket] = None
        self._wake_in: Optional[socket.socket] = None
        self._wake_out: Optional[socket.socket] = None
        self._sessions: Dict[Any, _RemoteSession] = {}  # by socket, the oldest first
        self._throttle = _TokenThrottle()
        self._repeats = RepeatFilter(self.log)
        self._last_summary = time.monotonic()

    # -- life cycle (node thread) -------------------------------------------
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
        self._listener.setblocking(False)
        self._wake_in, self._wake_out = socket.socketpair()
        self._wake_out.setblocking(False)  # a wake-up must never block the node's thread
        self._selector = selectors.DefaultSelector()
        self._selector.register(self._listener, selectors.EVENT_READ)
        self._selector.register(self._wake_in, selectors.EVENT_READ)
        host, port = self._listener.getsockname()[:2]
        factory._now_listening(host, port)
        self.info("Console receiver listening on %s:%d", host, port)
        super().begin()

    def halt(self) -> None:
        """Wake the loop's thread so it sees it must stop."""
        if self._wake_out is not None:
            try:
                self._wake_out.send(b"\0")
            except OSError:
                pass

    def terminate(self) -> None:
        """Send what is queued and a goodbye to every console, then close all sockets.

        The goodbyes share one short deadline, so consoles that do not read
        cannot hold up the node's shutdown.
        """
        goodbye = Reply(Status.BYE, f"Node {self.parent.role!r} is stopping.").encode()
        deadline = time.monotonic() + _GOODBYE_TIMEOUT_S
        for session in self._sessions.values():
            session.collect()
            if not session.bye_queued:
                session.out += goodbye
            try:
                session.sock.settimeout(max(0.001, deadline - time.monotonic()))
                session.sock.sendall(session.out)
            except OSError:
                pass  # gone already, or too slow to take its goodbye
            session.closed = True
            session.sock.close()
        self._sessions.clear()
        self._repeats.flush()
        for closable in (self._selector, self._listener, self._wake_in, self._wake_out):
            if closable is not None:
                closable.close()

    # -- the loop (its own thread) -------------------------------------------
    def loop(self) -> None:
        """Wait for connections, lines and replies; handle what arrived; enforce the limits."""
        if self._selector is None or self._wake_in is None:  # begin() could not listen
            self.set_terminate_flag("not listening")
            return
        now = time.monotonic()
        deadlines = [when for s in self._sessions.values() for when, _ in self._limits(s)]
        wait_s = max(0.005, min([now + _POLL_S, *deadlines]) - now)
        for key, mask in self._selector.select(wait_s):
            session = self._sessions.get(key.fileobj)
            if key.fileobj is self._listener:
                self._accept()
            elif key.fileobj is self._wake_in:
                self._wake_in.recv(_READ_CHUNK)  # the wake-ups: replies were filled in
            elif session is not None:
                if mask & selectors.EVENT_READ:
                    self._read(session)
                if mask & selectors.EVENT_WRITE and not session.closed:
                    self._write(session)
        now = time.monotonic()
        for session in list(self._sessions.values()):
            self._serve(session)
        for session in list(self._sessions.values()):
            for when, act in self._limits(session):
                if now > when:
                    act(session)
                    break
        if now - self._last_summary >= self._repeats.every_s:
            self._last_summary = now
            self._repeats.flush()  # counts of repeated warnings, even when they stopped

    def _limits(self, session: _RemoteSession) -> List[Tuple[float, Callable[[Any], None]]]:
        """The session's time limits: when each runs out, and what is done then."""
        limits: List[Tuple[float, Callable[[Any], None]]] = []
        if session.out:
            limits.append((session.last_sent + _SEND_TIMEOUT_S, self._drop_slow_reader))
        if not session.authenticated:
            limits.append((session.connected_at + self.auth_timeout_s, self._no_token_in_time))
        elif self.idle_timeout_s is not None and not session.waiting:
            limits.append((session.last_request + self.idle_timeout_s, self._close_idle))
        return limits

    def _accept(self) -> None:
        assert self._listener is not None and self._wake_out is not None
        try:
            sock, address = self._listener.accept()
        except OSError:
            return  # the client gave up before we accepted, or nothing is waiting
        sock.setblocking(False)
        session = _RemoteSession(sock, address, self._wake_out)
        if self.factory.token is None:
            self._sessions[sock] = session
            self._let_in(session)
            return
        waiting = [s for s in self._sessions.values() if not s.authenticated]
        if len(waiting) >= MAX_WAITING_CONSOLES:
            self._repeats.report(
                "waiting full",
                "Consoles pushed out while waiting to give their token",
                logging.WARNING,
                f"{MAX_WAITING_CONSOLES} consoles are waiting to give their token, the most "
                f"this receiver keeps; disconnected the oldest, {waiting[0].peer}, to make room.",
            )
            text = "Too many consoles are waiting to give their token."
            self._close_with(waiting[0], Reply(Status.BYE, text))
        self._sessions[sock] = session
        self.dbg("Console %s connected", session.peer)
        session.slot().send(
            Reply(Status.AUTH, "This node needs a console token: send `auth <token>`.")
        )

    def _let_in(self, session: _RemoteSession) -> None:
        """Greet the console, or turn it away if `MAX_CONSOLES` are connected."""
        if sum(s.authenticated for s in self._sessions.values()) >= MAX_CONSOLES:
            self._repeats.report(
                "full",
                "Consoles turned away (too many connected)",
                logging.WARNING,
                f"Turned away console {session.peer}: {MAX_CONSOLES} are connected, the most "
                "this receiver serves.",
            )
            text = f"Too many consoles ({MAX_CONSOLES}) are open."
            self._close_with(session, Reply(Status.BYE, text))
            return
        session.authenticated = True
        session.last_request = time.monotonic()
        session.slot().send(Reply(Status.HELLO, self.greeting()))
        self.info("Console %s connected", session.peer)

    def _read(self, session: _RemoteSession) -> None:
        try:
            data = session.sock.recv(_READ_CHUNK)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            self._drop(session, "disconnected")
        session.lines.feed(data)

    def _write(self, session: _RemoteSession) -> bool:
        """Send what the socket takes now; False if the console has gone."""
        try:
            session.write()
        except OSError:  # reset or broken pipe
            self._drop(session, "connection lost")
            return False
        return True

    def _serve(self, session: _RemoteSession) -> None:
        """Run the lines the console may have run, send its replies, watch its socket."""
        session.collect()
        while session.takes_lines():
            request = session.lines.next_request()
            if request is None:
                break
            if isinstance(request, Reply):
                session.slot().send(request)
            elif not session.authenticated:
                self._authenticate(session, request)
            else:
                session.last_request = time.monotonic()
                if request:
                    self.submit(request, session.slot())
                else:
                    session.slot().send(Reply(Status.OK, ""))
            if session.closed:
                return
            session.collect()
        if len(session.out) > MAX_SEND_BUFFER_BYTES:
            self._drop_slow_reader(session)
            return
        if not self._write(session):
            return
        if session.bye_queued and not session.out:
            self._drop(session, "closed")
            return
        # Tell the selector what this session waits for now.
        assert self._selector is not None
        events = (selectors.EVENT_READ if session.wants_to_read() else 0) | (
            selectors.EVENT_WRITE if session.out else 0
        )
        if events != session.events:
            if session.events:
                self._selector.unregister(session.sock)
            if events:
                self._selector.register(session.sock, events)
            session.events = events

    def _no_token_in_time(self, session: _RemoteSession) -> None:
        self._repeats.report(
            "no token",
            "Consoles disconnected for giving no token in time",
            logging.INFO,
            f"Console {session.peer} gave no token within {self.auth_timeout_s:g} s; "
            "disconnected it.",
        )
        text = f"No console token within {self.auth_timeout_s:g} s: disconnected."
        self._close_with(session, Reply(Status.BYE, text))

    def _close_idle(self, session: _RemoteSession) -> None:
        self._repeats.report(
            "idle",
            "Idle consoles disconnected",
            logging.INFO,
            f"Console {session.peer} sent no command for {self.idle_timeout_s:g} s; "
            "disconnected it.",
        )
        text = (
            f"Closed this console after {self.idle_timeout_s:g} s without a command. "
            "Connect again to carry on."
        )
        self._close_with(session, Reply(Status.BYE, text))

    def _drop_slow_reader(self, session: _RemoteSession) -> None:
        self._repeats.report(
            "slow reader",
            "Consoles dropped for not reading their replies",
            logging.WARNING,
            f"Dropped console {session.peer}: it did not read its replies ({len(session.out)} "
            f"bytes waiting, none taken for {time.monotonic() - session.last_sent:.1f} s).",
        )
        self._drop(session, "dropped")

    def _authenticate(self, session: _RemoteSession, line: str) -> None:
        token = self.factory.token
        assert token is not None
        word, _, given = line.partition(" ")
        now = time.monotonic()
        wait_s = self._throttle.wait_s(session.host, now) if word == "auth" else 0.0
        if wait_s > 0:
            self._repeats.report(
                "too early",
                "Console tokens refused unchecked (too soon after wrong ones)",
                logging.WARNING,
                f"Console {session.peer} gave a token {wait_s:.1f} s too soon after wrong ones "
                f"from {session.host}; refused it unchecked.",
            )
            text = (
                f"Too many wrong console tokens from {session.host}: the next one is checked "
                f"in {wait_s:.1f} s (each wrong token doubles the wait, up to "
                f"{self._throttle.max_delay_s:g} s)."
            )
            session.slot().send(Reply(Status.BYE, text))
        elif word == "auth" and tokens_match(token, given.strip()):
            self._throttle.succeeded(session.host)
            self._let_in(session)
        else:
            if word == "auth":
                failures, delay_s = self._throttle.failed(session.host, now)
                self._repeats.report(
                    "wrong token",
                    "Consoles that gave a wrong token",
                    logging.WARNING,
                    f"Console {session.peer} gave a wrong token ({failures} in a row from "
                    f"{session.host}); disconnected it. The next token from there is checked "
                    f"after {delay_s:.2f} s.",
                )
            else:
                self._repeats.report(
                    "no auth",
                    "Consoles that sent a command instead of their token",
                    logging.WARNING,
                    f"Console {session.peer} sent a command before its token; disconnected it.",
                )
            text = (
                "Wrong or missing console token. Give the node's token with "
                f"`snr-console HOST:PORT --token ...` or {TOKEN_ENV_VAR}, or, if the node "
                "has a secret, run the console with the same secret ($SNR_SECRET or "
                "the secret file; see docs/console.md)."
            )
            session.slot().send(Reply(Status.BYE, text))

    def _close_with(self, session: _RemoteSession, reply: Reply) -> None:
        """Queue what is ready and ``reply``, send what the socket takes now, and close."""
        session.collect()
        if not session.bye_queued:
            session.out += reply.encode()
        try:
            session.write()
        except OSError:
            pass  # it had gone already
        self._drop(session, "closed")

    def _drop(self, session: _RemoteSession, why: str) -> None:
        if self._sessions.pop(session.sock, None) is not None and session.events:
            assert self._selector is not None
            self._selector.unregister(session.sock)
        if session.authenticated:
            self.info("Console %s %s", session.peer, why)
        else:
            self.dbg("Console %s %s before giving its token", session.peer, why)
        session.closed = True
        session.sock.close()


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
