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
import os
import select
import selectors
import socket
import threading
import time
from typing import Any, Dict, Optional, Tuple

from snr.core import LoopFactory
from snr.core.checks.os_errors import explain_os_error
from snr.core.logs import RepeatFilter
from snr.prelude import AbstractNode, CommsError, ComponentName, ConfigError, Mode
from snr.std_mods.io.console_loop import ConsoleLoop
from snr.std_mods.io.console_protocol import (
    DEFAULT_CONSOLE_PORT,
    MAX_LINE_BYTES,
    TOKEN_ENV_VAR,
    ConsoleSession,
    Reply,
    Status,
    check_listen_policy,
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
        self._failures: Dict[str, Tuple[int, float]] = {}  # host -> (in a row, last failure)

    def wait_s(self, host: str, now: float) -> float:
        """How long ``host`` must still wait before its next token is checked."""
        entry = self._failures.get(host)
        if entry is None:
            return 0.0
        failures, last = entry
        if now - last > self.forget_after_s:
            del self._failures[host]
            return 0.0
        return max(0.0, last + self.delay_s(failures) - now)

    def delay_s(self, failures: int) -> float:
        """The wait after ``failures`` wrong tokens in a row."""
        return min(self.max_delay_s, self.first_delay_s * 2.0 ** min(failures - 1, 30))

    def failed(self, host: str, now: float) -> Tuple[int, float]:
        """Count a wrong token; the failures in a row and the wait before the next try."""
        entry = self._failures.pop(host, None)
        failures = 1 if entry is None or now - entry[1] > self.forget_after_s else entry[0] + 1
        if len(self._failures) >= self.max_addresses:  # forget the longest-quiet address
            del self._failures[min(self._failures, key=lambda h: self._failures[h][1])]
        self._failures[host] = (failures, now)
        return failures, self.delay_s(failures)

    def succeeded(self, host: str) -> None:
        """A right token: ``host`` starts afresh."""
        self._failures.pop(host, None)


class _RemoteSession:
    """One TCP console, served by the receiver loop's thread.

    Every request line gets a numbered `_ReplySlot`; whoever answers it (the
    node's thread for commands, the loop's thread for a refused line) fills
    the slot, and replies go out in request order, so a console always knows
    which reply answers which line. At most `MAX_UNANSWERED` requests wait for
    their replies; until some are sent, the console's lines wait in the
    socket (so a flood of commands costs the node nothing). Replies are sent
    without blocking from an output buffer that the loop thread drains.
    """

    def __init__(self, sock: socket.socket, address: Tuple[Any, ...], wake: socket.socket) -> None:
        self.sock = sock
        self.host = str(address[0])
        self.peer = f"{address[0]}:{address[1]}"
        self.authenticated = False
        self.closed = False
        self.leaving = False  # a BYE is due: run no more of this console's lines
        self.connected_at = self.last_request = self.last_sent = time.monotonic()
        self.events = 0  # what the selector watches for (0: not registered)
        self.out = bytearray()  # encoded replies not yet taken by the socket
        self.bye_queued = False  # the BYE is in `out`: close once it is sent
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
            pass  # the receiver is shutting down, or already has wake-ups to read

    @property
    def unanswered(self) -> int:
        """Requests whose replies have not gone to the output buffer yet."""
        return self._next_slot - self._next_to_send

    def takes_lines(self) -> bool:
        """True while this console may have another line run."""
        return (
            not self.leaving
            and self.unanswered < MAX_UNANSWERED
            and len(self.out) < _PAUSE_OUT_BYTES
        )

    def has_line_waiting(self) -> bool:
        """True when a line read from the socket waits to be run."""
        return b"\n" in self._inbox

    def wants_to_read(self) -> bool:
        """True when the socket should be read: lines are taken, none is waiting."""
        return self.takes_lines() and not self.has_line_waiting()

    def receive(self, data: bytes) -> None:
        """Keep bytes read from the socket until their lines are taken."""
        self._inbox += data

    def next_line(self) -> Tuple[bool, Optional[bytes]]:
        """``(True, line)`` for the next complete line (None: too long), else ``(False, None)``."""
        while True:
            newline = self._inbox.find(b"\n")
            if newline < 0:
                if len(self._inbox) > MAX_LINE_BYTES:
                    self._inbox.clear()
                    if not self._skipping_long_line:
                        self._skipping_long_line = True
                        return True, None
                return False, None
            line = bytes(self._inbox[:newline])
            del self._inbox[: newline + 1]
            if self._skipping_long_line:  # the tail of a line already refused
                self._skipping_long_line = False
                continue
            return True, line if len(line) <= MAX_LINE_BYTES else None

    def collect(self) -> None:
        """Move the replies that are ready, in order, to the output buffer."""
        while not self.bye_queued and self._next_to_send in self._ready:
            reply = self._ready.pop(self._next_to_send)
            self._next_to_send += 1
            if not self.out:
                self.last_sent = time.monotonic()  # the send clock starts now
            self.out += reply.encode()
            if reply.status is Status.BYE:
                self.bye_queued = True

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
        self.host = factory.host
        self.port = factory.port
        self.auth_timeout_s = factory.auth_timeout_s
        self.idle_timeout_s = factory.idle_timeout_s
        self._token = factory.token
        self._selector: Optional[selectors.BaseSelector] = None
        self._listener: Optional[socket.socket] = None
        self._wake_in: Optional[socket.socket] = None
        self._wake_out: Optional[socket.socket] = None
        self._sessions: Dict[socket.socket, _RemoteSession] = {}
        self._throttle = _TokenThrottle()
        self._repeats = RepeatFilter(self.log)
        self._last_summary = time.monotonic()

    # -- life cycle (node thread) -------------------------------------------
    def begin(self) -> None:
        """Listen on ``host:port`` and add the command processor."""
        try:
            listener = socket.create_server((self.host, self.port))
        except OSError as error:
            self._cannot_listen(error)
            return
        listener.setblocking(False)
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
        message = explain_os_error(
            error,
            action="listen",
            target=f"{self.host}:{self.port}",
            who=f"Console receiver {self.name!r}",
            setting="CommandReceiverFactory(port=...)",
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
        """Send what is queued and a goodbye to every console, then close all sockets.

        The goodbyes share one short deadline, so consoles that do not read
        cannot hold up the node's shutdown.
        """
        goodbye = Reply(Status.BYE, f"Node {self.parent.role!r} is stopping.").encode()
        sessions = list(self._sessions.values())
        for session in sessions:
            session.collect()
            if not session.bye_queued:
                session.out += goodbye
        deadline = time.monotonic() + _GOODBYE_TIMEOUT_S
        waiting = [s for s in sessions if s.out]
        while waiting and time.monotonic() < deadline:
            for session in list(waiting):
                try:
                    session.write()
                except OSError:
                    session.out.clear()  # it had gone already
                if not session.out:
                    waiting.remove(session)
            if waiting:
                select.select(
                    [], [s.sock for s in waiting], [], max(0.0, deadline - time.monotonic())
                )
        for session in sessions:
            session.close()
        self._sessions.clear()
        self._repeats.flush()
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
        """Wait for connections, lines and replies; handle what arrived; enforce the limits."""
        selector = self._selector
        if selector is None:  # begin() could not listen
            self.set_terminate_flag("not listening")
            return
        for key, mask in selector.select(timeout=self._next_wake_s(time.monotonic())):
            sock: Any = key.fileobj
            if sock is self._listener:
                self._accept()
            elif sock is self._wake_in:
                self._drain_wakeups()
            elif sock in self._sessions:
                session = self._sessions[sock]
                if mask & selectors.EVENT_READ:
                    self._read(session)
                if mask & selectors.EVENT_WRITE and not session.closed:
                    self._write(session)
        now = time.monotonic()
        for session in list(self._sessions.values()):
            self._serve(session)
        self._enforce_time_limits(now)
        if now - self._last_summary >= self._repeats.every_s:
            self._last_summary = now
            self._repeats.flush()  # counts of repeated warnings, even when they stopped

    def _next_wake_s(self, now: float) -> float:
        """Seconds until the nearest time limit (at most `_POLL_S`)."""
        wake = _POLL_S
        for session in self._sessions.values():
            if not session.authenticated:
                wake = min(wake, session.connected_at + self.auth_timeout_s - now)
            elif self.idle_timeout_s is not None:
                wake = min(wake, session.last_request + self.idle_timeout_s - now)
            if session.out:
                wake = min(wake, session.last_sent + _SEND_TIMEOUT_S - now)
        return max(0.005, wake)

    def _accept(self) -> None:
        assert self._listener is not None and self._wake_out is not None
        try:
            sock, address = self._listener.accept()
        except OSError:
            return  # the client gave up before we accepted, or nothing is waiting
        sock.setblocking(False)
        session = _RemoteSession(sock, address, self._wake_out)
        if self._token is None:
            if self._count_connected() >= MAX_CONSOLES:
                self._turn_away(session)
                return
            self._add(session)
            self._admit(session)
            return
        waiting = [s for s in self._sessions.values() if not s.authenticated]
        if len(waiting) >= MAX_WAITING_CONSOLES:
            oldest = min(waiting, key=lambda s: s.connected_at)
            self._repeats.report(
                "waiting full",
                "Consoles pushed out while waiting to give their token",
                logging.WARNING,
                "%d consoles are waiting to give their token, the most this receiver "
                "keeps; disconnected the oldest, %s, to make room.",
                MAX_WAITING_CONSOLES,
                oldest.peer,
            )
            self._close_with(
                oldest, Reply(Status.BYE, "Too many consoles are waiting to give their token.")
            )
        self._add(session)
        session.answer(Reply(Status.AUTH, "This node needs a console token: send `auth <token>`."))

    def _add(self, session: _RemoteSession) -> None:
        self._sessions[session.sock] = session
        self.dbg("Console %s connected", session.peer)

    def _count_connected(self) -> int:
        return sum(1 for s in self._sessions.values() if s.authenticated)

    def _admit(self, session: _RemoteSession) -> None:
        session.authenticated = True
        session.last_request = time.monotonic()
        session.answer(Reply(Status.HELLO, self.greeting()))
        self.info("Console %s connected", session.peer)

    def _turn_away(self, session: _RemoteSession) -> None:
        self._repeats.report(
            "full",
            "Consoles turned away (too many connected)",
            logging.WARNING,
            "Turned away console %s: %d are connected, the most this receiver serves.",
            session.peer,
            MAX_CONSOLES,
        )
        self._close_with(
            session, Reply(Status.BYE, f"Too many consoles ({MAX_CONSOLES}) are open.")
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
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            self._drop(session, "disconnected")
            return
        session.receive(data)

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
        while True:
            while not session.closed and session.takes_lines():
                got, raw = session.next_line()
                if not got:
                    break
                self._on_line(session, raw)
            if session.closed:
                return
            unanswered = session.unanswered
            session.collect()
            # A reply filled after this pass read its wake-up is collected here:
            # if that makes room for a line already read, run it now, or it would
            # wait for the next wake-up (up to _POLL_S) with nothing to bring it.
            if session.unanswered == unanswered or not session.has_line_waiting():
                break
        if len(session.out) > MAX_SEND_BUFFER_BYTES:
            self._drop_slow_reader(session)
            return
        if not self._write(session):
            return
        if session.bye_queued and not session.out:
            self._drop(session, "closed")
            return
        self._watch(session)

    def _watch(self, session: _RemoteSession) -> None:
        """Tell the selector what this session waits for now."""
        assert self._selector is not None
        events = (selectors.EVENT_READ if session.wants_to_read() else 0) | (
            selectors.EVENT_WRITE if session.out else 0
        )
        if events == session.events:
            return
        if session.events == 0:
            self._selector.register(session.sock, events, None)
        elif events == 0:
            self._selector.unregister(session.sock)
        else:
            self._selector.modify(session.sock, events, None)
        session.events = events

    def _enforce_time_limits(self, now: float) -> None:
        for session in list(self._sessions.values()):
            if session.closed:
                continue
            if session.out and now - session.last_sent > _SEND_TIMEOUT_S:
                self._drop_slow_reader(session)
            elif not session.authenticated and now - session.connected_at > self.auth_timeout_s:
                self._repeats.report(
                    "no token",
                    "Consoles disconnected for giving no token in time",
                    logging.INFO,
                    "Console %s gave no token within %g s; disconnected it.",
                    session.peer,
                    self.auth_timeout_s,
                )
                text = f"No console token within {self.auth_timeout_s:g} s: disconnected."
                self._close_with(session, Reply(Status.BYE, text))
            elif (
                self.idle_timeout_s is not None
                and session.authenticated
                and session.unanswered == 0
                and now - session.last_request > self.idle_timeout_s
            ):
                self._repeats.report(
                    "idle",
                    "Idle consoles disconnected",
                    logging.INFO,
                    "Console %s sent no command for %g s; disconnected it.",
                    session.peer,
                    self.idle_timeout_s,
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
            "Dropped console %s: it did not read its replies (%d bytes waiting, none "
            "taken for %.1f s).",
            session.peer,
            len(session.out),
            time.monotonic() - session.last_sent,
        )
        self._drop(session, "dropped")

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
            return
        session.last_request = time.monotonic()
        if not line:
            session.answer(Reply(Status.OK, ""))
        else:
            self.submit(line, session.slot())

    def _authenticate(self, session: _RemoteSession, line: str) -> None:
        assert self._token is not None
        word, _, given = line.partition(" ")
        now = time.monotonic()
        wait_s = self._throttle.wait_s(session.host, now) if word == "auth" else 0.0
        if wait_s > 0:
            self._repeats.report(
                "too early",
                "Console tokens refused unchecked (too soon after wrong ones)",
                logging.WARNING,
                "Console %s gave a token %.1f s too soon after wrong ones from %s; "
                "refused it unchecked.",
                session.peer,
                wait_s,
                session.host,
            )
            text = (
                f"Too many wrong console tokens from {session.host}: the next one is checked "
                f"in {wait_s:.1f} s (each wrong token doubles the wait, up to "
                f"{self._throttle.max_delay_s:g} s)."
            )
            session.answer(Reply(Status.BYE, text))
            return
        if word == "auth" and tokens_match(self._token, given.strip()):
            self._throttle.succeeded(session.host)
            if self._count_connected() >= MAX_CONSOLES:
                self._turn_away(session)
                return
            self._admit(session)
            return
        if word == "auth":
            failures, delay_s = self._throttle.failed(session.host, now)
            self._repeats.report(
                "wrong token",
                "Consoles that gave a wrong token",
                logging.WARNING,
                "Console %s gave a wrong token (%d in a row from %s); disconnected it. "
                "The next token from there is checked after %.2f s.",
                session.peer,
                failures,
                session.host,
                delay_s,
            )
        else:
            self._repeats.report(
                "no auth",
                "Consoles that sent a command instead of their token",
                logging.WARNING,
                "Console %s sent a command before its token; disconnected it.",
                session.peer,
            )
        session.answer(
            Reply(
                Status.BYE,
                "Wrong or missing console token. Give the node's token with "
                f"`snr-console HOST:PORT --token ...` or {TOKEN_ENV_VAR}.",
            )
        )

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
            session.events = 0
        if session.authenticated:
            self.info("Console %s %s", session.peer, why)
        else:
            self.dbg("Console %s %s before giving its token", session.peer, why)
        session.close()


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
        if token is None:
            token = os.environ.get(TOKEN_ENV_VAR) or None
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
