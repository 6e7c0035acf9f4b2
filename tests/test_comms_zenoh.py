"""Zenoh comms: settings, the page codec, nodes in one process and in five processes.

Everything runs on 127.0.0.1 with multicast scouting off, explicit endpoints
and ports chosen at run time. Skipped when the Zenoh extra is not installed.
"""

from __future__ import annotations

import collections
import importlib.util
import json
import multiprocessing
import os
import queue
import random
import signal
import struct
import subprocess
import sys
import threading
import time
import unittest
from typing import Any, Callable, Deque, Dict, List, Sequence, Tuple
from unittest import mock

from snr import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Node,
    Page,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)
from snr.extras.zenoh.inbox import WAKE, SequenceFollower, count_attachment, read_count
from snr.prelude import ConfigError, WireFormatError
from snr.prelude.install import install_hint
from snr.utils import MockNode
from tests.comms_helpers import (
    EchoFactory,
    EventReporterFactory,
    NodeProcess,
    Reports,
    SendOnConnectFactory,
    StopAfterFactory,
    TickerFactory,
)
from tests.helpers import free_port, wait_until
from tests.optional import reason
from tests.quiet import capture_test_logs
from tests.test_comms_local import LocalNodes

HAVE_ZENOH = importlib.util.find_spec("zenoh") is not None
NEEDS_ZENOH = reason("zenoh")
PLAIN_CLIENT = os.path.join(os.path.dirname(__file__), "zenoh_plain_client.py")

if HAVE_ZENOH:
    from snr import ZenohCommsFactory
    from snr.extras.zenoh import ZenohComms
    from snr.extras.zenoh.comms import (
        BATCH_TIME_LIMIT_MS,
        _zenoh_module,
        page_from_sample,
        zenoh_config,
    )


def zenoh_safe_context() -> Any:
    """Processes forked from a clean server: a child forked from a process whose
    Zenoh runtime has run (an earlier test here) can hang in ``zenoh.open``."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["zenoh", "tests.test_comms_zenoh"])  # import once, not per node
    return ctx


def endpoint(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def start_router(test: unittest.TestCase) -> str:
    """A Zenoh router in this process, standing in for zenohd; its endpoint (closed at cleanup)."""
    zenoh = _zenoh_module()
    ep = endpoint(free_port())
    config = zenoh.Config()
    config.insert_json5("mode", '"router"')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("listen/endpoints", json.dumps([ep]))
    router = zenoh.open(config)
    test.addCleanup(router.close)
    return ep


def comms(system: str, **kwargs: Any) -> Any:
    """A ZenohCommsFactory as the tests use it: no multicast, explicit endpoints."""
    return ZenohCommsFactory(system, scouting=False, **kwargs)


def zenoh_of(node: Any) -> Any:
    found = [c for c in node.components.values() if isinstance(c, ZenohComms)]
    return found[0]


def data_of(task: Task) -> List[Any]:
    """The data of the pages a ``store_pages`` task carries, in order."""
    return [page.data for page in task.val_list]


class FakeFifo:
    """A stand-in for a Zenoh FIFO handler: ``recv`` waits, and raises once closed."""

    def __init__(self) -> None:
        self.items: queue.Queue[Any] = queue.Queue()
        self.waiting = threading.Event()  # set each time recv() starts waiting

    def put(self, item: Any) -> None:
        self.items.put(item)

    def close(self) -> None:
        self.items.put(self)

    def recv(self) -> Any:
        self.waiting.set()
        item = self.items.get(timeout=5)
        if item is self:
            raise RuntimeError("channel is empty and closed")
        return item

    def try_recv(self) -> Any:
        try:
            item = self.items.get_nowait()
        except queue.Empty:
            return None
        return None if item is self else item


def sample_of(data: Any, attachment: Any = None) -> Any:
    """A stand-in for a Zenoh sample under ``snr/lab/n`` whose payload is ``{"data": data}``."""
    body = json.dumps({"data": data}).encode()
    payload = mock.Mock(to_bytes=mock.Mock(return_value=body))
    return mock.Mock(key_expr="snr/lab/n", payload=payload, attachment=attachment)


@unittest.skipUnless(HAVE_ZENOH, NEEDS_ZENOH)
class TestZenohSettings(unittest.TestCase):
    """Bad settings fail at once with a clear message; samples decode strictly."""

    def test_bad_settings_are_config_errors_that_say_why(self) -> None:
        cases: List[Tuple[Callable[[], object], str]] = [
            (lambda: ZenohCommsFactory("a/b", publish="x"), "one word"),
            (lambda: ZenohCommsFactory("", publish="x"), "non-empty"),
            (lambda: ZenohCommsFactory("team", publish="x*"), "* $ ? #"),
            (lambda: ZenohCommsFactory("team", subscribe="a*b"), "whole part"),
            (lambda: ZenohCommsFactory("team", subscribe="a//b"), "empty part"),
            (lambda: ZenohCommsFactory("team", publish="@node"), "'@'"),
            (lambda: ZenohCommsFactory("team"), "no keys"),
            (lambda: ZenohCommsFactory("team", "x", mode="server"), "mode"),
            (lambda: ZenohCommsFactory("team", "x", congestion="wait"), '"drop"'),
            (lambda: ZenohCommsFactory("team", "x", connect="tcp/h:1"), "list of endpoints"),
        ]
        for make, words in cases:
            with self.subTest(words=words), self.assertRaises(ConfigError) as caught:
                make()
            self.assertIn(words, str(caught.exception))
        ZenohCommsFactory("team", publish=["a/b"], subscribe="*")  # fine
        ZenohCommsFactory("team", publish=["a/b"], subscribe=["sensors/*/**", "motors/*"])

    def test_subscriptions_must_differ_before_a_wildcard(self) -> None:
        accepted = [
            ["sensors/depth", "sensors/range", "motors"],  # exact keys that differ
            ["sensors", "sensors/depth"],  # one ends before the other
            ["sensors/*", "motors/*"],  # they differ at the first part
            ["sensors/*", "robot/status"],  # (as examples/zenoh_team/team.py has it)
            ["a/b/**", "a/c/*"],
        ]
        for patterns in accepted:
            with self.subTest(patterns=patterns):
                ZenohCommsFactory("team", subscribe=patterns)
        refused = [
            ["sensors/*", "sensors/depth"],
            ["sensors/**", "sensors"],  # ** may match no part
            ["x", "**"],
            ["*/depth", "sensors/*"],
            ["a/*/x", "a/*/y"],  # no key matches both, but the rule stops at the first *
            ["a/b", "a/b/c", "a/*"],  # the first pair is fine, the refused one is named
        ]
        for patterns in refused:
            with self.subTest(patterns=patterns), self.assertRaises(ConfigError) as caught:
                ZenohCommsFactory("team", subscribe=patterns)
            message = str(caught.exception)
            first, second = patterns[0], patterns[-1]
            self.assertIn(f"patterns {first!r} and {second!r}, which may match a key", message)
            self.assertIn("before either has a '*' or '**'", message)  # the rule
            self.assertIn("Give exact keys, or one wider pattern", message)  # the fix

    def test_patterns_the_rule_accepts_never_intersect_in_zenoh(self) -> None:
        from snr.extras.zenoh.comms import _differ_before_a_wildcard

        canon = _zenoh_module().KeyExpr.autocanonize  # "**/*" is "*/**" to Zenoh
        parts = ["a", "b", "*", "**"]
        patterns = [f"{x}/{y}" for x in parts for y in parts] + parts + ["a/*/**", "**/b/*"]
        accepted = 0
        for first in patterns:
            for second in patterns:
                if first != second and _differ_before_a_wildcard(first, second):
                    accepted += 1
                    with self.subTest(first=first, second=second):
                        both = canon(f"snr/t/{first}").intersects(canon(f"snr/t/{second}"))
                        self.assertFalse(both, "accepted, so no key may match both")
        self.assertGreater(accepted, 10)  # the check above did look at some pairs

    def test_batches_fill_longer_while_the_link_is_busy_unless_told_otherwise(self) -> None:
        path = "transport/link/tx/queue/batching"
        zenoh_default = json.loads(_zenoh_module().Config().get_json(path))["time_limit"]
        ours = json.loads(zenoh_config(scouting=False).get_json(path))
        self.assertEqual((ours["enabled"], ours["time_limit"]), (True, BATCH_TIME_LIMIT_MS))
        self.assertNotEqual(BATCH_TIME_LIMIT_MS, zenoh_default)
        told = zenoh_config(scouting=False, extra={f"{path}/time_limit": 1}).get_json(path)
        self.assertEqual(json.loads(told)["time_limit"], 1)

    def test_a_missing_library_names_the_extra_to_install(self) -> None:
        with mock.patch.dict(sys.modules, {"zenoh": None}), self.assertRaises(ConfigError) as e:
            _zenoh_module()
        self.assertIn(install_hint("zenoh"), str(e.exception))

    def test_samples_decode_as_frames_do_and_plain_programs_may_say_less(self) -> None:
        full = b'{"v":1,"kind":"page","key":"d","data":[1,2],"origin":"r","created_at_s":5.0}'
        self.assertEqual(page_from_sample("d", full), Page("d", [1, 2], "r", 5.0))
        plain = page_from_sample("depth_m", b'{"data": 3.5}')
        self.assertEqual((plain.key, plain.data, plain.origin), ("depth_m", 3.5, "zenoh"))
        bad = {
            b"[1]": "object",
            b'{"data": NaN}': "NaN",
            b'{"v": 2, "data": 1}': "version",
            b'{"kind": "beat"}': "not a page",
            b'{"key": "other", "data": 1}': "not the key",
            b'{"data": 1, "origin": 7}': "origin",
            b'{"origin": "r"}': "no 'data'",
        }
        for payload, words in bad.items():
            with self.subTest(payload=payload), self.assertRaises(WireFormatError) as caught:
                page_from_sample("d", payload)
            self.assertIn(words, str(caught.exception))


class TestSequenceFollower(unittest.TestCase):
    """Gaps in a sender's count are lost pages, less those the node dropped itself."""

    def test_gaps_less_what_was_dropped_here(self) -> None:
        follow = SequenceFollower()
        a, b = b"A" * 8, b"B" * 8
        self.assertEqual([follow.taken(a, "x", n) for n in (1, 2, 5)], [0, 0, 2])
        with follow.lock:
            for n in (6, 7, 9, 12, 13):
                follow.dropped(a, "x", n)
        self.assertEqual(follow.taken(a, "x", 10), 1, "8 never came; 6, 7 and 9 dropped here")
        self.assertEqual(follow.taken(a, "x", 14), 1, "11 never came; 12 and 13 dropped here")
        self.assertEqual(follow.taken(b, "x", 40), 0, "a newcomer starts where it is")
        self.assertEqual(follow.taken(a, "y", 3), 0, "each key is counted alone")
        self.assertEqual(follow.taken(a, "x", 14), 0, "a repeat is no gap")

    def test_a_batch_counts_what_its_pages_one_by_one_would(self) -> None:
        rng = random.Random(14)
        senders, keys = [b"A" * 8, b"B" * 8], ["x", "y"]
        for trial in range(200):
            one_by_one, batched = SequenceFollower(max_streams=3), SequenceFollower(max_streams=3)
            counts = {(s, k): 0 for s in senders for k in keys}
            batch: List[Tuple[str, bytes]] = []
            for _ in range(rng.randrange(1, 40)):
                stream = rng.choice(list(counts))
                counts[stream] += rng.choice([1, 1, 1, 1, 2, 5, 0, -1])  # runs, gaps, repeats
                attachment = count_attachment(stream[0], max(counts[stream], 0))
                if rng.random() < 0.05:
                    attachment = b"plain program's"  # no count: skipped
                batch.append((stream[1], attachment))
            if rng.random() < 0.3:
                with one_by_one.lock, batched.lock:
                    one_by_one.dropped(senders[0], "x", 3)
                    batched.dropped(senders[0], "x", 3)
            expected = 0
            for key, attachment in batch:
                numbered = read_count(attachment)
                if numbered is not None:
                    expected += one_by_one.taken(numbered[0], key, numbered[1])
            with self.subTest(trial=trial):
                self.assertEqual(batched.taken_all(batch), expected)
                self.assertEqual(batched._last, one_by_one._last)
                self.assertEqual(batched._dropped, one_by_one._dropped)

    def test_dropped_runs_are_bounded_and_streams_too(self) -> None:
        follow = SequenceFollower(max_streams=3)
        sender = b"A" * 8
        follow.taken(sender, "x", 0)
        with follow.lock:
            for n in range(1, 1000, 2):  # 500 runs of one page, 1 page apart
                follow.dropped(sender, "x", n)
        self.assertLessEqual(len(follow._dropped[(sender, "x")]), 65)
        # Joined runs count what lay between the oldest ones as dropped: fewer
        # pages said lost than the 499 really missing, never more.
        self.assertLessEqual(follow.taken(sender, "x", 1000), 499)
        self.assertEqual(follow.taken(sender, "x", 1003), 2, "a later gap counts in full")
        for key in "abcdef":
            follow.taken(sender, key, 1)
        self.assertLessEqual(len(follow._last), 3)


@unittest.skipUnless(HAVE_ZENOH, NEEDS_ZENOH)
class TestZenohCounting(unittest.TestCase):
    """What a receiver counts, without a network: gaps in a sender's count, bad samples."""

    def setUp(self) -> None:
        self.comms = ZenohCommsFactory("lab", subscribe="**").get(MockNode())

    def test_a_gap_in_a_senders_count_is_counted_as_lost(self) -> None:
        from snr.extras.zenoh.inbox import count_attachment

        sender, other = b"A" * 8, b"B" * 8
        with self.assertLogs("snr", "WARNING") as logs:
            for count in (1, 2, 5, 6):  # 3 and 4 never came
                self.comms._follow_sequences([("depth", count_attachment(sender, count))])
            self.comms._follow_sequences([("depth", count_attachment(other, 7))])  # a newcomer
            self.comms._follow_sequences([("depth", b"not a count")])  # ignored
        self.assertEqual(self.comms.stats()["lost"], 2)
        self.assertIn("Lost 2 pages from Zenoh", logs.output[0])

    def test_attachments_of_plain_programs_are_neither_counts_nor_wake_ups(self) -> None:
        comms = ZenohCommsFactory("lab", subscribe="**").get(MockNode())

        def attached(data: int, attachment: bytes) -> Any:
            return sample_of(data, mock.Mock(to_bytes=lambda: attachment))

        def page_of(sample: Any) -> Any:
            pages = comms._pages_of([sample])
            return pages[0] if pages else None

        # A plain Zenoh program's own 16 bytes (the old shape of SNR's count).
        for i, data in enumerate((1, 2)):
            page = page_of(attached(data, struct.pack(">8sQ", b"plainapp", i * 10**9)))
            self.assertEqual(page.data if page else None, data)
        self.assertEqual(comms.stats()["lost"], 0, "not an SNR count: no gap")
        # "snr-wake" from elsewhere is a page (only this process's own wake-ups are not).
        page = page_of(attached(3, b"snr-wake"))
        self.assertEqual(page.data if page else None, 3)
        self.assertIsNone(page_of(attached(4, WAKE)), "our own wake-up is no page")
        self.assertEqual(comms.stats()["received"], 3)

    def test_pages_dropped_here_are_not_counted_again_as_lost(self) -> None:
        from snr.extras.zenoh import comms as zc
        from snr.extras.zenoh.inbox import count_attachment

        sender = b"A" * 8

        def counted(i: int) -> Any:
            return sample_of(i, mock.Mock(to_bytes=lambda: count_attachment(sender, i)))

        comms = ZenohCommsFactory("lab", subscribe="**").get(MockNode())
        fifo: Deque[Any] = collections.deque()
        channel = zc.SampleChannel(mock.Mock(try_recv=lambda: fifo.popleft() if fifo else None))
        comms._channels.append(channel)
        fifo.append(counted(1))
        comms._hand_over(channel, fifo.popleft())
        comms._take_waiting()
        wake = mock.Mock(to_bytes=lambda: WAKE)
        fifo.extend([counted(2), counted(3), sample_of(None, wake), counted(4)])
        with self.assertLogs("snr", "WARNING") as logs:
            comms._relieve(channel)  # the node's thread was stuck
            fifo.extend([counted(5), counted(8)])  # 6 and 7 never came
            comms._hand_over(channel, fifo.popleft())
            comms._take_waiting()
        self.assertEqual(comms.stats()["dropped"], 3, "three pages; a wake is not a page")
        self.assertEqual(comms.stats()["lost"], 2, "only 6 and 7")
        self.assertIn("Dropped 3 pages from Zenoh", logs.output[0])
        self.assertIn("Lost 2 pages from Zenoh", logs.output[1])

    def test_samples_reach_the_node_in_bounded_batches_in_order_and_a_stuck_node_drops(
        self,
    ) -> None:
        from snr.extras.zenoh import comms as zc

        node = MockNode()
        comms = ZenohCommsFactory("lab", subscribe="**").get(node)

        sample = sample_of
        fifo: Deque[Any] = collections.deque()  # a stand-in for Zenoh's FIFO
        channel = zc.SampleChannel(mock.Mock(try_recv=lambda: fifo.popleft() if fifo else None))
        comms._channels.append(channel)
        count = zc._BATCH + 3
        fifo.extend(sample(i) for i in range(count))
        comms._hand_over(channel, fifo.popleft())  # what the watcher does with a burst's first
        self.assertEqual(len(node.scheduled), 1, "one task asks for the whole burst")
        first = comms.take_batch(node.scheduled[0], node.scheduled[0].id())
        assert isinstance(first, list)
        self.assertEqual([t.name for t in first], [tasks.STORE_PAGES, "zenoh_comms_arrived"])
        self.assertEqual(data_of(first[0]), list(range(zc._BATCH)), "one burst, in order")
        self.assertFalse(channel.emptied.is_set(), "the watcher waits: the node is not done")
        rest = comms.take_batch(first[-1], first[-1].id())
        assert isinstance(rest, list)
        self.assertEqual(data_of(rest[0]), list(range(zc._BATCH, count)), "the rest behind")
        self.assertEqual([t.name for t in rest], [tasks.STORE_PAGES, "zenoh_comms_arrived"])
        self.assertTrue(channel.emptied.is_set(), "emptied: the watcher waits for the next")
        self.assertEqual(comms.take_batch(rest[-1], rest[-1].id()), [], "nothing more to take")
        self.assertEqual(comms.stats()["received"], count)

        # The node's thread is stuck: the watcher drops what waits, counted and said.
        fifo.extend(sample(i) for i in range(4))
        comms._hand_over(channel, fifo.popleft())
        with self.assertLogs("snr", "WARNING") as logs:
            comms._relieve(channel)
        self.assertEqual(comms.stats()["dropped"], 3)
        self.assertIn("Dropped 3 pages from Zenoh", logs.output[0])
        with self.assertLogs("snr", "WARNING") as logs:  # the node's thread is back
            back = comms.take_batch(node.scheduled[-1], node.scheduled[-1].id())
        self.assertIn("Recovered: 3 pages from Zenoh dropped", logs.output[0])
        assert isinstance(back, list)
        self.assertEqual(data_of(back[0]), [0], "the one handed over stays")

    def test_nothing_is_taken_while_the_nodes_queue_is_full(self) -> None:
        from snr.extras.zenoh import comms as zc

        node = MockNode()
        comms = ZenohCommsFactory("lab", subscribe="**").get(node)
        fifo: Deque[Any] = collections.deque(sample_of(i) for i in range(3))
        channel = zc.SampleChannel(mock.Mock(try_recv=lambda: fifo.popleft() if fifo else None))
        comms._channels.append(channel)
        comms._hand_over(channel, fifo.popleft())
        asked = node.scheduled[0]
        with mock.patch.object(node, "wait_for_room", return_value=False):
            later = comms.take_batch(asked, asked.id())
        assert isinstance(later, list)
        self.assertEqual([t.name for t in later], ["zenoh_comms_arrived"], "asked again later")
        self.assertEqual(len(fifo), 2, "the samples wait in the FIFO")
        batch = comms.take_batch(later[0], later[0].id())
        assert isinstance(batch, list)
        self.assertEqual(data_of(batch[0]), [0, 1, 2], "room again: all of them, in order")

    def test_a_watcher_wakes_the_node_once_a_burst_and_ends_with_the_subscriber(self) -> None:
        from snr.extras.zenoh import comms as zc

        node = MockNode()
        comms = ZenohCommsFactory("lab", subscribe="**").get(node)
        fifo = FakeFifo()
        channel = zc.SampleChannel(fifo)
        comms._watch_channel(channel)
        for i in range(3):
            fifo.put(sample_of(i))
        self.assertTrue(wait_until(lambda: len(node.scheduled) == 1), "the node was asked")
        batch = comms.take_batch(node.scheduled[0], node.scheduled[0].id())
        assert isinstance(batch, list)
        self.assertEqual(data_of(batch[0]), [0, 1, 2], "one batch, in order")
        self.assertEqual(len(node.scheduled), 1, "the burst woke the node once")
        with self.assertLogs("snr", "ERROR") as logs:  # closed, but not by the component
            fifo.close()
            comms._watchers[0].join(5)
        self.assertFalse(comms._watchers[0].is_alive(), "the watcher ended with its channel")
        self.assertIn("Stopped taking samples from Zenoh", logs.output[0])

        second = FakeFifo()
        comms._watch_channel(zc.SampleChannel(second))
        self.assertTrue(second.waiting.wait(5), "the second watcher waits for a sample")
        comms._closed.set()  # the component closing: its watcher ends without a word
        with self.assertNoLogs("snr", "ERROR"):
            second.close()
            comms._watchers[-1].join(5)
        self.assertFalse(comms._watchers[-1].is_alive())

    def test_the_idle_node_waits_in_the_fifo_and_its_watcher_covers_while_it_works(self) -> None:
        from snr.extras.zenoh import comms as zc

        node = MockNode()
        comms = ZenohCommsFactory("lab", subscribe="n").get(node)
        fifo = FakeFifo()
        sample = sample_of
        woken_by: List[str] = []
        wake_sample = sample(None, mock.Mock(to_bytes=mock.Mock(return_value=WAKE)))

        def put_wake(key: str) -> None:  # what a session-local put does
            woken_by.append(key)
            fifo.put(wake_sample)

        channel = zc.SampleChannel(fifo)
        reader = zc.IdleReader(
            channel, "snr/lab/n", take=comms._take_now, put_wake=put_wake, has_room=lambda: True
        )
        comms._reader = reader
        reader.busy_since = time.monotonic() + 60  # "just started working": the watcher waits
        comms._watch_channel(channel)
        self.addCleanup(comms._closed.set)

        # A burst while the node waits: its own thread takes it all, in order.
        fifo.put(sample(0))
        fifo.put(sample(1))
        reader.wait(5.0)
        reader.woken()
        stored, next_batch = node.scheduled
        self.assertEqual(data_of(stored), [0, 1], "one burst, in order")
        self.assertEqual(next_batch.name, "zenoh_comms_arrived", "the next batch asked behind")
        self.assertEqual(comms.take_batch(next_batch, next_batch.id()), [], "nothing more")
        self.assertTrue(channel.emptied.is_set(), "the FIFO is empty: nothing owed")

        # The wait ends by the time the node asked for: the watcher wakes it.
        started = time.monotonic()
        reader.wait(0.1)
        reader.woken()
        self.assertGreaterEqual(time.monotonic() - started, 0.1)
        self.assertLess(time.monotonic() - started, 2.0)
        self.assertEqual(woken_by, ["snr/lab/n"])
        self.assertEqual(len(node.scheduled), 2, "a wake-up is no page")

        # wake() from another thread ends a wait at once.
        threading.Timer(0.05, reader.wake).start()
        started = time.monotonic()
        reader.wait(30.0)
        reader.woken()
        self.assertLess(time.monotonic() - started, 2.0)

        # The node's thread has worked a while: the watcher hands a burst over.
        reader.busy_since = time.monotonic() - 1.0
        fifo.put(sample(2))
        self.assertTrue(wait_until(lambda: len(node.scheduled) == 3), "the node was asked")
        batch = comms.take_batch(node.scheduled[2], node.scheduled[2].id())
        assert isinstance(batch, list)
        self.assertEqual(batch[0].val_list[0].data, 2)
        self.assertTrue(channel.emptied.is_set())
        self.assertEqual(comms.take_batch(batch[-1], batch[-1].id()), [], "nothing more")

        # While the node's thread holds the channel, the watcher takes nothing.
        with channel.take_lock:
            fifo.put(sample(3))
            time.sleep(0.2)
            self.assertEqual(len(node.scheduled), 3)
        self.assertTrue(wait_until(lambda: len(node.scheduled) == 4), "then it does")

        comms._closed.set()
        comms._watchers[0].join(5)
        self.assertFalse(comms._watchers[0].is_alive(), "the watcher ends with the component")

    def test_a_ctrl_c_in_the_idle_wait_never_leaves_the_take_lock_held(self) -> None:
        from snr.extras.zenoh import comms as zc

        node = MockNode()
        comms = ZenohCommsFactory("lab", subscribe="n").get(node)
        fifo = FakeFifo()
        channel = zc.SampleChannel(fifo)
        reader = zc.IdleReader(
            channel, "snr/lab/n", take=comms._take_now, put_wake=fifo.put, has_room=lambda: True
        )
        comms._reader = reader
        # Its watcher runs all along, but takes over only at the end: by then
        # it needs the lock the node's thread may have kept.
        busy_reads = mock.patch.object(zc, "_BUSY_READS_S", 3600.0)
        busy_reads.start()
        self.addCleanup(busy_reads.stop)
        comms._watch_channel(channel)
        self.addCleanup(comms._closed.set)

        # Ctrl-C inside the wait in the FIFO: the lock is given back as it unwinds.
        with mock.patch.object(fifo, "recv", side_effect=KeyboardInterrupt):
            with self.assertRaises(KeyboardInterrupt):
                reader.wait(5.0)
        self.assertFalse(channel.take_lock.locked(), "Ctrl-C in recv() kept the take lock")
        self.assertFalse(reader.reading)

        # Ctrl-C after the wait took a sample, before woken() (in the queue's
        # `finally`): woken() never runs, and the lock is free all the same.
        fifo.put(sample_of(0))
        reader.wait(5.0)
        self.assertFalse(channel.take_lock.locked(), "held from wait() on to woken()")
        # ... and the order holds: what came after is stored after it.
        fifo.put(sample_of(1))
        reader.wait(5.0)
        reader.woken()
        self.assertEqual(data_of(node.scheduled[0]), [0, 1])
        comms.take_batch(node.scheduled[-1], node.scheduled[-1].id())
        self.assertTrue(channel.emptied.is_set(), "the FIFO is empty: nothing owed")

        # Ctrl-C while woken() queues the pages: the lock stays free.
        fifo.put(sample_of(2))
        reader.wait(5.0)
        with mock.patch.object(comms, "_take_waiting", side_effect=KeyboardInterrupt):
            with self.assertRaises(KeyboardInterrupt):
                reader.woken()
        self.assertFalse(channel.take_lock.locked(), "Ctrl-C in woken() kept the take lock")

        # The watcher, which needs the lock, still hands a burst over.
        reader.wait(5.0)  # what waits is taken on, as the node takes it after a Ctrl-C
        reader.woken()
        comms.take_batch(node.scheduled[-1], node.scheduled[-1].id())
        self.assertTrue(channel.emptied.is_set())
        scheduled = len(node.scheduled)
        reader.busy_since = time.monotonic() - 7200.0  # the node's thread has worked a while
        fifo.put(sample_of(3))
        self.assertTrue(wait_until(lambda: len(node.scheduled) > scheduled), "the watcher took it")
        comms._closed.set()
        comms._watchers[0].join(5)
        self.assertFalse(comms._watchers[0].is_alive(), "the watcher ends with the component")

    def test_a_wake_key_is_one_the_subscription_matches(self) -> None:
        from snr.extras.zenoh.comms import wake_key

        zenoh = _zenoh_module()
        for pattern, key in [
            ("lab/cmd", "lab/cmd"),
            ("lab/**", "lab/_snr_wake"),
            ("lab/*/x", "lab/_snr_wake/x"),
            ("lab/arm_$*", "lab/arm_"),
            ("lab/x$*y/**", "lab/xy/_snr_wake"),
        ]:
            with self.subTest(pattern=pattern):
                self.assertEqual(wake_key(pattern), key)
                self.assertTrue(zenoh.KeyExpr(pattern).includes(zenoh.KeyExpr(key)))
        self.assertIsNone(wake_key("lab/@node/**"), "verbatim chunks: no key is made up")

    def test_bad_samples_are_counted_and_the_first_five_explained(self) -> None:
        with self.assertLogs("snr", "WARNING") as logs:
            for _ in range(7):
                self.comms._bad_sample("snr/lab/x", WireFormatError("not JSON"))
        self.assertEqual(self.comms.stats()["bad_samples"], 7)
        self.assertEqual(len(logs.output), 5)
        self.assertIn("snr/lab/x", logs.output[0])
        self.assertIn("only counted", logs.output[-1])


class Pulse(ThreadLoop):
    """Stores 0, 1, 2, ... under ``key`` at ``hz`` once ``peers`` nodes have joined."""

    def __init__(self, factory: PulseFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, f"pulse_{factory.key}", max_tick_rate_hz=factory.hz)
        self.spec = factory
        self.joined: List[str] = []
        self.ready = threading.Event()
        self.sent = 0
        self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.on_joined}
        if factory.peers == 0:
            self.ready.set()

    def on_joined(self, task: Task, key: TaskId) -> SomeTasks:
        self.joined.append(task.val_list[1])
        if len(set(self.joined)) >= self.spec.peers:
            self.ready.set()
        return None

    def loop(self) -> None:
        if not self.ready.wait(0.1):
            return
        if self.sent < self.spec.count:
            self.store_data(self.spec.key, self.sent)
            self.sent += 1


class PulseFactory(LoopFactory):
    def __init__(self, key: str, count: int, hz: float, peers: int = 1) -> None:
        super().__init__()
        self.key, self.count, self.hz, self.peers = key, count, hz, peers

    def get(self, parent: AbstractNode) -> Pulse:
        return Pulse(self, parent)


class Tally(Endpoint):
    """Collects the data of pages under ``keys``; reports each key's list once ``count`` came."""

    def __init__(self, factory: TallyFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "tally")
        self.spec = factory
        self.seen: Dict[str, List[Any]] = {key: [] for key in factory.keys}
        self.task_handlers = {(TaskType.store_page, key): self.count for key in factory.keys}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        page: Page = task.val_list[0]
        seen = self.seen[page.key]
        seen.append(page.data)
        if len(seen) == self.spec.count:
            self.spec.writer.send(("tally", self.parent.role, page.key, page.origin, seen))
            self.seen[page.key] = []
        return None


class TallyFactory(EndpointFactory):
    def __init__(self, writer: Any, keys: Sequence[str], count: int) -> None:
        super().__init__()
        self.writer, self.keys, self.count = writer, list(keys), count

    def get(self, parent: AbstractNode) -> Tally:
        return Tally(self, parent)


class Stall(Endpoint):
    """Blocks the node's thread on the first page under ``key`` (a stuck handler),
    then stops the node once ``resume_after`` more pages have come."""

    def __init__(self, factory: StallFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "stall")
        self.spec = factory
        self.task_handlers = {(TaskType.store_page, factory.key): self.on_page}

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        data = task.val_list[0].data
        if self.spec.first is None:
            self.spec.first = data
            time.sleep(self.spec.stall_s)  # on purpose: what a stuck handler does
            return None
        self.spec.after.append(data)
        if len(self.spec.after) >= self.spec.resume_after:
            return tasks.terminate("pages flow again")
        return None


class StallFactory(EndpointFactory):
    def __init__(self, key: str, stall_s: float, resume_after: int) -> None:
        super().__init__()
        self.key, self.stall_s, self.resume_after = key, stall_s, resume_after
        self.first: Any = None
        self.after: List[int] = []

    def get(self, parent: AbstractNode) -> Stall:
        return Stall(self, parent)


@unittest.skipUnless(HAVE_ZENOH, NEEDS_ZENOH)
class TestZenohInOneProcess(unittest.TestCase):
    """Nodes on threads of this process, each with its own Zenoh session."""

    def run_nodes(self, config: Dict[str, List[Any]], roles: Sequence[str]) -> LocalNodes:
        safety = TimeoutLoopFactory(seconds=8)
        built = Config({role: [*f, safety] for role, f in config.items()}, mode=Mode.TEST)
        nodes = LocalNodes(built, roles)
        self.addCleanup(nodes.stop)
        return nodes

    def test_pages_arrive_in_order_with_their_fields_and_never_echo(self) -> None:
        count = 300
        ep = endpoint(free_port())
        nodes = self.run_nodes(
            {
                # The receiver publishes "n" too: pages it got from Zenoh must not go back.
                "receiver": [
                    comms("lab", publish=["n", "ack"], subscribe="*", listen=[ep]),
                    StopAfterFactory("n", count=count, then_store="ack", on_store=True),
                ],
                "sender": [
                    comms("lab", publish="n", subscribe="*", connect=[ep]),
                    SendOnConnectFactory("n", count),
                    StopAfterFactory("ack", on_store=True),
                ],
            },
            ["sender", "receiver"],
        )
        sender = nodes.wait_first()
        self.assertEqual(sender.terminate_reason, "got ack")
        receiver = nodes.nodes[1]
        self.assertEqual(receiver.get_page("n"), Page("n", count - 1, "sender", 1000.0 + count - 1))
        got, sent = zenoh_of(receiver).stats(), zenoh_of(sender).stats()
        nodes.stop()
        self.assertEqual(nodes.errors, [])
        self.assertEqual((got["received"], got["lost"], got["dropped"]), (count, 0, 0))
        self.assertEqual(got["published"], 1, "only the ack: received pages are never re-sent")
        self.assertEqual((sent["published"], sent["received"]), (count, 1))

    def test_an_idle_node_waits_in_zenoh_yet_wakes_for_its_own_loops(self) -> None:
        ep = endpoint(free_port())
        nodes = self.run_nodes(
            {
                # Published keys ("pong", "tick") are not the one it subscribes to,
                # so its thread waits in that subscription's FIFO when idle.
                "caller": [
                    comms("lab", publish="ping", subscribe="*", listen=[ep]),
                    PulseFactory("ping", 20, 200),
                    StopAfterFactory("tick", count=25, on_store=True),
                ],
                "echoer": [
                    comms("lab", publish=["pong", "tick"], subscribe="ping", connect=[ep]),
                    EchoFactory("ping", "pong"),
                    TickerFactory("tick", 50),
                ],
            },
            ["caller", "echoer"],
        )
        echoer = nodes.nodes[1]
        self.assertTrue(
            wait_until(lambda: zenoh_of(echoer)._reader is not None), "the echoer reads idle"
        )
        self.assertIs(echoer.queue.waiter, zenoh_of(echoer)._reader)
        # 25 ticks at 50 Hz: a loop's page wakes the node at once. Were it woken
        # only when its wait times out (1 s), 25 would take longer than the test.
        caller = nodes.wait_first()
        self.assertEqual(caller.terminate_reason, "got tick")
        self.assertIsNone(zenoh_of(caller)._reader, "'*' matches its own 'ping': no idle read")
        pong = caller.get_page("pong")
        self.assertEqual(pong.data if pong else None, 19, "every ping answered")
        nodes.stop()
        self.assertEqual(nodes.errors, [])
        self.assertIsNone(echoer.queue.waiter, "stopped: the node waits on its bell again")

    def test_a_node_with_sockets_and_zenoh_waits_on_one_and_hears_both(self) -> None:
        ep = endpoint(free_port())
        pair = SocketsPair(server_tuple=("127.0.0.1", free_port()))
        nodes = self.run_nodes(
            {
                "hub": [pair.server(), comms("lab", subscribe="z", listen=[ep])],
                "by_socket": [pair.client("s"), SendOnConnectFactory("s", 30)],
                "by_zenoh": [comms("lab", publish="z", connect=[ep]), PulseFactory("z", 30, 200)],
            },
            ["hub", "by_socket", "by_zenoh"],
        )
        hub = nodes.nodes[0]

        def heard(key: str) -> bool:
            page = hub.get_page(key)
            return page is not None and page.data == 29

        self.assertTrue(wait_until(lambda: heard("s") and heard("z"), 6.0), "both arrived")
        self.assertIsNotNone(hub.queue.waiter, "the hub waits on one of them when idle")
        nodes.stop()
        self.assertEqual(nodes.errors, [])

    def test_a_stuck_receiver_drops_what_waits_counted_and_recovers(self) -> None:
        logs = capture_test_logs(self)
        ep = endpoint(free_port())
        stall = StallFactory("n", stall_s=0.8, resume_after=20)
        nodes = self.run_nodes(
            {
                "receiver": [comms("lab", subscribe="n", listen=[ep], max_wait_s=0.2), stall],
                # "block": Zenoh would hold the sender while the receiver's FIFO is full
                "sender": [
                    comms("lab", publish="n", connect=[ep], congestion="block"),
                    PulseFactory("n", 100_000, 1000),
                ],
            },
            ["receiver", "sender"],
        )
        receiver = nodes.wait_first()
        self.assertEqual(receiver.terminate_reason, "pages flow again")
        dropped = zenoh_of(receiver).stats()["dropped"]
        lost = zenoh_of(receiver).stats()["lost"]
        nodes.stop()
        self.assertEqual(nodes.errors, [])
        self.assertGreater(dropped, 0, "what waited while the node was stuck was dropped")
        self.assertEqual(lost, 0, "dropped here (counted once), not lost on the way")
        said = [line for line in logs if "Dropped" in line and "pages from Zenoh" in line]
        self.assertTrue(said, f"the drop was said: {logs}")
        self.assertIn("a handler is stuck", said[0])
        self.assertGreater(stall.after[-1], stall.first + dropped, "later pages came through")

    def test_two_systems_on_the_same_endpoints_do_not_hear_each_other(self) -> None:
        ep = endpoint(free_port())
        nodes = self.run_nodes(
            {
                "listener": [
                    comms("red", subscribe="x", listen=[ep]),
                    StopAfterFactory("x", count=5, on_store=True),
                ],
                "speaker": [comms("red", publish="x", connect=[ep]), PulseFactory("x", 50, 100)],
                "stranger": [comms("blue", publish="x", subscribe="**", connect=[ep])],
            },
            ["listener", "speaker", "stranger"],
        )
        listener = nodes.wait_first()
        self.assertEqual(listener.terminate_reason, "got x")
        stranger = zenoh_of(nodes.nodes[2]).stats()
        nodes.stop()
        self.assertEqual(nodes.errors, [])
        self.assertEqual((stranger["received"], stranger["peers"]), (0, []))

    def test_nodes_in_client_mode_talk_through_a_router(self) -> None:
        ep = start_router(self)  # zenohd, where multicast is blocked
        nodes = self.run_nodes(
            {
                "topside": [
                    comms("lab", subscribe="n", mode="client", connect=[ep]),
                    StopAfterFactory("n", count=20, on_store=True),
                ],
                "robot": [
                    comms("lab", publish="n", mode="client", connect=[ep]),
                    SendOnConnectFactory("n", 20),
                ],
            },
            ["topside", "robot"],
        )
        topside = nodes.wait_first()
        self.assertEqual(topside.terminate_reason, "got n")
        self.assertEqual(topside.get_page("n"), Page("n", 19, "robot", 1019.0))
        nodes.stop()
        self.assertEqual(nodes.errors, [])

    def test_a_plain_zenoh_program_reads_snr_pages_and_publishes_to_snr(self) -> None:
        ep = endpoint(free_port())
        nodes = self.run_nodes(
            {
                "robot": [
                    comms("lab", publish="depth_m", subscribe="from_plain", listen=[ep]),
                    PulseFactory("depth_m", 1000, 50, peers=0),
                    StopAfterFactory("from_plain", on_store=True),
                ]
            },
            ["robot"],
        )
        plain = subprocess.Popen(
            [sys.executable, PLAIN_CLIENT, ep, "lab", "2"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        self.addCleanup(plain.__exit__, None, None, None)  # closes its pipes and waits
        self.addCleanup(plain.kill)
        assert plain.stdout is not None and plain.stdin is not None
        lines = [json.loads(plain.stdout.readline()) for _ in range(3)]
        self.assertEqual(plain.stdout.readline().strip(), "publishing")
        robot = nodes.wait_first()
        plain.stdin.write("stop\n")
        plain.stdin.flush()
        self.assertEqual(plain.wait(5), 0)
        self.assertEqual(robot.terminate_reason, "got from_plain")
        page = robot.get_page("from_plain")
        assert page is not None
        self.assertEqual((page.data, page.origin), (42, "zenoh"))
        samples, imported = lines[:2], lines[2]
        self.assertEqual(imported, {"snr_imported": False})
        for sample in samples:
            self.assertEqual(sample["key_expr"], "snr/lab/depth_m")
            self.assertEqual(sample["encoding"], "application/json")
            body = sample["payload"]
            self.assertEqual(
                sorted(body), ["created_at_s", "data", "key", "kind", "origin", "process", "v"]
            )
            self.assertEqual((body["v"], body["kind"], body["key"]), (1, "page", "depth_m"))
            self.assertEqual(body["origin"], "robot")
        self.assertEqual(samples[1]["payload"]["data"], samples[0]["payload"]["data"] + 1)


class Flood(ThreadLoop):
    """Stores 0, 1, 2, ... under ``key``, ``per_tick`` pages a tick, up to 1000 ticks a second."""

    def __init__(self, factory: FloodFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "flood", max_tick_rate_hz=1000)
        self.key, self.per_tick = factory.key, factory.per_tick
        self.sent = 0

    def loop(self) -> None:
        for _ in range(self.per_tick):
            self.store_data(self.key, self.sent)
            self.sent += 1


class FloodFactory(LoopFactory):
    def __init__(self, key: str, per_tick: int = 50) -> None:
        super().__init__()
        self.key, self.per_tick = key, per_tick

    def get(self, parent: AbstractNode) -> Flood:
        return Flood(self, parent)


class SlowHandler(Endpoint):
    """Takes half a millisecond for each page under ``key``: a receiver slower than its sender."""

    def __init__(self, factory: SlowHandlerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "slow_handler")
        self.task_handlers = {(TaskType.store_page, factory.key): self.on_page}

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        time.sleep(0.0005)  # on purpose: a handler slower than the pages come
        return None


class SlowHandlerFactory(EndpointFactory):
    def __init__(self, key: str) -> None:
        super().__init__()
        self.key = key

    def get(self, parent: AbstractNode) -> SlowHandler:
        return SlowHandler(self, parent)


class DaemonNodes:
    """Nodes on daemon threads: a node that hangs fails its test instead of the test run.

    ``stop`` asks from a daemon thread too (asking may be what hangs) and
    says which nodes did not stop within the time given.
    """

    def __init__(self, config: Config, roles: Sequence[str]) -> None:
        self.nodes = {role: Node(role, config) for role in roles}
        self.threads = {
            role: threading.Thread(target=node.loop, name=f"test-{role}", daemon=True)
            for role, node in self.nodes.items()
        }
        for thread in self.threads.values():
            thread.start()

    def comms_of(self, role: str) -> Any:
        return self.nodes[role].components["zenoh_comms"]

    def stop(self, roles: Sequence[str] = (), timeout_s: float = 5.0) -> List[str]:
        """Stop ``roles`` (default: all); the roles still running after ``timeout_s``."""
        roles = list(roles or self.nodes)
        for role in roles:
            asker = threading.Thread(
                target=self.nodes[role].set_terminate_flag, args=("test over",), daemon=True
            )
            asker.start()
        deadline = time.monotonic() + timeout_s
        for role in roles:
            self.threads[role].join(max(0.0, deadline - time.monotonic()))
        return [role for role in roles if self.threads[role].is_alive()]


@unittest.skipUnless(HAVE_ZENOH, NEEDS_ZENOH)
class TestZenohUnderFlood(unittest.TestCase):
    """A receiver slower than its sender: it stops, reloads and stays bounded."""

    def start(self, subscribe: Sequence[str] = ("n",), per_tick: int = 50) -> DaemonNodes:
        """A sender flooding a slow receiver subscribed to ``subscribe`` with pages under "n"."""
        capture_test_logs(self)
        ep = endpoint(free_port())
        safety = TimeoutLoopFactory(seconds=20)
        config = Config(
            {
                "receiver": [
                    comms("lab", subscribe=list(subscribe), listen=[ep]),
                    SlowHandlerFactory("n"),
                    safety,
                ],
                "sender": [
                    comms("lab", publish="n", connect=[ep]),
                    FloodFactory("n", per_tick),
                    safety,
                ],
            },
            mode=Mode.TEST,
        )
        nodes = DaemonNodes(config, ["receiver", "sender"])
        self.addCleanup(nodes.stop)
        return nodes

    def flood(self) -> DaemonNodes:
        """A sender flooding a slow receiver, until the receiver is well behind."""
        nodes = self.start()

        def behind() -> bool:  # more pages sent than the receiver's FIFO holds
            sent = int(nodes.comms_of("sender").published)
            return sent - int(nodes.comms_of("receiver").received) > 12_000

        self.assertTrue(wait_until(behind, 10.0), "the receiver fell behind")
        return nodes

    def test_a_receiver_behind_on_pages_stops_at_once(self) -> None:
        nodes = self.flood()
        self.assertEqual(nodes.stop(["receiver"]), [], "the receiver stopped")
        self.assertEqual(nodes.stop(), [])

    def test_a_receiver_behind_on_pages_reloads_its_comms_and_goes_on(self) -> None:
        nodes = self.flood()
        receiver = nodes.nodes["receiver"]
        old = nodes.comms_of("receiver")
        receiver.schedule(tasks.reload_component("zenoh_comms"))

        def reloaded_and_receiving() -> bool:
            new = nodes.comms_of("receiver")
            return new is not old and bool(new.received > 0)

        self.assertTrue(wait_until(reloaded_and_receiving, 5.0), "reloaded, pages come again")
        self.assertEqual(nodes.stop(), [], "both nodes stopped")

    def test_a_slow_receivers_queue_holds_at_most_a_batch_from_zenoh(self) -> None:
        from snr.extras.zenoh.comms import _BATCH

        # Under "n" the pages come through a watcher thread (the node's thread
        # waits in the FIFO of "x" when idle); some ticks the FIFO is empty a moment.
        nodes = self.start(subscribe=["x", "n"], per_tick=10)
        queue = nodes.nodes["receiver"].queue
        most = 0

        def well_ahead() -> bool:  # the receiver handles fewer than 2,000 pages a second
            nonlocal most
            most = max(most, len(queue))
            return int(nodes.comms_of("sender").published) >= 12_000

        self.assertTrue(wait_until(well_ahead, 10.0), "the sender went well ahead")
        self.assertGreater(nodes.comms_of("receiver").received, 0, "pages came")
        self.assertLessEqual(most, _BATCH + 10, "a batch of pages, and a task to take the next")
        self.assertEqual(nodes.stop(), [])


@unittest.skipUnless(HAVE_ZENOH, NEEDS_ZENOH)
class TestZenohProcesses(unittest.TestCase):
    def test_five_processes_exchange_pages_in_order_and_a_restarted_one_rejoins(self) -> None:
        ctx = zenoh_safe_context()
        reports = Reports(ctx)
        self.addCleanup(reports.close)
        roles = [f"n{i}" for i in range(5)]
        ports = [free_port() for _ in roles]
        count, hz = 40, 200

        def node(i: int) -> NodeProcess:
            others = [r for r in roles if r != roles[i]]
            factories = [
                comms(
                    "five",
                    publish=roles[i],
                    subscribe="*",
                    listen=[endpoint(ports[i])],
                    connect=[endpoint(p) for p in ports[:i]],
                ),
                PulseFactory(roles[i], count, hz, peers=len(others)),
                TallyFactory(reports.writer, others, count),
                EventReporterFactory(reports.writer, [COMMS_DISCONNECTED]),
            ]
            process = NodeProcess(ctx, roles[i], factories).start()
            self.addCleanup(process.kill)
            return process

        processes = [node(i) for i in range(5)]
        expected = list(range(count))

        def tallies(how_many: int, origin: str = "") -> List[Any]:
            found: List[Any] = []
            while len(found) < how_many:
                report = reports.wait_for(lambda r: r[0] == "tally", timeout_s=10.0)
                if not origin or report[3] == origin:
                    found.append(report)
            return found

        first = tallies(5 * 4)
        self.assertEqual(
            sorted((r[1], r[2]) for r in first), [(a, b) for a in roles for b in roles if a != b]
        )
        for _, role, key, origin, data in first:
            self.assertEqual((origin, data), (key, expected), f"{role} got {key} out of order")

        processes[4].kill()  # no goodbye: as if it crashed
        lost = [
            reports.wait_for(lambda r: r[0] == "event" and r[2] == COMMS_DISCONNECTED)
            for _ in range(4)
        ]
        self.assertEqual(sorted(r[1] for r in lost), roles[:4])
        self.assertTrue(all(r[3][1] == "n4" for r in lost), lost)

        processes[4] = node(4)  # the same role on the same port: it rejoins
        again = tallies(4, origin="n4")
        self.assertEqual(sorted(r[1] for r in again), roles[:4])
        for report in again:
            self.assertEqual(report[4], expected)
        for process in processes:  # stop them all at once, then wait
            if process.process.pid is not None:
                os.kill(process.process.pid, signal.SIGINT)
        for process in processes:
            self.assertEqual(process.join(5.0), 0)


if __name__ == "__main__":
    unittest.main()
