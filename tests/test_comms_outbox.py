"""The one `Outbox` every link queues in: bounded, newest per key wins, every drop counted."""

from __future__ import annotations

import logging
import threading
import unittest
from typing import List, Optional

from snr.core.logs import LossReport
from snr.std_mods.comms import Outbox
from snr.std_mods.comms.comms_loop import CLOSED, FIRST, QUEUED, SENT


class Peer:
    """Takes up to ``room`` bytes a call (all of them if None) and remembers each call."""

    def __init__(self, room: Optional[int] = None) -> None:
        self.room = room
        self.sends: List[bytes] = []

    def send(self, data: bytes) -> int:
        if self.room == 0:
            raise BlockingIOError
        taken = data if self.room is None else data[: self.room]
        self.sends.append(bytes(taken))
        return len(taken)


def outbox(max_bytes: int) -> Outbox:
    log = logging.getLogger("snr.test.outbox")
    log.addHandler(logging.NullHandler())
    log.propagate = False
    return Outbox(max_bytes, LossReport(log, "frames", "the test is full"))


class TestWhenFull(unittest.TestCase):
    def test_the_newest_per_key_wins_and_a_flood_never_pushes_out_another_key(self) -> None:
        box = outbox(40)
        self.assertEqual(box.put(b"speed 1\n", "speed"), FIRST)  # 8 bytes each
        self.assertEqual(box.put(b"light 1\n", "light"), QUEUED)
        for value in range(2, 5):
            box.put(f"speed {value}\n".encode(), "speed")
        self.assertEqual(box.dropped, 0, "40 bytes fit")
        # full: each new speed line pushes out the oldest speed line
        box.put(b"speed 5\n", "speed")
        box.put(b"speed 6\n", "speed")
        # a key with nothing waiting pushes out the oldest line of the key with
        # the most waiting, so the only light line stays
        box.put(b"beep 1\n", "beep")
        self.assertEqual((box.dropped, box.dropped_by_key), (3, {"speed": 3}))
        self.assertEqual(box.loss.total, 3, "told to the link's loss report")
        taken = []
        while len(box):
            taken.append(box.take(0))
        expected = [b"light 1\n", b"speed 4\n", b"speed 5\n", b"speed 6\n", b"beep 1\n"]
        self.assertEqual(taken, expected)
        self.assertEqual(box.queued_bytes, 0)
        self.assertIsNone(box.take(0))

    def test_frames_without_a_key_are_never_pushed_out(self) -> None:
        box = outbox(10)
        box.put(b"hello", None)
        box.put_first(b"head")
        box.put(b"page", "k")
        box.put(b"newer", "k")  # pushes out "page", never the frames without a key
        self.assertEqual(box.dropped_by_key, {"k": 1})
        self.assertEqual([box.take(0) for _ in range(3)], [b"head", b"hello", b"newer"])

    def test_a_frame_bigger_than_the_cap_still_goes_when_nothing_waits(self) -> None:
        box = outbox(4)
        self.assertEqual(box.put(b"0123456789", "big"), FIRST)
        self.assertEqual(box.take(0), b"0123456789")

    def test_the_rest_of_a_big_frame_written_in_part_waits_whole_and_keyless(self) -> None:
        box, peer = outbox(4), Peer(room=3)
        self.assertEqual(box.put(b"0123456789", "big", peer.send), FIRST)
        self.assertEqual((len(box), box.queued_bytes, box.dropped), (1, 7, 0))
        box.put(b"new", "big")  # over the cap, but the started frame is never pushed out
        self.assertEqual([box.take(0), box.take(0)], [b"3456789", b"new"])
        self.assertEqual(box.dropped, 0)

    def test_a_long_flood_keeps_memory_bounded(self) -> None:
        box = outbox(100)
        peer = Peer(room=0)  # a peer that reads nothing
        for n in range(20_000):
            box.put(b"%09d\n" % n, "flood", peer.send)
        self.assertEqual(len(box), 10)
        self.assertLess(len(box._entries), 200, "pushed-out frames are forgotten now and then")
        self.assertEqual(box.dropped, 20_000 - 10)


class TestWriting(unittest.TestCase):
    def test_a_frame_goes_at_once_when_nothing_waits_and_a_burst_in_one_call(self) -> None:
        box, peer = outbox(1 << 20), Peer()
        self.assertEqual(box.put(b"a", "k", peer.send), SENT)
        self.assertEqual(box.put(b"b", "k"), FIRST, "no write given: queued")
        self.assertEqual(box.put(b"c", "k", peer.send), QUEUED, "frames wait: behind them")
        self.assertEqual(box.put_all([b"d", b"e"], "k"), QUEUED)
        self.assertTrue(box.write_to(peer.send))
        self.assertEqual(peer.sends, [b"a", b"bcde"], "the waiting frames went in one call")

    def test_what_the_peer_does_not_take_stays_first_in_line_and_is_never_pushed_out(
        self,
    ) -> None:
        box, peer = outbox(11), Peer(room=3)
        self.assertEqual(box.put(b"abcde", "k", peer.send), FIRST, "the rest of it waits")
        box.put(b"fghij", "k")
        peer.room = 0
        self.assertFalse(box.write_to(peer.send), "full: later")
        box.put(b"klmno", "k")  # pushes out "fghij", not the rest of "abcde"
        peer.room = None
        self.assertTrue(box.write_to(peer.send))
        self.assertEqual(b"".join(peer.sends), b"abcdeklmno")
        self.assertEqual(box.dropped, 1)

    def test_a_broken_peer_is_the_writers_to_find(self) -> None:
        def broken(data: bytes) -> int:
            raise ConnectionResetError("gone")

        box = outbox(100)
        self.assertEqual(box.put(b"a", "k", broken), FIRST, "queued: the writer finds out")
        with self.assertRaises(ConnectionResetError):
            box.write_to(broken)

    def test_a_run_that_does_not_fit_makes_room_frame_by_frame(self) -> None:
        box = outbox(6)
        box.put(b"ab", "k")
        box.put_all([b"cd", b"ef", b"gh"], "k")
        self.assertEqual((box.dropped, box.queued_bytes), (1, 6))
        self.assertEqual([box.take(0) for _ in range(3)], [b"cd", b"ef", b"gh"])


class TestClosing(unittest.TestCase):
    def test_closed_it_takes_nothing_and_a_writer_gets_what_is_left(self) -> None:
        box = outbox(100)
        box.put(b"a", "k")
        box.close()
        self.assertEqual(box.put(b"b", "k"), CLOSED)
        self.assertEqual(box.put_all([b"c"], "k"), CLOSED)
        self.assertEqual(box.take(), b"a")
        self.assertIsNone(box.take(), "closed and empty: does not wait")

    def test_discarding_says_how_many_were_forgotten(self) -> None:
        box = outbox(100)
        box.put_all([b"a", b"b"], "k")
        self.assertEqual(box.close(discard=True), 2)
        self.assertEqual((len(box), box.queued_bytes), (0, 0))

    def test_a_writer_thread_waiting_in_take_is_woken_by_a_put_and_by_close(self) -> None:
        box = outbox(100)
        got: List[Optional[bytes]] = []
        writer = threading.Thread(target=lambda: got.extend([box.take(5.0), box.take(5.0)]))
        writer.start()
        box.put(b"line", "k")
        box.close()
        writer.join(5.0)
        self.assertEqual(got, [b"line", None])


if __name__ == "__main__":
    unittest.main()
