"""How a Zenoh subscription's samples reach a node's thread: FIFOs and the idle reader.

Each subscription of a `ZenohComms` puts its samples in a bounded Zenoh FIFO,
a `SampleChannel`. The node's thread empties it in batches; a watcher thread
of `ZenohComms` wakes the node for the first sample of a burst. While the
node is idle, its own thread may wait in one channel itself (`IdleReader`),
woken for other work by a sample of its own that only wakes it (`wake_key`,
`is_wake`). A `SequenceFollower` counts the pages that never arrived.
``zenoh_comms.py`` uses them; nothing here imports Zenoh.

Example::

    channel = SampleChannel(subscriber.handler)
    wake_key("team7/**")    # "team7/_snr_wake": a key that pattern matches
"""

from __future__ import annotations

import os
import struct
import threading
import time
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

__all__ = [
    "COUNT_MARK",
    "SEQUENCE",
    "WAKE",
    "IdleReader",
    "SampleChannel",
    "SequenceFollower",
    "count_attachment",
    "is_wake",
    "read_count",
    "wake_key",
]

COUNT_MARK = b"snr#"
"""The first bytes of an SNR sender's count attachment (`SEQUENCE`): other attachments are not."""

SEQUENCE = struct.Struct(">4s8sQ")
"""An SNR sender's attachment on a page: `COUNT_MARK`, its random id, then its count of pages
under the key (20 bytes). Made by `count_attachment`, read by `read_count`."""

WAKE = b"snr-wake-" + os.urandom(8)
"""The attachment of a sample that only wakes a node's thread (`IdleReader`).

Random for each process: such a sample never leaves its session, so a
sample from elsewhere that carries it (or anything like it) is no wake-up
and is taken as a page.
"""

_WAKE_CHUNK = "_snr_wake"  # what stands for a wildcard in the key of such a sample


class SampleChannel:
    """One subscription's samples: a bounded Zenoh FIFO that the node's thread empties.

    Zenoh's network thread puts each sample in ``handler`` (a
    ``zenoh.handlers.FifoChannel``; it waits while the FIFO is full). The
    channel's watcher thread waits in ``handler.recv()``, without the GIL,
    for the first sample of a burst and hands it over in ``first``; from then
    until ``emptied`` is set again the node's thread owns the channel and
    takes the rest straight from the FIFO with ``try_recv()``. One hand-off
    between threads a burst, where a Python callback per sample took the GIL
    from the node's thread for every page.

    Example::

        channel = SampleChannel(subscriber.handler)   # then ZenohComms watches it

    Attributes:
        first: the sample the watcher handed over, taken first by the node.
        emptied: set while the watcher owns the channel (the node emptied it).
        taken: samples the node's thread has taken (the watcher sees progress).
    """

    def __init__(self, handler: Any) -> None:
        self.handler = handler
        self.first: Any = None
        self.emptied = threading.Event()
        self.emptied.set()
        self.taken = 0
        #: Held by whoever takes the first sample of a burst from the FIFO
        #: when two threads may (`IdleReader`): so they never take two at once.
        self.take_lock = threading.Lock()


def wake_key(pattern: str) -> Optional[str]:
    """A key that ``pattern`` (a subscription's key expression) matches, to wake a reader with.

    Wildcards become ``_snr_wake``; None if the pattern has verbatim
    (``@``) chunks, whose keys are not made up.

    Example::

        wake_key("team7/cmd")        # "team7/cmd"
        wake_key("team7/**")         # "team7/_snr_wake"
        wake_key("team7/arm_$*")     # "team7/arm_"
    """
    chunks = []
    for chunk in pattern.split("/"):
        if chunk.startswith("@"):
            return None
        if chunk in ("*", "**"):
            chunk = _WAKE_CHUNK
        chunk = chunk.replace("$*", "")
        chunks.append(chunk or _WAKE_CHUNK)
    return "/".join(chunks)


def count_attachment(sender: bytes, count: int) -> bytes:
    """The attachment of page number ``count`` that ``sender`` (8 bytes) publishes under a key.

    Example::

        count_attachment(b"sender01", 7)   # b'snr#sender01' + (7).to_bytes(8, "big")
    """
    return SEQUENCE.pack(COUNT_MARK, sender, count)


def read_count(attachment: Optional[bytes]) -> Optional[Tuple[bytes, int]]:
    """The sender and count of an SNR sender's attachment; None for any other attachment.

    A program that is not SNR may attach anything (16 bytes of its own, say):
    only an attachment of `SEQUENCE`'s size that starts with `COUNT_MARK` is a count.

    Example::

        read_count(count_attachment(b"sender01", 7))   # (b'sender01', 7)
        read_count(b"0123456789abcdef")                # None
    """
    if attachment is None or len(attachment) != SEQUENCE.size:
        return None
    if not attachment.startswith(COUNT_MARK):
        return None
    _, sender, count = SEQUENCE.unpack(attachment)
    return sender, count


def is_wake(sample: Any) -> bool:
    attachment = sample.attachment
    return attachment is not None and attachment.to_bytes() == WAKE


class IdleReader:
    """The node's thread, while idle, waits in one subscription's FIFO itself.

    A node's `snr.core.task_queue.IdleWaiter` (as the socket links' I/O loop is): a sample that
    arrives while the node is idle is taken by the node's own thread as
    Zenoh hands it over, with no hand-off between Python threads (what that
    saves on a round trip: docs/performance.md). Zenoh's FIFO
    has no timeout and nothing but a sample wakes it, so `wake` puts an
    empty sample marked ``snr-wake`` under a key the subscription matches,
    for this session only (``Locality.SESSION_LOCAL``: no other program sees
    it); samples so marked are skipped wherever they are taken.

    While the node's thread works, the channel's watcher takes over: once the
    thread has worked `_BUSY_READS_S` without waiting, the watcher hands a
    waiting burst over as other watchers do (`ZenohComms._watch_for_node`).

    Its owner (`ZenohComms`) gives it three things to call: ``take()`` on
    the node's thread after a wait that left samples in the channel for the
    node (one it took is handed over there, as a watcher hands one over),
    ``put_wake(key)`` to put a wake-up sample, and ``has_room()``: whether
    the node's queue has room for what waits.

    Example (what `ZenohComms.begin` does for one subscription)::

        reader = IdleReader(channel, "snr/team7/cmd", comms._take_now, comms._put_wake,
                            lambda: node.wait_for_room(0))
        node.queue.use_waiter(reader)   # True: idle waits are now in its FIFO

    Attributes:
        reading: the node's thread is waiting in the FIFO now.
        deadline: when that wait must end (``time.monotonic()``; None: never).
        busy_since: when the node's thread last left its wait.
    """

    def __init__(
        self,
        channel: SampleChannel,
        wake_key: str,
        take: Callable[[], None],
        put_wake: Callable[[str], None],
        has_room: Callable[[], bool],
    ) -> None:
        self.channel = channel
        self.wake_key = wake_key
        self._take_from = take
        self._put_wake = put_wake
        self._has_room = has_room
        self.reading = False
        self.deadline: Optional[float] = None
        self.busy_since = time.monotonic()
        self._take = False  # woken() takes what the node's thread owns in the channel
        self._nudge = threading.Event()  # wakes a wait that is not in the FIFO

    def wait(self, timeout_s: Optional[float]) -> None:
        """Node's thread, queue empty: wait in the FIFO for a sample or a wake-up."""
        channel = self.channel
        if not channel.emptied.is_set():
            # Samples wait for the node's thread: take them now if its queue has
            # room, else (a paused node with a full queue) wait as on the bell.
            if self._has_room():
                self._take = True
            else:
                self._nudge.wait(timeout_s)
                self._nudge.clear()
            return
        # The lock is held only inside this block, never on to woken(): a Ctrl-C
        # (a KeyboardInterrupt on this thread) between the two would keep it,
        # and the watcher, which needs it, would block. A sample taken here is
        # handed to the node's thread as a watcher hands one over (`first`,
        # `emptied` cleared) before the lock is let go: the watcher takes
        # nothing until the rest of the burst is taken, so no later sample is
        # stored first.
        with channel.take_lock:
            self.deadline = None if timeout_s is None else time.monotonic() + timeout_s
            self.reading = True
            try:
                # `wake` sets the nudge, then puts a wake-up only if it sees `reading`:
                # checked after `reading` is set, one of the two always sees the other.
                if self._nudge.is_set():
                    sample = None
                else:
                    try:
                        sample = channel.handler.recv()  # waits without the GIL
                    except Exception:  # undeclared: the component is closing
                        sample = None
            finally:
                self.reading = False
                self._nudge.clear()
                self.busy_since = time.monotonic()
            if sample is not None and not is_wake(sample):
                channel.first = sample  # set before emptied is cleared: the node takes it
                channel.emptied.clear()
                self._take = True

    def woken(self) -> None:
        """Node's thread, after its wait: queue the pages of what it took."""
        if self._take:
            self._take = False
            self._take_from()

    def wake(self) -> None:
        """End the node thread's wait, in the FIFO or not (any thread).

        A wake-up sample is put only while the node's thread waits in the
        FIFO, which is then empty. Put while the node works, it could find
        the FIFO full, and a full FIFO holds the put until the node's thread
        takes from it: for ever, if that thread is stopping (or is the one
        putting). A wait that starts later sees the nudge and does not wait.
        """
        self._nudge.set()
        if self.reading:
            self._put_wake(self.wake_key)


_Stream = Tuple[bytes, str]  # (the sender's id, the key)
_MAX_DROPPED_RUNS = 64  # runs of counts dropped here, kept a stream until its next page


class SequenceFollower:
    """Counts the pages that never arrived, from each sender's count under each key.

    An SNR sender numbers the pages it publishes under a key (`SEQUENCE`, the
    sample's attachment), so a gap between two counts the node takes is
    pages lost on the way. Pages the node dropped itself (its thread was
    stuck: `dropped`, from the watcher's thread) are counted as dropped
    where they were dropped, so they are left out of the gap. Up to
    ``max_streams`` (sender, key) pairs are followed; then it starts again.

    Example::

        follower = SequenceFollower()
        follower.taken(b"sender01", "depth", 1)   # 0: the first count seen
        follower.dropped(b"sender01", "depth", 2)  # the node dropped count 2 itself
        follower.taken(b"sender01", "depth", 5)   # 2: counts 3 and 4 never arrived
    """

    def __init__(self, max_streams: int = 10_000) -> None:
        self.max_streams = max_streams
        self._last: Dict[_Stream, int] = {}
        # Runs [first, last] of counts dropped here, per stream, oldest first;
        # the node's thread reads them only for a gap, under the lock.
        self._dropped: Dict[_Stream, List[List[int]]] = {}
        self.lock = threading.Lock()

    def taken(self, sender: bytes, key: str, count: int) -> int:
        """Node's thread: the node took ``count``; how many pages before it never arrived."""
        stream = (sender, key)
        last = self._last.get(stream)
        if last is None and len(self._last) >= self.max_streams:
            self._last.clear()
        self._last[stream] = count
        if last is None or count <= last + 1:
            return 0
        with self.lock:  # rare: a gap
            runs = self._dropped.pop(stream, None)
            if not runs:
                return count - last - 1
            dropped_here = 0
            later: List[List[int]] = []
            for first, final in runs:
                if first >= count:
                    later.append([first, final])
                else:
                    dropped_here += max(0, min(final, count - 1) - max(first, last + 1) + 1)
            if later:
                self._dropped[stream] = later
        return max(0, count - last - 1 - dropped_here)

    def taken_all(self, counted: Sequence[Tuple[str, bytes]]) -> int:
        """Node's thread: `taken` for each (key, attachment) of a batch, in order; pages lost.

        Attachments that are not an SNR sender's count are skipped. A run of
        consecutive counts of one sender under one key costs one `taken` (its
        first) and one comparison of bytes per page after it: a burst of
        pages is checked for gaps at a fraction of a `taken` call each.

        Example::

            follower = SequenceFollower()
            follower.taken_all([("depth", count_attachment(b"sender01", n)) for n in (1, 2, 5)])
            # 2: counts 3 and 4 never arrived
        """
        lost = 0
        run_key: Optional[str] = None  # the key of the run of counts being followed
        sender, count, expected = b"", 0, b""  # ... its sender, last count, and next attachment
        for key, attachment in counted:
            if attachment == expected and key == run_key:
                count += 1
                expected = count_attachment(sender, count + 1)
                continue
            if run_key is not None:
                self._last[(sender, run_key)] = count  # the run ended: no gap inside it
            numbered = read_count(attachment)
            if numbered is None:
                run_key, expected = None, b""
                continue
            sender, count = numbered
            lost += self.taken(sender, key, count)
            run_key = key
            expected = count_attachment(sender, count + 1)
        if run_key is not None:
            self._last[(sender, run_key)] = count
        return lost

    def dropped(self, sender: bytes, key: str, count: int) -> None:
        """Any thread, holding `lock`: the node dropped the page numbered ``count``."""
        stream = (sender, key)
        runs = self._dropped.get(stream)
        if runs is None:
            if len(self._dropped) >= self.max_streams:
                self._dropped.clear()
            runs = self._dropped[stream] = []
        if runs and runs[-1][1] == count - 1:
            runs[-1][1] = count
            return
        runs.append([count, count])
        if len(runs) > _MAX_DROPPED_RUNS:  # join the two oldest (what lay between them counts too)
            runs[0][1] = runs[1][1]
            del runs[1]
