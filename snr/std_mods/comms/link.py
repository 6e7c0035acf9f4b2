"""`Link`: one live connection to one peer node, over a `Transport`.

A `Link` owns a *transport* (a TCP socket or a pipe end, see `Transport`) and
an `Outbox` (``outbox.py``) of frames waiting to be written, and has no thread of its own:
the node's one `IOLoop` thread reads the transport when bytes arrive
(cutting them into frames and handing pages to its `CommsLoop`, in
``comms_loop.py``) and writes queued frames when the transport has room, for
every link of the node together.

Example (a `CommsLoop` opens its links with ``open_link``)::

    link = comms_loop.open_link(transport)
    link.send(encode_page(page), key=page.key)
    link.close()              # flush, then end the connection
"""

from __future__ import annotations

import enum
import logging
import selectors
import struct
import threading
import time
from typing import (
    TYPE_CHECKING,
    Any,
    Dict,
    List,
    Optional,
    Protocol,
    Set,
)

from snr.core.logs import LossReport
from snr.prelude import CommsError, DataKey, Page, WireFormatError
from snr.std_mods.comms.handshake import Handshake, Refused
from snr.std_mods.comms.io_loop import IOLoop, IOTimer
from snr.std_mods.comms.link_hints import watch_link
from snr.std_mods.comms.outbox import CLOSED, FIRST, Outbox
from snr.std_mods.comms.wire import (
    Beat,
    Bye,
    FrameDecoder,
    Hello,
    Message,
    Proof,
    encode_beat,
    encode_bye,
)

if TYPE_CHECKING:
    from snr.std_mods.comms.comms_loop import CommsLoop

try:  # Linux and macOS say how many bytes wait unread; Windows has no fcntl
    import fcntl
    import termios

    _FIONREAD: Optional[int] = termios.FIONREAD
except ImportError:
    _FIONREAD = None

__all__ = ["Link", "LinkState", "Transport", "shown_role", "unread_bytes"]

_WRITE_NOW_BYTES = 64 * 1024  # the node's thread writes a backlog this big before it goes idle
_BURST_S = 0.0002  # a frame this soon after the last send joins a batch for the I/O thread
_TICK_S = 0.25  # the shortest wait between two looks at a link's beat, silence and drops
_LATE_S = 0.001  # a look at a deadline comes just after it, so the limit has passed
_READ = selectors.EVENT_READ
_WRITE = selectors.EVENT_WRITE
_MAX_KEYS_NOTED = 1000  # DEBUG: how many received keys a link remembers for the hints
_PROGRESS_BYTES = 16 * 1024  # this much of a frame still arriving is a sign of life (a big frame)
_SHOWN_ROLE_CHARS = 60  # a peer's role in log lines is cut to this many characters


def shown_role(role: str) -> str:
    """A peer's role as log lines show it: quoted, and cut short if it is long.

    A role is whatever the peer's hello said; a hostile or broken peer may
    send megabytes of it, which must not be copied into every log line.

    Example::

        shown_role("urov")        # "'urov'"
        shown_role("x" * 5000)    # "'xxx…xxx'… (5,000 characters)"
    """
    if len(role) <= _SHOWN_ROLE_CHARS:
        return repr(role)
    return f"{role[:_SHOWN_ROLE_CHARS]!r}… ({len(role):,} characters)"


def unread_bytes(fd: int) -> Optional[int]:
    """How many received bytes wait unread in the OS for ``fd``; None where it cannot say.

    A socket or pipe that is not read keeps what arrives; a link whose node is
    behind uses this to tell a peer that still talks from one that fell silent.

    Example::

        unread_bytes(sock.fileno())   # 0 when nothing waits
    """
    if _FIONREAD is None:
        return None
    try:
        answer = fcntl.ioctl(fd, _FIONREAD, b"\0\0\0\0")
    except OSError:
        return None
    return int(struct.unpack("i", answer)[0])


class Transport(Protocol):
    """A byte stream to one peer that the node's `IOLoop` can watch: a TCP socket or a pipe.

    Every method returns at once (the file descriptor is non-blocking): the
    loop calls ``recv_into`` when ``fileno()`` is readable and ``send`` when
    it is writable, and the node's thread may call ``send`` too (under the
    outbox's lock) to write a frame straight away.

    Example: ``SocketTransport(sock, "127.0.0.1:9000")`` in ``sockets.py``.
    """

    peer: str
    """Where the peer is, for log messages, e.g. ``"127.0.0.1:9000"``."""

    def fileno(self) -> int:
        """The file descriptor the I/O loop watches."""

    def send(self, data: bytes) -> int:
        """Write what fits without blocking; how many bytes went.

        Raises BlockingIOError if nothing fits, another OSError if the peer is gone.
        """

    def recv_into(self, buffer: bytearray) -> int:
        """Read what has arrived into ``buffer``; 0 at end of stream.

        Raises BlockingIOError if nothing has arrived, another OSError if the link broke.
        """

    def end_writing(self) -> None:
        """Tell the peer nothing more will be sent (after a graceful flush)."""

    def close(self) -> None:
        """Release the socket or pipe."""


class LinkState(enum.Enum):
    """Where a link is in its life: one value, moved by the methods named below.

    ======== ================================================ ==========================
    state    the link                                         moves on to
    ======== ================================================ ==========================
    HELLO    waits for the peer's hello (and proof, with a    OPEN, ENDING, CLOSED
             secret): sends no page, takes none
    OPEN     sends pages, reads, beats, judges silence        CLOSING, ENDING, CLOSED
    CLOSING  ``close()``: writes what waits, then a bye       DRAINING, ENDING, CLOSED
    DRAINING all written, half-closed: reads what still comes CLOSED (after ``drain_s``)
    ENDING   ``abort()``, or the node's thread found the end: CLOSED (on the I/O thread)
             no more reads; the I/O thread finishes it
    CLOSED   transport closed, the `CommsLoop` told           (the end)
    ======== ================================================ ==========================

    Whether the link reads is the one other thing that changes: it stops
    while pages it read wait for room in the node's queue (``Link._held``).

    A link whose node names no system and has no secret starts OPEN (as
    older SNR did); any other starts in HELLO (docs/comms.md, "Who may connect").

    Example::

        link.state is LinkState.OPEN
    """

    HELLO = "hello"
    OPEN = "open"
    CLOSING = "closing"
    DRAINING = "draining"
    ENDING = "ending"
    CLOSED = "closed"


_OPEN, _CLOSING, _DRAINING = LinkState.OPEN, LinkState.CLOSING, LinkState.DRAINING
_HELLO = LinkState.HELLO
_LIVE = (LinkState.HELLO, LinkState.OPEN)  # looked at on a clock (silence, beats, handshake)
_ENDED = (LinkState.ENDING, LinkState.CLOSED)  # no more reading or writing


class Link:
    """One live connection to one peer, served by the node's `IOLoop` (no thread of its own).

    The I/O loop reads the link's transport when bytes arrive, cuts them into
    frames and hands pages to the `CommsLoop`; it writes queued frames when
    the transport has room. The link ends on the loop's thread when the peer
    goes away, a bad length header arrives, the peer falls silent, or the
    link is closed or aborted: it closes the transport and tells the
    `CommsLoop`.

    Liveness: both sides promise a sign of life in their hello (``beat_s``)
    and a link that has sent nothing for that long sends a beat frame. A sign
    of life is a whole frame, or 16 KiB more of one still arriving (a big
    page on slow Wi-Fi): a byte now and then does not keep a link open, and
    a connection with no well-formed frame (not even a hello) within
    ``hello_timeout_s`` is closed, unless its first frame is still arriving.
    A peer that promised beats and is then not heard from for
    ``max(dead_after_s, 3 * its beat_s)`` is declared lost — also while pages
    flow the other way, which is when a Wi-Fi link usually dies — and the
    log says how many pages may have been lost with it.

    Goodbye: a link closed in order (its node is stopping) sends a bye frame
    last, to a peer whose hello said it understands one, so that peer logs
    the end as news rather than as a lost link.

    Backpressure: while the node's queue is over its high-water mark the
    link stops reading (the bytes wait in the OS and TCP slows the sender)
    and reads on once there is room; the I/O thread never waits for it.
    Meanwhile bytes piling up in the OS are the peer's sign of life, and a
    peer that sends nothing at all while nothing waits is judged silent as
    usual; bytes that wait without growing (its last words, or a buffer so
    full it cannot send) are judged once they are read.

    Example::

        link = Link(comms_loop, transport)
        link.start()
        link.send(encode_page(page), key=page.key)
        link.close()              # flush, then end the connection

    Attributes:
        pages_sent: pages handed to the transport or queued for it.
        pages_received: pages that arrived.
        keys_received: in DEBUG mode, the keys of the pages that arrived (up to
            1,000, for the hints of ``link_hints.py``); None otherwise.
        went_silent: the link was closed because the peer fell silent.
        refusal: why the peer was refused (another system, no or a wrong
            secret, a page before the handshake ended), or None.
        announced: the link reached OPEN and COMMS_CONNECTED was scheduled.
        peer_said_bye: the peer sent a bye: the end that follows is orderly.
        loss: the `LossReport` of pages dropped because the peer fell behind.
    """

    flush_timeout_s: float = 1.0
    drain_s: float = 0.25  # after a graceful half-close, how long to read what still comes

    def __init__(self, owner: CommsLoop, transport: Transport) -> None:
        io = owner.io_loop
        if io is None:
            raise CommsError(
                f"Cannot open a link for comms component {owner.name!r}: it is not running "
                "(it was never started, or it has stopped)."
            )
        self.owner = owner
        self.io: IOLoop = io
        self.log = owner.log
        self.beat_s = owner.beat_s  # how often a quiet link sends a beat (its hello says so)
        self.hello_timeout_s = owner.hello_timeout_s
        self.dead_after_s = owner.dead_after_s
        self.recovered_after_s = owner.recovered_after_s
        self.transport = transport
        self.peer_role: Optional[str] = None
        self.hello_at: Optional[float] = None  # when the peer's hello arrived
        self.peer_beat_s: Optional[float] = None
        self.state = LinkState.OPEN
        self.bad_frames = 0
        self.went_silent = False
        self.refusal: Optional[Refused] = None
        self.announced = False
        self.peer_said_bye = False
        self._peer_takes_bye = False  # its hello said it understands a bye frame
        self.pages_sent = 0
        self.pages_received = 0
        self.keys_received: Optional[Set[DataKey]] = None  # noted in DEBUG (link_hints.py)
        self.opened_at = time.monotonic()
        self.last_heard = self.opened_at
        self._heard_frame = False  # a well-formed frame has arrived (for the hello timeout)
        self._progress = 0  # bytes of a frame still arriving, since the peer was last heard
        self._progress_at = self.opened_at  # when they last added up to _PROGRESS_BYTES (or opened)
        self._sent_when_heard = 0
        self.loss = LossReport(
            owner.log,
            f"pages for {transport.peer}",
            "the peer is not taking them as fast as they are stored "
            f"({owner.max_backlog_bytes // 1024:,} KiB wait to be sent; the newest page "
            "under each key is kept)",
        )
        self._closed = threading.Event()
        # These belong to the I/O loop's thread (set before the hello, which may wake it).
        self._decoder = FrameDecoder()
        self._unread_seen = 0  # while paused: bytes the OS held for us at the last look
        # Decoded while the node was behind, delivered first; while any wait,
        # the link reads no more.
        self._held: List[Page] = []
        self._timer: Optional[IOTimer] = None
        self._tick_s = min(_TICK_S, owner.beat_s / 4)
        self._answer_due = False  # the peer was heard since the last send: answer at once
        self.outbox = Outbox(owner.max_backlog_bytes, self.loss)
        self.handshake = Handshake(owner.parent.role, owner.side, owner.system, owner.secret)
        if self.handshake.needed:  # no page passes either way until the peer is judged
            self.state = LinkState.HELLO
        self.outbox.put(self.handshake.hello_frame(self.beat_s))

    @property
    def label(self) -> str:
        """The peer for log lines: ``"'receiver' at 127.0.0.1:9000"``."""
        if self.peer_role:
            return f"{shown_role(self.peer_role)} at {self.transport.peer}"
        return self.transport.peer

    @property
    def peer_name(self) -> str:
        """The peer's role for log lines (quoted, cut short), or ``"unknown"`` before its hello.

        Example::

            link.peer_name   # "'urov'"
        """
        return shown_role(self.peer_role) if self.peer_role else "unknown"

    def fileno(self) -> int:
        """The transport's file descriptor (what the I/O loop watches)."""
        return self.transport.fileno()

    def start(self) -> None:
        """Hand the link to the node's I/O loop, which sends the hello and starts reading."""
        self.io.call_soon(self._attach)

    def send(self, frame: bytes, now: bool = True, key: Optional[DataKey] = None) -> bool:
        """Send or queue a page's ``frame`` (node thread); False if the link is not open.

        If the backlog is full, older frames make room (see `Outbox`): they
        are counted and reported (at most once a second).
        """
        if self.state is not _OPEN:
            return False
        outbox = self.outbox
        # A frame right behind another (a burst) waits for one joined send
        # (a burst of pages then costs a few system calls instead of one
        # each). A frame after a pause goes at once, and so does one sent
        # after the peer was heard (a reply: a fast ping-pong would otherwise
        # look like a burst and pay a trip through the I/O thread every time).
        write = None
        if now and (self._answer_due or time.monotonic() - outbox.last_sent_at >= _BURST_S):
            self._answer_due = False
            write = self.transport.send
        outcome = outbox.put(frame, key, write)
        if outcome == CLOSED:
            return False
        self.pages_sent += 1
        if outcome == FIRST:
            self._wake_writer()
        elif outbox.queued_bytes >= _WRITE_NOW_BYTES and not self.io.events(self) & _WRITE:
            self.write_waiting()  # a long burst: do not wait for the node to go idle
        return True

    def send_burst(self, frames: List[bytes], key: DataKey) -> None:
        """`send` for the frames of a run of pages under ``key`` (node thread), with one lock.

        They leave when the node's thread next goes idle, or at once once
        64 KiB wait.

        Example::

            link.send_burst([encode_page(page) for page in pages], "depth")
        """
        if self.state is not _OPEN:
            return
        outbox = self.outbox
        outcome = outbox.put_all(frames, key)
        if outcome == CLOSED:
            return
        self.pages_sent += len(frames)
        if outcome == FIRST:
            self._wake_writer()
        elif outbox.queued_bytes >= _WRITE_NOW_BYTES and not self.io.events(self) & _WRITE:
            self.write_waiting()

    def close(self) -> None:
        """Send what is queued and a goodbye, then end the connection (graceful)."""
        if self.state is _HELLO:  # no page was sent yet: nothing to flush
            self.abort("the link was closed during its handshake")
        elif self.state is _OPEN:
            self.state = _CLOSING
            if self._peer_takes_bye:  # older peers never get a frame they do not know
                outcome = self.outbox.put(encode_bye(), None, self.transport.send)
                if outcome == FIRST:
                    self._wake_writer()
            self.outbox.close()
            self.io.call_soon(self._flush_then_end)

    def abort(self, reason: str = "the link was closed") -> None:
        """End the connection now, dropping what is queued; ``reason`` goes in the log line."""
        if self.state not in _ENDED:
            self.state = LinkState.ENDING
            self.outbox.close(discard=True)
            self.io.call_soon(lambda: self._finish(reason))

    def is_closed(self) -> bool:
        """True once the link has ended and the transport is closed."""
        return self._closed.is_set()

    def wait_closed(self, timeout_s: Optional[float]) -> bool:
        """Wait up to ``timeout_s`` for the link to close; True if it has."""
        return self._closed.wait(timeout_s)

    def stats(self) -> Dict[str, Any]:
        """The link's counters, e.g. for the console's ``stats`` command.

        Example::

            link.stats()["dropped"]   # pages dropped because the peer fell behind
        """
        return {
            "peer": self.label,
            "state": self.state.value,
            "pages_sent": self.pages_sent,
            "pages_received": self.pages_received,
            "dropped": self.outbox.dropped,
            "dropped_by_key": dict(self.outbox.dropped_by_key),
            "waiting_frames": len(self.outbox),
            "waiting_bytes": self.outbox.queued_bytes,
            "bad_frames": self.bad_frames,
            "heard_s_ago": round(time.monotonic() - self.last_heard, 3),
        }

    # -- I/O loop thread: life ------------------------------------------------
    def _attach(self) -> None:
        if self.state in _ENDED:  # aborted before the loop got to it
            return
        self.io.watch(self, _READ)
        self._timer = self.io.call_later(self.hello_timeout_s + _LATE_S, self._tick)
        self.on_writable()  # the hello goes at once

    def _wake_writer(self) -> None:
        # Any thread, when the outbox stops being empty. Another thread than
        # the loop's (the node's, storing a burst) writes it itself before it
        # sleeps, or the loop's thread a moment later (IOLoop.write_soon).
        if self.io.in_loop_thread():
            self._want_write()
        else:
            self.io.write_soon(self)

    def write_waiting(self) -> None:
        """Write queued frames now without blocking (not on the loop's thread).

        What does not fit is left to the loop's thread, which writes it when
        the transport has room. Frames leave in order either way (the
        outbox's lock); after the link has ended the outbox is empty, so
        nothing is written to a closed transport.
        """
        if not len(self.outbox):
            return
        try:
            done = self.outbox.write_to(self.transport.send)
        except OSError:  # broken: the loop's thread finds out and ends the link
            done = False
        if not done:
            self.io.call_soon(self._want_write)

    def _want_write(self) -> None:
        if self.state not in _ENDED and len(self.outbox):
            self.io.watch(self, self.io.events(self) | _WRITE)

    def _flush_then_end(self) -> None:
        if self.state is _CLOSING and not len(self.outbox):
            self._end_writing()

    def _end_writing(self) -> None:
        """CLOSING, everything sent: half-close, then read what still comes for a moment."""
        if self.state is not _CLOSING:
            return
        self.state = _DRAINING
        self.transport.end_writing()
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self.io.call_later(self.drain_s, lambda: self._finish("the link was closed"))

    def _tick(self) -> None:
        """At the link's next deadline: is the peer still there, and do we owe it a beat?"""
        self._timer = None
        if self.state in _ENDED:
            return
        silence = self._silence_while_paused() if self._held else self._silence()
        if silence is not None:
            self._finish(silence)
            return
        if self.state in _LIVE:
            if (
                self.state is _OPEN
                and self.peer_beat_s is not None
                and not len(self.outbox)
                and time.monotonic() - self.outbox.last_sent_at >= self.beat_s
            ):
                outcome = self.outbox.put(encode_beat(), None, self.transport.send)
                if outcome == FIRST:  # quiet for beat_s: a sign of life, written later
                    self._want_write()
            self._check_recovered()
            self._timer = self.io.call_later(self._next_look_s(), self._tick)

    def _look_again(self) -> None:
        """Loop thread: put the next look at the link's first deadline (they moved)."""
        if self._timer is not None and self.state in _LIVE:  # (else it is the drain's timer)
            self._timer.cancel()
            self._timer = self.io.call_later(self._next_look_s(), self._tick)

    def _next_look_s(self) -> float:
        """Seconds until the link must be looked at again: its first deadline.

        A quiet link wakes its I/O thread once a beat, not four times: the
        deadlines are when a beat is owed, when the peer's silence (or the
        wait for its first frame) passes the limit, and, every quarter beat,
        while pages are held or dropped (their counts move without a frame).
        A deadline already past (a beat held back by frames still waiting)
        is looked at again a quarter beat later.
        """
        now = time.monotonic()
        if self._held or self.loss.dropping:
            return self._tick_s
        due = []
        if not self._heard_frame:
            due.append(self._progress_at + self.hello_timeout_s)
        if self.state is _HELLO:
            due.append(self.opened_at + self.hello_timeout_s)
        if self.peer_beat_s is not None:
            due.append(self.outbox.last_sent_at + self.beat_s)
            due.append(self.last_heard + max(self.dead_after_s, 3 * self.peer_beat_s))
        if not due:
            return self._tick_s
        wait_s = min(due) + _LATE_S - now
        return wait_s if wait_s > 0 else self._tick_s

    def _check_recovered(self) -> None:
        # The peer has caught up once everything queued went out and nothing
        # was dropped for a while (a second by default).
        if self.loss.dropping and not len(self.outbox):
            self.loss.recovered(quiet_s=self.recovered_after_s)

    def on_io_stop(self) -> None:
        """The I/O loop is stopping: end the link now."""
        self._finish("the node stopped")

    def _end(self, reason: str) -> None:
        """End the link: at once on the I/O loop's thread, else soon, by that thread."""
        if self.io.in_loop_thread():
            self._finish(reason)
        else:  # the node's thread, reading while idle, leaves it to the loop's
            self.state = LinkState.ENDING  # and reads it no more meanwhile
            self.io.call_soon(lambda: self._finish(reason))

    def _finish(self, reason: str) -> None:
        """Any state → CLOSED, on the I/O thread: close the transport, tell the `CommsLoop`."""
        if self.state is LinkState.CLOSED:
            return
        with self.io.read_role():  # nobody reads the socket while it closes
            if self.peer_said_bye:
                reason = "it said goodbye (its node is stopping)"
            elif self.state in (_CLOSING, _DRAINING) and not self.went_silent:
                reason = reason if reason.startswith("the peer") else "the link was closed"
            self.state = LinkState.CLOSED
            self.outbox.close(discard=True)
            if self._timer is not None:
                self._timer.cancel()
            self.io.forget(self)
            self._drain_unread()
            try:
                self.transport.close()
            except OSError:
                pass
        self.loss.ended("the link ended")  # drops not yet in the log are said now
        self._closed.set()
        self.owner.link_closed(self, reason)

    def _drain_unread(self) -> None:
        # Closing a socket with unread bytes makes the OS reset the connection,
        # and the peer may then lose what it has not read of ours yet.
        for _ in range(16):
            try:
                if not self.transport.recv_into(self.io.buffer):
                    return
            except OSError:
                return

    # -- I/O loop thread: writing ---------------------------------------------
    def on_writable(self) -> None:
        """Write what is queued; stop watching for room once it is all out."""
        try:
            self._write()
        except Exception as error:  # a bug must not kill the node silently
            self._failed(error)

    def on_readable(self) -> None:
        """Read what arrived, cut it into frames, hand the pages on."""
        try:
            self._read()
        except Exception as error:  # a bug must not kill the node silently
            self._failed(error)

    def _failed(self, error: Exception) -> None:
        self.log.exception("Link to %s failed", self.label)
        self._end(f"unexpected {type(error).__name__}: {error}")

    def _write(self) -> None:
        if self.state in _ENDED:
            return
        try:
            done = self.outbox.write_to(self.transport.send)
        except OSError as error:
            self._finish(f"{type(error).__name__}: {error}")
            return
        if done:
            events = self.io.events(self)
            if events & _WRITE:
                self.io.watch(self, events & ~_WRITE)
            self._check_recovered()
            if self.state is _CLOSING:
                self._end_writing()
        else:
            if not self.io.events(self) & _WRITE:
                self.io.watch(self, self.io.events(self) | _WRITE)

    # -- I/O loop thread: reading ---------------------------------------------
    def _read(self) -> None:
        # On the thread that holds the read role: the I/O loop's, or the
        # node's while it is idle. Everything else (ending the link, pausing)
        # is left to the loop's thread.
        if self.state in _ENDED or self._held:
            return
        try:
            count = self.transport.recv_into(self.io.buffer)
        except BlockingIOError:
            return
        except OSError as error:
            self._end(f"{type(error).__name__}: {error}")
            return
        decoder = self._decoder
        if not count:
            if decoder.pending_bytes():
                self._bad_frame(
                    WireFormatError(
                        "the connection ended in the middle of a frame "
                        f"({decoder.pending_bytes()} bytes of it arrived)"
                    )
                )
            self._end("the peer closed the connection")
            return
        self._answer_due = True
        bodies: List[bytes] = []
        pages: List[Page] = []
        try:
            decoder.cut_frames(self.io.view[:count].tobytes(), bodies)
        except WireFormatError as error:  # a bad length: the stream is lost
            self._decode_bodies(bodies, pages)
            self._bad_frame(error, resetting=True)
            self._deliver(pages)
            self._end(f"reset after a bad frame ({error})")
            return
        if bodies:  # a sign of life is a whole frame (wire format 3.3)...
            self._heard(time.monotonic())
        else:  # ...or 16 KiB more of one still arriving (a big page on slow Wi-Fi)
            self._progress += count
            if self._progress >= _PROGRESS_BYTES:
                self._progress_at = now = time.monotonic()
                self._heard(now)
        self._decode_bodies(bodies, pages)
        if pages and self.state not in _ENDED:  # (a refused peer's pages are not stored)
            self._heard_frame = True
            self._deliver(pages)

    def _heard(self, now: float) -> None:
        # A byte now and then (a peer that trickles) adds up to 16 KiB too
        # slowly to keep a link open: the silence limit passes first.
        self.last_heard = now
        self._sent_when_heard = self.pages_sent
        self._progress = 0

    def _decode_bodies(self, bodies: List[bytes], pages: List[Page]) -> None:
        """Decode each frame body: pages go to ``pages``, hellos and byes are acted on."""
        decode = self.owner.decode_message
        for body in bodies:  # every frame received passes here: a page is the usual case
            try:
                message = decode(body)
            except WireFormatError as error:
                if self.state is _HELLO:  # before the handshake ends, a bad frame ends it
                    self._refuse(Refused("order", f"a bad frame before its hello: {error}"))
                    return
                self._bad_frame(error)
                continue
            except Exception as error:  # a bug in decoding: say so, and lose no other frame
                self.log.exception("Decoding a frame from %s failed", self.label)
                self._bad_frame(WireFormatError(f"it could not be decoded ({error!r:.80})"))
                continue
            if message.__class__ is Page and self.state is not _HELLO:
                pages.append(message)
            else:
                self._on_message(message)
                if self.state in _ENDED:  # refused: nothing more it sent is looked at
                    pages.clear()
                    return

    def _deliver(self, pages: List[Page]) -> None:
        if not pages:
            return
        self.pages_received += len(pages)
        noted = self.keys_received
        if noted is not None and len(noted) < _MAX_KEYS_NOTED:
            if len(pages) == 1:  # the usual read: one page
                noted.add(pages[0].key)
            else:
                noted.update([page.key for page in pages])
        if self._held or not self.owner.parent.wait_for_room(0):
            # The node is behind: keep these, read no more until it has room
            # (from now on, on either thread: _read sees them held).
            first = not self._held
            self._held.extend(pages)
            if first and self.io.in_loop_thread():
                self._stop_reading()
            elif first:
                self.io.call_soon(self._stop_reading)
            return
        self.owner.deliver(self, pages)

    def _stop_reading(self) -> None:
        if self.state not in _ENDED:
            self.io.watch(self, self.io.events(self) & ~_READ)
            self._unread_seen = 0
            self.io.when_room(self._resume)

    def _resume(self) -> None:
        if self.state in _ENDED:
            return
        if self._note_unread() != 0:  # what waits is read next: news of the peer
            self.last_heard = time.monotonic()
        held, self._held = self._held, []
        if held:
            self.owner.deliver(self, held)
        self.io.watch(self, self.io.events(self) | _READ)

    def _note_unread(self) -> Optional[int]:
        """Bytes waiting unread in the OS (None if it cannot say); more than last time is life."""
        unread = unread_bytes(self.transport.fileno())
        if unread is not None:
            if unread > self._unread_seen:  # the peer sent something while we did not read
                self.last_heard = time.monotonic()
            self._unread_seen = unread
        return unread

    def _silence_while_paused(self) -> Optional[str]:
        """`_silence` for a link that does not read (its node is behind).

        Bytes that arrive meanwhile are life. Bytes that wait but do not
        grow may be the peer's last words or a full buffer stopping it: the
        silence is judged once they are read. Nothing waiting, and nothing
        arriving for the silence limit, is a dead path as when reading.
        """
        unread = self._note_unread()
        if unread is None or unread:
            return None
        return self._silence()

    def _silence(self) -> Optional[str]:
        """Why the link is lost if the peer has been quiet too long, else None."""
        quiet_s = time.monotonic() - self.last_heard
        limit_s = self.hello_timeout_s
        if self.state is _HELLO and time.monotonic() - self.opened_at > limit_s:
            return f"it did not finish the hello (and proof) within {limit_s:g} s of connecting"
        # Nothing well-formed yet, and no big first frame still coming in steadily:
        if not self._heard_frame and time.monotonic() - self._progress_at > limit_s:
            return (
                f"it sent no well-formed frame, not even a hello, within {limit_s:g} s "
                "of connecting"
            )
        if self.peer_beat_s is None:
            return None  # a peer that promised no beats may be quiet for ever
        limit = max(self.dead_after_s, 3 * self.peer_beat_s)
        if quiet_s <= limit:
            return None
        at_risk = self.pages_sent - self._sent_when_heard
        self.went_silent = True
        return (
            f"nothing heard from it for {quiet_s:.1f} s, though it promised a sign of life "
            f"every {self.peer_beat_s:g} s (the network path is gone, or the peer froze); "
            f"{at_risk} pages sent since it was last heard from may be lost"
        )

    def _on_message(self, message: Message) -> None:
        """A frame that is not a page (or a page before the handshake ended)."""
        self._heard_frame = True
        if self.state is _HELLO and not isinstance(message, (Hello, Proof, Beat, Bye)):
            what = "a page" if isinstance(message, Page) else "a frame"
            self._refuse(Refused("order", f"it sent {what} before the handshake ended"))
            return
        if isinstance(message, Proof):
            if self.state is not _HELLO:  # once open, a proof is a mistake, not a danger
                self._bad_frame(WireFormatError("a proof frame after the handshake ended"))
                return
            try:
                self.handshake.on_proof(message)
            except Refused as refusal:
                self._refuse(refusal)
                return
            self._handshake_done()
            return
        if isinstance(message, Hello):
            if self.peer_role is not None:  # said once per connection; more is a mistake
                if message.role != self.peer_role:
                    self._bad_frame(
                        WireFormatError(
                            f"a second hello, from role {shown_role(message.role)}; this "
                            f"connection is {shown_role(self.peer_role)}'s and stays so"
                        )
                    )
                return
            self.peer_role = message.role
            self.peer_beat_s = message.beat_s
            self._peer_takes_bye = message.bye
            try:
                proof = self.handshake.on_hello(message)
            except Refused as refusal:
                self._refuse(refusal)
                return
            # our answer to its challenge, if it sent one; its answer comes next
            if proof is not None and self.outbox.put(proof, None, self.transport.send) == FIRST:
                self._want_write()
            if self.handshake.done:
                self._handshake_done()
        elif isinstance(message, Bye):
            self.peer_said_bye = True

    def _handshake_done(self) -> None:
        """The peer is one of ours: pages may pass (HELLO → OPEN), say so once."""
        self.hello_at = time.monotonic()
        if self.state is _HELLO:
            self.state = _OPEN
            self.owner.announce(self)
        self.io.call_soon(self._look_again)  # beats are owed from now on
        self.owner.on_hello(self)
        watch_link(self.owner, self)

    def _refuse(self, refusal: Refused) -> None:
        """The peer may not link here: say why (once per peer), count it, close the connection.

        Nothing it sent is stored: pages read with the refused frame are dropped.
        """
        if self.state in _ENDED:
            return
        self.refusal = refusal
        self.owner.on_refused(self, refusal)
        self.abort(f"refused: {refusal.reason}")

    def _bad_frame(self, error: WireFormatError, resetting: bool = False) -> None:
        # Counted by the component, not per link: sixty hostile connections
        # must not write five lines each (at most five a 5 s, then a count).
        self.bad_frames += 1
        what = "reset the connection" if resetting else "dropped the frame"
        count = self.bad_frames
        more = f"; {count} bad frames from this peer so far" if count > 1 else ""
        self.owner.say_bad_frame(
            "Connections reset after a bad frame" if resetting else "Bad frames",
            logging.WARNING,
            "Bad frame from %s: %s (%s; the node keeps running%s; see docs/wire-format.md)",
            self.label,
            error,
            what,
            more,
        )
