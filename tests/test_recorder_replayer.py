"""Recorder, PageReader, replayers: round trips, timing, bad files, a killed recorder."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
import time
import unittest
from typing import Dict, List, Sequence, Tuple
from unittest import mock

from snr import (
    AbstractFactory,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    Mode,
    MovingAvgFilterFactory,
    Node,
    Page,
    RecorderEndpointFactory,
    ReplayerLoopFactory,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.core import NodeCore, TestRunner
from snr.prelude import ConfigError, WireFormatError
from snr.std_mods import codec
from snr.std_mods.io import PageReader, TextReader, TextReplayerFactory, replayer
from snr.std_mods.io.replayer import MAX_GAP_S, MAX_PROBLEMS
from tests.helpers import StopWhenFactory
from tests.page_collector import PageCollectorFactory

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_role(role: str, factories: Sequence[AbstractFactory], timeout_s: float = 5.0) -> None:
    runner = TestRunner(role, Config({role: list(factories)}, mode=Mode.TEST), timeout_s)
    runner.run()
    assert not runner.timed_out, f"node {role!r} did not stop by itself"


def write_lines(path: str, lines: List[str], end: str = "\n") -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + end)


def page_line(key: str, data: object, created_at_s: float, origin: str = "robot") -> str:
    page = {"key": key, "data": data, "origin": origin, "created_at_s": created_at_s}
    return json.dumps(page)


HEADER = '{"format":"snr-pages","version":1}'


class TestRoundTrip(SNRTestCase):
    def test_replay_into_a_second_node_gives_identical_pages(self) -> None:
        path = self.temp_file(".jsonl")
        depths = [0.5, 0.75, 1.0, 1.5, 2.25]
        modes = ["dive", {"lights": True, "pwm": [1, 2]}, None]
        recorded = PageCollectorFactory(["depth_m", "mode"], stop_after=len(depths) + len(modes))
        run_role(
            "robot",
            [
                ListReplayerFactory(depths, "depth_m", period_s=0.002),
                ListReplayerFactory(modes, "mode", period_s=0.003),
                RecorderEndpointFactory(path, ["depth_m", "mode"]),
                recorded,
            ],
        )
        replayed = PageCollectorFactory(["depth_m", "mode"])
        run_role("sim", [ReplayerLoopFactory(path, fast=True, exit_when_done=True), replayed])

        self.assertEqual(len(recorded.pages), 8)
        self.assertEqual(replayed.pages, recorded.pages)  # key, data, origin, time, process
        self.assertEqual({p.origin for p in replayed.pages}, {"robot"})
        self.assertEqual(PageReader(path).problems, [])
        self.assertEqual(list(PageReader(path)), recorded.pages)

    def test_only_the_chosen_keys_are_recorded_and_replayed(self) -> None:
        path = self.temp_file(".jsonl")
        collected = PageCollectorFactory(["a", "b"], stop_after=4)
        run_role(
            "robot",
            [
                ListReplayerFactory([1, 2], "a"),
                ListReplayerFactory([3, 4], "b"),
                RecorderEndpointFactory(path, "a"),  # one key as a plain string
                collected,
            ],
        )
        self.assertEqual([p.data for p in PageReader(path)], [1, 2])
        replayed = PageCollectorFactory(["a"])
        run_role("sim", [ReplayerLoopFactory(path, True, True, keys=["b"]), replayed])
        self.assertEqual(replayed.pages, [])

    def test_original_timing_keeps_the_spacing_of_the_pages(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + [page_line("t", i, 1000.0 + 0.03 * i) for i in range(4)])
        replayed = PageCollectorFactory(["t"])
        run_role("sim", [ReplayerLoopFactory(path, exit_when_done=True), replayed])
        self.assertEqual(replayed.data(), [0, 1, 2, 3])
        span = replayed.arrived_s[-1] - replayed.arrived_s[0]
        self.assertGreaterEqual(span, 0.075)  # never early: 0.09 s recorded (a lower bound only)
        self.assertEqual(replayed.pages[3].created_at_s, 1000.0 + 0.03 * 3)

    def test_exit_when_done_lets_the_node_finish_what_the_pages_cause(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + [page_line("raw", float(i), 5.0 + i) for i in range(30)])
        averaged = PageCollectorFactory(["avg"])
        run_role(
            "sim",
            [
                ReplayerLoopFactory(path, fast=True, exit_when_done=True),
                MovingAvgFilterFactory("raw", "avg", 2),
                averaged,
            ],
        )
        self.assertEqual(len(averaged.pages), 30)
        self.assertEqual(averaged.data()[-1], 28.5)

    def test_a_replay_resumes_where_it_was_after_a_reload(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + [page_line("n", i, 1.0) for i in range(5)])
        factory = ReplayerLoopFactory(path, fast=True, exit_when_done=True)
        factory.position = 3  # what a reload keeps on the factory
        replayed = PageCollectorFactory(["n"])
        run_role("sim", [factory, replayed])
        self.assertEqual(replayed.data(), [3, 4])
        self.assertEqual(factory.position, 5)


class ReloadAt(Endpoint):
    def __init__(self, factory: ReloadAtFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "reload_at")
        self.at = factory.at
        self.task_handlers = {(TaskType.store_page, "n"): self.check}

    def check(self, task: Task, key: TaskId) -> SomeTasks:
        return tasks.reload_component("recorder") if task.val_list[0].data == self.at else None


class ReloadAtFactory(EndpointFactory):
    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def get(self, parent: AbstractNode) -> ReloadAt:
        return ReloadAt(self, parent)


class SilentCore(NodeCore):
    """A student's node core that drops a store_page task without a Page, saying nothing."""

    def store_page_handler(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.page()
        if page is not None:
            self.pages[page.key] = page
        return None


class SilentCoreFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> SilentCore:
        core = SilentCore(self, parent)
        core.task_handlers[TaskType.terminate] = lambda task, key: parent.set_terminate_flag("stop")
        return core


class TestRecorder(SNRTestCase):
    def test_a_store_page_task_without_a_page_is_said_whatever_the_node_core(self) -> None:
        path = self.temp_file(".jsonl")
        stop = StopWhenFactory((TaskType.store_page, "k"))
        robot = [RecorderEndpointFactory(path, ["k"]), stop]
        config = Config({"robot": robot}, mode=Mode.DEPLOYED, node_core=SilentCoreFactory())
        node = Node("robot", config)
        node.schedule(Task(TaskType.store_page, "k", ["not a page"]))
        with self.assertLogs("snr.robot", "WARNING") as logs:
            node.loop()
        self.assertEqual(
            logs.output,
            [
                "WARNING:snr.robot.recorder:A store_page task for 'k' carries "
                "['not a page'], not a Page"
            ],
        )
        self.assertEqual(list(PageReader(path)), [])

    def test_data_json_cannot_hold_is_reported_and_skipped(self) -> None:
        path = self.temp_file(".jsonl")
        values: List[object] = [1, {1, 2}, 2, object(), {3}, 3]
        with self.assertLogs("snr.robot.recorder", "ERROR") as logs:
            run_role(
                "robot",
                [
                    ListReplayerFactory(values, "k"),
                    RecorderEndpointFactory(path, ["k"]),
                    PageCollectorFactory(["k"], stop_after=len(values)),
                ],
            )
        self.assertEqual([p.data for p in PageReader(path)], [1, 2, 3])
        text = "\n".join(logs.output)
        self.assertIn("'k' to a recording or serial link: data is a set", text)
        self.assertIn("data is a object", text)
        self.assertEqual(len(logs.output), 3)  # the second set is only counted...
        self.assertIn("Pages under 'k' not recorded (set data): 1 more times", logs.output[2])
        self.assertIn("(2 in all)", logs.output[2])  # ...and the count logged at the end

    def test_a_reload_appends_to_the_same_file(self) -> None:
        path = self.temp_file(".jsonl")
        with self.assertLogs("snr.robot", "INFO") as logs:
            run_role(
                "robot",
                [
                    ListReplayerFactory(list(range(6)), "n", period_s=0.002),
                    RecorderEndpointFactory(path, ["n"]),
                    ReloadAtFactory(2),
                    PageCollectorFactory(["n"], stop_after=6),
                ],
            )
        self.assertTrue(any("Reloaded 'recorder'" in line for line in logs.output), logs.output)
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
        self.assertEqual(lines[0], HEADER)
        self.assertEqual(len(lines), 7)  # one header, six pages: nothing lost or repeated
        self.assertEqual([p.data for p in PageReader(path)], list(range(6)))

    def test_a_folder_that_does_not_exist_is_a_clear_error(self) -> None:
        path = os.path.join(self.temp_file(), "missing", "run.jsonl")
        with self.assertRaises(ConfigError) as caught:
            run_role("robot", [RecorderEndpointFactory(path, ["k"])])
        self.assertIn("missing", str(caught.exception))
        self.assertIn("folder", str(caught.exception))

    def test_keys_must_be_given(self) -> None:
        with self.assertRaises(ConfigError):
            RecorderEndpointFactory("run.jsonl", [])

    def test_every_page_is_on_disk_while_the_recorder_is_still_open(self) -> None:
        path = self.temp_file(".jsonl")
        seen: List[List[int]] = []

        class Reader(Endpoint):
            def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
                super().__init__(factory, parent, "reader")
                self.task_handlers = {(TaskType.store_page, "n"): self.read}

            def read(self, task: Task, key: TaskId) -> SomeTasks:
                seen.append([p.data for p in PageReader(path)])
                return None

        class ReaderFactory(EndpointFactory):
            def get(self, parent: AbstractNode) -> Reader:
                return Reader(self, parent)

        run_role(
            "robot",
            [
                ListReplayerFactory(list(range(5)), "n"),
                RecorderEndpointFactory(path, ["n"]),
                ReaderFactory(),
                PageCollectorFactory(["n"], stop_after=5),
            ],
        )
        self.assertEqual(seen, [list(range(i + 1)) for i in range(5)])

    def test_a_killed_process_keeps_every_flushed_page(self) -> None:
        path = self.temp_file(".jsonl")
        script = textwrap.dedent(
            f"""
            import os
            from snr import *

            class Killer(Endpoint):
                def __init__(self, factory, parent):
                    super().__init__(factory, parent, "killer")
                    self.task_handlers = {{(TaskType.store_page, "n"): self.maybe_kill}}

                def maybe_kill(self, task, key):
                    if task.val_list[0].data == 20:
                        os._exit(3)  # no clean-up at all, like kill -9

            class KillerFactory(EndpointFactory):
                def get(self, parent):
                    return Killer(self, parent)

            Node("robot", Config({{"robot": [
                ListReplayerFactory(list(range(50)), "n"),
                RecorderEndpointFactory({path!r}, ["n"]),
                KillerFactory(),
                TimeoutLoopFactory(seconds=10),
            ]}}, mode=Mode.TEST)).loop()
            """
        )
        done = subprocess.run(
            [sys.executable, "-c", script], cwd=ROOT, capture_output=True, timeout=30
        )
        self.assertEqual(done.returncode, 3, done.stderr.decode())
        reader = PageReader(path)
        self.assertEqual([p.data for p in reader], list(range(21)))
        self.assertEqual(reader.problems, [])


class TestPageReader(SNRTestCase):
    def test_bad_lines_are_reported_with_their_number_and_skipped(self) -> None:
        path = self.temp_file(".jsonl")
        lines = [
            HEADER,
            page_line("a", 1, 1.0),
            "not json at all",
            "[1, 2]",
            '{"key": "a", "origin": "x", "created_at_s": 1}',
            '{"key": "a", "data": 2, "created_at_s": "yesterday"}',
            "",
            page_line("a", 3, 2.0),
            '{"key": "a", "data": 4, "ori',
        ]
        write_lines(path, lines, end="")
        reader = PageReader(path)
        with self.assertLogs("snr.replay", "WARNING"):
            pages = list(reader)
        self.assertEqual([p.data for p in pages], [1, 3])
        self.assertEqual(len(reader.problems), 5)
        for number, problem in zip([3, 4, 5, 6, 9], reader.problems):
            self.assertIn(f".jsonl:{number}:", problem)
        self.assertIn("no 'data' field", reader.problems[2])
        self.assertIn("created_at_s", reader.problems[3])
        self.assertIn("cut short", reader.problems[4])

    def test_a_page_may_leave_out_origin_time_and_process(self) -> None:
        path = self.temp_file(".jsonl", '{"key":"temp","data":21.5}\n')
        (page,) = list(PageReader(path))
        self.assertEqual((page.key, page.data, page.origin, page.process), ("temp", 21.5, "", True))

    def test_a_newer_format_asks_to_upgrade(self) -> None:
        path = self.temp_file(".jsonl", '{"format":"snr-pages","version":99}\n')
        with self.assertRaises(WireFormatError) as caught:
            PageReader(path)
        self.assertIn("upgrade", str(caught.exception))

    def test_a_missing_file_is_a_clear_error_when_the_node_is_built(self) -> None:
        factory = ReplayerLoopFactory("no_such_recording.jsonl")  # fine until it is used
        with self.assertRaises(ConfigError) as caught:
            run_role("sim", [factory])
        self.assertIn("no_such_recording.jsonl", str(caught.exception))


class TestTextReplayer(SNRTestCase):
    def test_each_line_becomes_a_page(self) -> None:
        path = self.temp_file(".txt")
        with open(path, "wb") as f:
            f.write(b"$GPGGA,1\r\n$GPGGA,2\n\nlast line")
        collected = PageCollectorFactory(["nmea"])
        run_role("gps", [TextReplayerFactory(path, "nmea", exit_when_done=True), collected])
        self.assertEqual(collected.data(), ["$GPGGA,1", "$GPGGA,2", "", "last line"])
        self.assertEqual({p.origin for p in collected.pages}, {"gps"})

    def test_a_line_that_is_not_utf8_is_reported_and_kept(self) -> None:
        path = self.temp_file(".txt")
        with open(path, "wb") as f:
            f.write(b"ok\nbad \xff byte\n")
        reader = TextReader(path)
        with self.assertLogs("snr.replay", "WARNING"):
            self.assertEqual(list(reader), ["ok", "bad \ufffd byte"])
        self.assertIn(".txt:2:", reader.problems[0])

    def test_a_text_replay_resumes_where_it_was_after_a_reload(self) -> None:
        path = self.temp_file(".txt", "a\nb\nc\n")
        factory = TextReplayerFactory(path, "line", exit_when_done=True)
        factory.position = 2  # what a reload keeps on the factory
        collected = PageCollectorFactory(["line"])
        run_role("t", [factory, collected])
        self.assertEqual(collected.data(), ["c"])
        self.assertEqual(factory.position, 3)

    def test_period_spaces_the_lines(self) -> None:
        path = self.temp_file(".txt", "a\nb\nc\n")
        collected = PageCollectorFactory(["line"])
        run_role("t", [TextReplayerFactory(path, "line", 0.03, exit_when_done=True), collected])
        self.assertEqual(collected.data(), ["a", "b", "c"])
        self.assertGreaterEqual(collected.arrived_s[-1] - collected.arrived_s[0], 0.045)

    def test_a_text_replay_is_a_text_replayer_loop_with_only_text_options(self) -> None:
        path = self.temp_file(".txt", "a\n")
        factory = TextReplayerFactory(path, "line", exit_when_done=True)
        for recording_only in ("fast", "keys", "max_gap_s", "retimed", "bad_lines"):
            self.assertFalse(hasattr(factory, recording_only), recording_only)
        runner = TestRunner("t", Config({"t": [factory]}, mode=Mode.TEST), 5.0)
        runner.run()
        assert runner.node is not None
        loop = runner.node.components["text_replayer"]
        self.assertEqual(type(loop).__name__, "TextReplayerLoop")  # its messages name it


class TestPageObjects(SNRTestCase):
    def test_pages_are_the_dataclass_students_know(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER, page_line("x", [1, "two"], 3.5, origin="urov")])
        self.assertEqual(list(PageReader(path)), [Page("x", [1, "two"], "urov", 3.5, True)])


def bad_lines_of_every_kind() -> List[bytes]:
    """One line of each kind of damage a recording can hold (none is a page)."""
    page = '{"key":"n","data":1,"origin":"robot","created_at_s":%s}'
    return [
        b"[" * 100_000 + b"]" * 100_000,  # nested far too deep
        ('{"key":"n","data":' + "[" * 100_000 + "]" * 100_000 + "}").encode(),
        (page % ("9" * 400)).encode(),  # a time no double can hold
        (page % "1e999").encode(),
        (page % "Infinity").encode(),
        (page % "NaN").encode(),
        (page % "-1e400").encode(),
        b'{"key":"n","data":' + b"9" * 5000 + b"}",  # an integer over Python's limit
        b'{"key":"n","data":"\\ud800"}',  # a lone surrogate
        b"\xff\xfe not UTF-8 \x80",
        bytes(b for b in range(256) if b != 10),  # random bytes (no newline)
        b'{"key":7,"data":1}',  # wrong types
        b'{"key":"n","data":1,"created_at_s":"noon"}',
        b'{"key":"n","data":1,"process":"yes"}',
        b'{"format":"snr-pages","version":99}',  # a header of a newer SNR, mid-file
        b'{"format":"other","version":1}',
        b"x" * 5_000_000,  # a long line of junk
        b'{"key":"n","da',  # cut short
    ]


def write_with_bad_lines(
    path: str, rounds: int, created_s: float = 1000.0, spacing_s: float = 0.01
) -> int:
    """Good pages 0, 1, 2... with every kind of bad line between them; returns how many bad."""
    bad = bad_lines_of_every_kind()
    lines = [HEADER.encode()]
    n = 0
    for _ in range(rounds):
        for line in bad:
            lines.append(page_line("n", n, created_s + spacing_s * n).encode())
            lines.append(line)
            n += 1
    lines.append(page_line("n", n, created_s + spacing_s * n).encode())
    with open(path, "wb") as f:
        f.write(b"\n".join(lines) + b"\n")
    return rounds * len(bad)


class TestReplayNeverStopsOnData(SNRTestCase):
    def test_every_good_page_is_replayed_in_order_around_bad_lines(self) -> None:
        path = self.temp_file(".jsonl")
        bad = write_with_bad_lines(path, rounds=3)
        factory = ReplayerLoopFactory(path, fast=True, exit_when_done=True)
        replayed = PageCollectorFactory(["n"])
        with self.assertLogs("snr.replay", "WARNING") as logs:
            run_role("sim", [factory, replayed], timeout_s=30)
        self.assertEqual(bad, 54)
        self.assertEqual(replayed.data(), list(range(bad + 1)))
        self.assertEqual(factory.position, bad + 1)
        self.assertEqual(factory.bad_lines, bad)
        text = "\n".join(logs.output)
        for number in (3, 5, 7, 9, 11):  # the first five in full, with their line numbers
            self.assertIn(f".jsonl:{number}: skipped a bad line", text)
        self.assertIn(f"skipped {bad} bad lines in all (lines 3, 5, 7, 9, 11,", text)

    def test_any_error_from_a_line_skips_only_that_line(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + [page_line("n", i, 1.0) for i in range(6)])
        real = codec.page_from_fields

        def fragile(fields: Dict[str, object]) -> Page:
            errors = {1: RecursionError("deep"), 3: OverflowError("big"), 4: MemoryError()}
            data = fields.get("data")
            if isinstance(data, int) and data in errors:
                raise errors[data]
            return real(fields)

        factory = ReplayerLoopFactory(path, fast=True, exit_when_done=True)
        replayed = PageCollectorFactory(["n"])
        with mock.patch.object(replayer, "page_from_fields", fragile):
            with self.assertLogs("snr.replay", "WARNING") as logs:
                run_role("sim", [factory, replayed])
        self.assertEqual(replayed.data(), [0, 2, 5])
        text = "\n".join(logs.output)
        self.assertIn(".jsonl:3: skipped a bad line: RecursionError('deep')", text)
        self.assertIn(".jsonl:5: skipped a bad line: OverflowError('big')", text)
        self.assertIn(".jsonl:6: skipped a bad line: MemoryError()", text)

    def test_a_reader_keeps_the_first_problems_and_counts_them_all(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + ["junk"] * (MAX_PROBLEMS + 50) + [page_line("n", 1, 1.0)])
        reader = PageReader(path)
        with self.assertLogs("snr.replay", "WARNING"):
            self.assertEqual([p.data for p in reader], [1])
        self.assertEqual(reader.bad_lines, MAX_PROBLEMS + 50)
        self.assertEqual(len(reader.problems), MAX_PROBLEMS)

    def test_exit_when_done_fires_in_deployed_mode_despite_bad_lines(self) -> None:
        path = self.temp_file(".jsonl")
        bad = write_with_bad_lines(path, rounds=1, spacing_s=0.002)  # replayed in real time
        replayed = PageCollectorFactory(["n"])
        config = Config(
            {"sim": [ReplayerLoopFactory(path, exit_when_done=True, max_gap_s=0.05), replayed]},
            mode=Mode.DEPLOYED,
        )
        runner = TestRunner("sim", config, timeout_s=30)
        with self.assertLogs("snr.replay", "WARNING"):
            runner.run()
        self.assertFalse(runner.timed_out, "exit_when_done did not stop the DEPLOYED node")
        self.assertEqual(replayed.data(), list(range(bad + 1)))

    def test_a_done_event_scheduled_by_hand_with_only_its_rounds_stops_the_node(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + [page_line("n", i, 5.0 * i) for i in range(3)])  # 10 s
        factory = ReplayerLoopFactory(path, exit_when_done=True)
        node = Node("sim", Config({"sim": [factory]}, mode=Mode.TEST))
        for val_list in ([replayer.DRAIN_ROUNDS], [0]):
            node.schedule(tasks.event("replayer_done", val_list))  # [rounds] alone, by hand
        started = time.monotonic()
        with self.assertNoLogs("snr.sim", "WARNING"):
            node.loop()
        self.assertEqual(node.terminate_reason, f"replayed {path}")
        self.assertLess(time.monotonic() - started, 5.0, "the replay ran on to its end")

    def test_exit_when_done_fires_in_deployed_mode_when_the_loop_fails(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER] + [page_line("n", i, 1.0) for i in range(3)])
        config = Config(
            {"sim": [ReplayerLoopFactory(path, fast=True, exit_when_done=True)]},
            mode=Mode.DEPLOYED,
        )
        runner = TestRunner("sim", config, timeout_s=10)
        broken = mock.patch.object(
            replayer.ReplayerLoop, "store", side_effect=RuntimeError("disk gone")
        )
        with broken, self.assertLogs("snr.sim", "ERROR") as logs:
            runner.run()
        self.assertFalse(runner.timed_out, "exit_when_done did not stop the DEPLOYED node")
        self.assertIn("disk gone", "\n".join(logs.output))


class TestTimedReplayOfAbsurdTimes(SNRTestCase):
    def replay_timed(self, lines: List[str], max_gap_s: float = 0.05) -> Tuple[float, List[str]]:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER, *lines])
        replayed = PageCollectorFactory(["n"])
        factory = ReplayerLoopFactory(path, exit_when_done=True, max_gap_s=max_gap_s)
        started = time.monotonic()
        with self.assertLogs("snr.replay", "WARNING") as logs:
            run_role("sim", [factory, replayed], timeout_s=20)
        took = time.monotonic() - started
        self.assertEqual(replayed.data(), list(range(len(replayed.pages))))
        self.replayed = replayed
        return took, logs.output

    def test_a_time_far_in_the_future_waits_max_gap_only(self) -> None:
        took, logs = self.replay_timed(
            [
                page_line("n", 0, 1000.0),
                page_line("n", 1, 1e10),  # line 3: 263 years later
                page_line("n", 2, 1000.02),  # line 4: back to normal
                page_line("n", 3, 1e308),  # line 5
                page_line("n", 4, -1e308),  # line 6
                page_line("n", 5, 1000.04),
            ]
        )
        self.assertEqual(len(self.replayed.pages), 6)
        self.assertLess(took, 3.0)  # two clamped gaps of 0.05 s, and two of 0.02 s
        text = "\n".join(logs)
        self.assertIn(".jsonl:3: the page under 'n' was created 1e+10 s after", text)
        self.assertIn("waiting 0.05 s instead (max_gap_s)", text)
        self.assertIn(".jsonl:4: the time of the page under 'n' goes back by 1e+10 s", text)
        self.assertIn(".jsonl:5:", text)
        self.assertIn(".jsonl:6:", text)
        self.assertEqual(self.replayed.pages[1].created_at_s, 1e10)  # the page as recorded

    def test_infinite_and_unreadable_times_are_bad_lines(self) -> None:
        took, logs = self.replay_timed(
            [
                page_line("n", 0, 1000.0),
                '{"key":"n","data":-1,"created_at_s":1e999}',
                '{"key":"n","data":-1,"created_at_s":Infinity}',
                '{"key":"n","data":-1,"created_at_s":-Infinity}',
                '{"key":"n","data":-1,"created_at_s":' + "9" * 400 + "}",
                page_line("n", 1, 1000.02),
            ]
        )
        self.assertEqual(self.replayed.data(), [0, 1])
        self.assertLess(took, 3.0)
        text = "\n".join(logs)
        for number in (3, 4, 5, 6):
            self.assertIn(f".jsonl:{number}: skipped a bad line", text)

    def test_a_page_without_a_time_does_not_stall_the_replay(self) -> None:
        took, logs = self.replay_timed(
            [
                page_line("n", 0, 1000.0),
                '{"key":"n","data":1}',  # line 3: no created_at_s
                page_line("n", 2, 1000.02),
            ]
        )
        self.assertEqual(len(self.replayed.pages), 3)
        self.assertLess(took, 3.0)
        self.assertIn(".jsonl:3: the page under 'n' has no created_at_s", "\n".join(logs))

    def test_each_origin_keeps_its_own_clock(self) -> None:
        # Two nodes whose clocks disagree by years: each keeps its own spacing.
        lines = []
        for i in range(10):
            origin, base = ("urov", 1e9) if i % 2 else ("laptop", 1.7e9)
            lines.append(page_line("n", i, base + 0.01 * i, origin=origin))
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER, *lines])
        factory = ReplayerLoopFactory(path, exit_when_done=True, max_gap_s=0.5)
        replayed = PageCollectorFactory(["n"])
        started = time.monotonic()
        run_role("sim", [factory, replayed])  # no warning: nothing is out of the ordinary
        took = time.monotonic() - started
        self.assertEqual(replayed.data(), list(range(10)))
        self.assertEqual(factory.retimed, 0)
        self.assertLess(took, 2.0)  # 0.09 s recorded; clamping every switch would take 2.25 s
        self.assertGreaterEqual(replayed.arrived_s[-1] - replayed.arrived_s[0], 0.06)

    def test_each_page_waits_as_recorded_or_as_retimed(self) -> None:
        path = self.temp_file(".jsonl")
        lines = [
            page_line("n", 0, 1000.0),  # line 2: due now
            page_line("n", 1, 1000.02),
            page_line("n", 2, 1e10),  # line 4: a gap over max_gap_s
            page_line("n", 3, 1000.04),  # line 5: back
            '{"key":"n","data":4}',  # line 6: no time
            page_line("n", 5, 1000.06),
            page_line("n", 6, 5.0, origin="urov"),  # another origin starts its own clock
            page_line("n", 7, 5.01, origin="urov"),
        ]
        write_lines(path, [HEADER, *lines])
        factory = ReplayerLoopFactory(path, max_gap_s=0.05)
        clock = mock.Mock(monotonic=mock.Mock(return_value=100.0))  # the replayer's time only
        with mock.patch.object(replayer, "time", clock):
            with self.assertLogs("snr.replay", "WARNING") as logs:
                steps = list(factory.items())
        self.assertEqual([page.data for _, page in steps], list(range(8)))
        # The clock stands still, so each wait is counted from the first page:
        # +0.02, +0.05 (cut to max_gap_s), +0 (back), +0 (no time), +0.02, +0 (urov's first), +0.01.
        waits = [round(wait_s, 6) for wait_s, _ in steps]
        self.assertEqual(waits, [0.0, 0.02, 0.07, 0.07, 0.07, 0.09, 0.09, 0.1])
        self.assertEqual(factory.retimed, 3)
        summary = " (3 pages not stored at their recorded time; see the warnings above)"
        self.assertEqual(factory.summary(), summary)
        text = "\n".join(logs.output)
        self.assertIn(
            ".jsonl:4: the page under 'n' was created 1e+10 s after the one before it: "
            "waiting 0.05 s instead (max_gap_s).",
            text,
        )
        self.assertIn(
            ".jsonl:5: the time of the page under 'n' goes back by 1e+10 s: "
            "stored right after the previous page.",
            text,
        )
        self.assertIn(
            ".jsonl:6: the page under 'n' has no created_at_s: stored right after "
            "the previous page.",
            text,
        )
        fast = ReplayerLoopFactory(path, fast=True)
        self.assertEqual([wait_s for wait_s, _ in fast.items()], [0.0] * 8)
        self.assertEqual(fast.retimed, 0)

    def test_max_gap_must_be_a_sane_number_of_seconds(self) -> None:
        self.assertEqual(ReplayerLoopFactory("x.jsonl").max_gap_s, MAX_GAP_S)
        for bad in (-1.0, math.inf, math.nan, 1e300):
            with self.assertRaises(ConfigError):
                ReplayerLoopFactory("x.jsonl", max_gap_s=bad)


def record(
    path: str, values: Sequence[object], overwrite: bool = False, append: bool = False
) -> RecorderEndpointFactory:
    """Run a node that records ``values`` under "n" into ``path``; returns the factory."""
    recorder = RecorderEndpointFactory(path, ["n"], overwrite=overwrite, append=append)
    run_role(
        "robot",
        [
            ListReplayerFactory(list(values), "n"),
            recorder,
            PageCollectorFactory(["n"], stop_after=len(values)),
        ],
    )
    return recorder


class TestRecordingsAreNeverSilentlyReplaced(SNRTestCase):
    def test_a_second_run_keeps_the_first_recording(self) -> None:
        path = self.temp_file(".jsonl")
        first = record(path, [1, 2])
        self.assertEqual((first.path, first.kept), (path, None))
        with self.assertLogs("snr.robot.recorder", "INFO") as logs:
            second = record(path, [3, 4])
        self.assertEqual(second.path, path)  # the name given holds the latest run
        self.assertEqual([p.data for p in PageReader(path)], [3, 4])
        kept = second.kept
        assert kept is not None
        self.assertRegex(os.path.basename(kept), r"^file-\d{4}-\d\d-\d\dT\d\d-\d\d-\d\d\.jsonl$")
        self.assertEqual([p.data for p in PageReader(kept)], [1, 2])
        self.assertIn(f"the recording that was there is kept as {kept}", "\n".join(logs.output))
        third = record(path, [5])  # within the same second: a free name, nothing lost
        self.assertNotIn(third.kept, (None, kept))
        runs = sorted(os.listdir(os.path.dirname(path)))
        self.assertEqual(len(runs), 3, runs)
        self.assertEqual([p.data for p in PageReader(path)], [5])

    def test_a_file_without_pages_is_reused(self) -> None:
        for contents in ("", HEADER + "\n", "\n"):
            path = self.temp_file(".jsonl", contents)
            recorder = record(path, [1])
            self.assertIsNone(recorder.kept)
            self.assertEqual(os.listdir(os.path.dirname(path)), ["file.jsonl"])

    def test_a_file_that_is_not_a_recording_is_left_alone(self) -> None:
        path = self.temp_file(".py", "print('my robot program')\n")
        with self.assertRaises(ConfigError) as caught:
            record(path, [1])
        self.assertIn("not an SNR recording", str(caught.exception))
        self.assertIn("overwrite=True", str(caught.exception))
        with open(path, encoding="utf-8") as f:
            self.assertEqual(f.read(), "print('my robot program')\n")

    def test_overwrite_replaces_the_file(self) -> None:
        path = self.temp_file(".jsonl")
        record(path, [1, 2])
        recorder = record(path, [3], overwrite=True)
        self.assertIsNone(recorder.kept)
        self.assertEqual([p.data for p in PageReader(path)], [3])
        self.assertEqual(os.listdir(os.path.dirname(path)), ["file.jsonl"])

    def test_append_adds_each_run_to_one_file(self) -> None:
        path = self.temp_file(".jsonl")
        record(path, [1, 2], append=True)
        with open(path, "a", encoding="utf-8") as f:
            f.write('{"key":"n","da')  # the first run was killed mid-line
        record(path, [3], append=True)
        reader = PageReader(path)
        with self.assertLogs("snr.replay", "WARNING"):
            self.assertEqual([p.data for p in reader], [1, 2, 3])
        self.assertEqual(reader.bad_lines, 1)  # only the cut line; the new header is intact
        self.assertEqual(os.listdir(os.path.dirname(path)), ["file.jsonl"])

    def test_overwrite_and_append_together_are_refused(self) -> None:
        with self.assertRaises(ConfigError):
            RecorderEndpointFactory("run.jsonl", ["n"], overwrite=True, append=True)


def nested(depth: int) -> object:
    data: object = 1
    for _ in range(depth):
        data = [data]
    return data


class StorePages(Endpoint):
    """Stores hand-made pages, as a comms link stores what a remote node sent."""

    def __init__(self, factory: StorePagesFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "remote")
        self.pages = factory.pages

    def begin(self) -> None:
        for page in self.pages:
            self.parent.schedule(tasks.store_page(page))


class StorePagesFactory(EndpointFactory):
    def __init__(self, pages: List[Page]) -> None:
        super().__init__()
        self.pages = pages

    def get(self, parent: AbstractNode) -> StorePages:
        return StorePages(self, parent)


class TestTheRecorderKeepsTheNodeRunning(SNRTestCase):
    def test_pages_it_cannot_write_are_skipped_and_counted(self) -> None:
        path = self.temp_file(".jsonl")
        values = [0, nested(99), nested(100), 1, nested(100_000), 2, float("nan"), 3]
        with self.assertLogs("snr.robot.recorder", "ERROR") as logs:
            recorder = record(path, values)  # TEST mode: any error would stop the node
        self.assertEqual([p.data for p in PageReader(path)], [0, nested(99), 1, 2, 3])
        self.assertEqual((recorder.pages_written, recorder.pages_skipped), (5, 3))
        text = "\n".join(logs.output)
        self.assertIn("under 'n'", text)
        self.assertIn("more than 99 deep", text)

    def test_a_remote_page_nested_to_the_wire_limit_is_recorded(self) -> None:
        path = self.temp_file(".jsonl")
        deepest = Page("n", nested(99), "urov", 1.0)  # 100 deep with the page around it
        record_pages = [deepest, Page("n", 1, "urov", 2.0)]
        run_role(
            "robot",
            [
                StorePagesFactory(record_pages),
                RecorderEndpointFactory(path, ["n"]),
                PageCollectorFactory(["n"], stop_after=2),
            ],
        )
        self.assertEqual(list(PageReader(path)), record_pages)

    def test_hand_made_pages_a_reader_would_reject_are_skipped(self) -> None:
        path = self.temp_file(".jsonl")
        bad_times: List[object] = [10**400, float("inf"), "noon", None]
        pages = [Page("n", i, "urov", t) for i, t in enumerate(bad_times)]  # type: ignore[arg-type]
        pages.append(Page("n", 9, "urov", 5.0))
        with self.assertLogs("snr.robot.recorder", "ERROR") as logs:
            run_role(
                "robot",
                [
                    StorePagesFactory(pages),
                    RecorderEndpointFactory(path, ["n"]),
                    PageCollectorFactory(["n"], stop_after=len(pages)),
                ],
            )
        reader = PageReader(path)
        self.assertEqual([p.data for p in reader], [9])
        self.assertEqual(reader.problems, [])
        self.assertIn("created_at_s", "\n".join(logs.output))

    def test_any_error_while_encoding_skips_only_that_page(self) -> None:
        path = self.temp_file(".jsonl")
        real = codec.page_to_line

        def fragile(page: Page) -> str:
            if page.data == 2:
                raise RecursionError("maximum recursion depth exceeded")
            return real(page)

        with mock.patch("snr.std_mods.io.recorder.page_to_line", fragile):
            with self.assertLogs("snr.robot.recorder", "ERROR") as logs:
                recorder = record(path, [1, 2, 3])
        self.assertEqual([p.data for p in PageReader(path)], [1, 3])
        self.assertEqual(recorder.pages_skipped, 1)
        self.assertIn("under 'n'", logs.output[0])
        self.assertIn("RecursionError", logs.output[0])


class TestCreatedOrder(unittest.TestCase):
    def order(self, pages: List[Tuple[str, float, bool]], window: int = 1000) -> List[int]:
        recorded = [
            replayer.RecordedPage(line, Page("n", line, origin, at), timed)
            for line, (origin, at, timed) in enumerate(pages, start=2)
        ]
        return [r.line for r in replayer.in_created_order(recorded, 10.0, window)]

    def test_each_origin_in_created_order_in_its_own_places(self) -> None:
        pages = [("a", 2.0, True), ("b", 50.0, True), ("a", 1.0, True), ("b", 49.0, True)]
        self.assertEqual(self.order(pages), [4, 5, 2, 3])

    def test_untimed_pages_and_clock_jumps_keep_their_places(self) -> None:
        pages = [("a", 5.0, True), ("a", 0.0, False), ("a", 1e9, True), ("a", 4.0, True)]
        self.assertEqual(self.order(pages), [2, 3, 4, 5])

    def test_only_pages_within_the_window_swap(self) -> None:
        pages = [("a", 3.0, True), ("a", 2.0, True), ("a", 1.0, True)]
        self.assertEqual(self.order(pages, window=1), [3, 4, 2])  # one page of look-ahead
        self.assertEqual(self.order(pages), [4, 3, 2])
