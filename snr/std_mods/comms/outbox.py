"""`Outbox`: the frames waiting for one peer, for every link (TCP, pipe, serial).

Bounded in bytes; when full, the newest per key wins; every drop is counted
and reported; ``put`` never blocks. The policy, and why, is in
docs/design.md, "One outbox for every link".

Example::

    outbox = Outbox(max_bytes=64, loss=LossReport(log, "lines", "the board is not reading"))
    outbox.put(b"speed 1\n", key="speed")     # "first": queued, and the outbox was empty
    outbox.put(b"speed 2\n", key="speed")     # "queued"
    outbox.write_to(sock.send)                # True once everything is written
"""

from __future__ import annotations

import collections
import threading
import time
from typing import Callable, Deque, Dict, List, Optional

from snr.core.logs import LossReport
from snr.prelude import DataKey

__all__ = ["CLOSED", "FIRST", "QUEUED", "SENT", "Outbox", "Write"]

SENT = "sent"
"""`Outbox.put`: written to the peer at once."""

FIRST = "first"
"""`Outbox.put`: queued into an empty outbox (the caller wakes its writer)."""

QUEUED = "queued"
"""`Outbox.put`: queued behind other frames (a writer is on its way)."""

CLOSED = "closed"
"""`Outbox.put`: not taken, the outbox is closed."""

Write = Callable[[bytes], int]
"""Writes what fits now and says how many bytes went (``socket.send``); BlockingIOError if none."""

MAX_CHUNK_BYTES = 1024 * 1024
"""``write_to`` joins waiting frames into chunks up to this size: one system call for many."""


class _Entry:
    """One waiting frame: its key (None: never pushed out) and its bytes (None once gone)."""

    __slots__ = ("data", "key")

    def __init__(self, key: Optional[DataKey], data: Optional[bytes]) -> None:
        self.key = key
        self.data = data


class Outbox:
    """Frames waiting to be written to one peer, oldest first; bounded, newest per key wins.

    When a new frame does not fit, it pushes out the oldest frame waiting
    under its own key, or, if its key has none waiting, the oldest of the key
    with the most waiting: a flood under one key never pushes out the last
    value of another. Frames with no key are never pushed out.

    Safe from any thread: every change happens under one lock, and so does
    every write (``put`` with ``write``, ``write_to``), so frames leave in
    the order they were put and each whole.

    Example::

        outbox = Outbox(1024, loss)
        if outbox.put(frame, key="depth_m", write=sock.send) == FIRST:
            ...  # ask the writer to call outbox.write_to(sock.send)

    Attributes:
        max_bytes: how many bytes of frames may wait.
        loss: where drops are reported (the numbers, at most once a second).
        dropped: frames pushed out so far.
        dropped_by_key: the same, per data key.
        last_sent_at: when bytes last went to the peer (``time.monotonic()``).
    """

    def __init__(self, max_bytes: int, loss: LossReport) -> None:
        self.max_bytes = max_bytes
        self.loss = loss
        self.dropped = 0
        self.dropped_by_key: Dict[DataKey, int] = {}
        self.last_sent_at = time.monotonic()
        self._entries: Deque[_Entry] = collections.deque()  # pushed-out ones stay, data None
        self._by_key: Dict[DataKey, Deque[_Entry]] = {}  # waiting ones only, oldest first
        self._live = 0  # entries still waiting
        self._bytes = 0
        self._closed = False
        self._lock = threading.Lock()
        self._ready = threading.Condition(self._lock)  # for a writer thread in ``take``

    # -- putting (any thread, usually the node's) --------------------------------
    def put(
        self, frame: bytes, key: Optional[DataKey] = None, write: Optional[Write] = None
    ) -> str:
        """Queue ``frame``, or with ``write`` and nothing waiting, write it at once.

        Returns `SENT`, `FIRST` (queued into an empty outbox: wake the
        writer), `QUEUED` or `CLOSED`. A frame written in part is queued for
        the rest, first in line and never pushed out.
        """
        with self._lock:
            if self._closed:
                return CLOSED
            if write is not None and not self._live:
                try:
                    sent = write(frame)
                except OSError:  # full (BlockingIOError) or broken: the writer finds out
                    sent = 0
                if sent:
                    self.last_sent_at = time.monotonic()
                    if sent == len(frame):
                        return SENT
                    self._append(None, frame[sent:])
                    return FIRST
            first = not self._live
            if self._bytes + len(frame) > self.max_bytes:
                self._make_room(len(frame), key)
            self._append(key, frame)
        return FIRST if first else QUEUED

    def put_all(self, frames: List[bytes], key: DataKey) -> str:
        """`put` for a run of frames under ``key``, in order, with one lock; nothing is written.

        Example::

            outbox.put_all([encode_page(page) for page in pages], "depth")
        """
        size = 0
        for frame in frames:
            size += len(frame)
        with self._lock:
            if self._closed:
                return CLOSED
            first = not self._live
            if self._bytes + size <= self.max_bytes:  # the usual case: all fit
                run = [_Entry(key, frame) for frame in frames]
                self._entries.extend(run)
                waiting = self._by_key.get(key)
                if waiting is None:
                    self._by_key[key] = collections.deque(run)
                else:
                    waiting.extend(run)
                self._live += len(run)
                self._bytes += size
            else:  # room is made frame by frame, so each drop is decided as in put
                for frame in frames:
                    if self._bytes + len(frame) > self.max_bytes:
                        self._make_room(len(frame), key)
                    self._append(key, frame)
            if first:
                self._ready.notify()
        return FIRST if first else QUEUED

    def put_first(self, frame: bytes) -> None:
        """Queue ``frame`` before everything waiting, never to be pushed out (e.g. a header)."""
        with self._lock:
            if not self._closed:
                self._entries.appendleft(_Entry(None, frame))
                self._live += 1
                self._bytes += len(frame)
                self._ready.notify()

    def _append(self, key: Optional[DataKey], frame: bytes) -> None:
        entry = _Entry(key, frame)
        self._entries.append(entry)
        if key is not None:
            waiting = self._by_key.get(key)
            if waiting is None:
                self._by_key[key] = collections.deque((entry,))
            else:
                waiting.append(entry)
        self._live += 1
        self._bytes += len(frame)
        if self._live == 1:
            self._ready.notify()

    def _make_room(self, size: int, key: Optional[DataKey]) -> None:
        """Push out frames, oldest first, of ``key`` or else of the key with the most waiting."""
        pushed_out = 0
        by_key = self._by_key
        while by_key and self._bytes + size > self.max_bytes:
            victim_key = key if key in by_key else max(by_key, key=lambda k: len(by_key[k]))
            victims = by_key[victim_key]
            self._gone(victims.popleft())
            if not victims:
                del by_key[victim_key]
            pushed_out += 1
            self.dropped_by_key[victim_key] = self.dropped_by_key.get(victim_key, 0) + 1
        if pushed_out:
            self.dropped += pushed_out
            entries = self._entries
            if len(entries) > 2 * self._live + 64:  # forget the pushed-out ones now and then
                self._entries = collections.deque(e for e in entries if e.data is not None)
            self.loss.dropped(pushed_out)

    def _gone(self, entry: _Entry) -> None:
        """``entry`` leaves (written or pushed out); the deque forgets it when it reaches it."""
        if entry.data is not None:
            self._bytes -= len(entry.data)
            entry.data = None
            self._live -= 1

    # -- writing (the link's writer) -------------------------------------------------
    def write_to(self, write: Write) -> bool:
        """Write what ``write`` takes now, many frames a call; True once nothing waits.

        What does not fit stays first in line (its key can no longer push it out).

        Raises:
            OSError: the peer is gone (not BlockingIOError: a full buffer means "later").
        """
        with self._lock:
            entries = self._entries
            while self._live:
                parts: List[bytes] = []
                size = 0
                for entry in entries:
                    if size >= MAX_CHUNK_BYTES:
                        break
                    if entry.data is not None:
                        parts.append(entry.data)
                        size += len(entry.data)
                chunk = parts[0] if len(parts) == 1 else b"".join(parts)
                try:
                    sent = write(chunk)
                except BlockingIOError:
                    return False
                if sent:
                    self.last_sent_at = time.monotonic()
                self._consume(sent)
                if sent < size:
                    return False
            return True

    def _consume(self, sent: int) -> None:
        """Forget the first ``sent`` bytes of what waits (a frame written in part stays)."""
        entries = self._entries
        while entries:
            entry = entries[0]
            data = entry.data
            if data is not None:
                if sent < len(data):
                    if sent:  # the rest goes first next time; its key no longer pushes it out
                        entry.data = data[sent:]
                        self._bytes -= sent
                        self._unkey(entry)
                    return
                sent -= len(data)
                self._unkey(entry)
                self._gone(entry)
            entries.popleft()

    def _unkey(self, entry: _Entry) -> None:
        """``entry``, the oldest waiting of its key, leaves its key's line."""
        key = entry.key
        if key is not None:
            entry.key = None
            waiting = self._by_key.get(key)
            if waiting is not None and waiting[0] is entry:
                waiting.popleft()
                if not waiting:
                    del self._by_key[key]

    def take(self, timeout_s: Optional[float] = None) -> Optional[bytes]:
        """For a writer thread: the oldest frame, waiting up to ``timeout_s`` for one.

        Returns None when ``timeout_s`` passed, or the outbox is closed and empty.
        """
        with self._lock:
            if not self._live and not self._closed:
                self._ready.wait(timeout_s)
            entries = self._entries
            while entries:
                entry = entries.popleft()
                data = entry.data
                if data is not None:
                    self._unkey(entry)
                    self._gone(entry)
                    return data
            return None

    # -- closing ----------------------------------------------------------------------
    def close(self, discard: bool = False) -> int:
        """Take no more frames; with ``discard``, forget those waiting. How many were forgotten.

        A writer thread in ``take`` gets what is left, then None.
        """
        with self._lock:
            self._closed = True
            forgotten = 0
            if discard:
                forgotten = self._live
                self._entries.clear()
                self._by_key.clear()
                self._live = self._bytes = 0
            self._ready.notify_all()
            return forgotten

    @property
    def closed(self) -> bool:
        """True once ``close`` was called."""
        return self._closed

    @property
    def queued_bytes(self) -> int:
        """Bytes of frames waiting to be written."""
        return self._bytes

    def __len__(self) -> int:
        """How many frames wait to be written."""
        return self._live
