"""Recorder, PageReader, replayers: round trips, timing, bad files, a killed recorder."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from typing import List, Sequence

from snr import (
    AbstractFactory,
    AbstractNode,
    Config,
    ConfigError,
    Endpoint,
    EndpointFactory,
    ListReplayerFactory,
    Mode,
    MovingAvgFilterFactory,
    Page,
    PageReader,
    RecorderEndpointFactory,
    ReplayerLoopFactory,
    SNRTestCase,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    TestRunner,
    TextReader,
    TextReplayerFactory,
    WireFormatError,
    tasks,
)
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
        write_lines(path, [HEADER] + [page_line("t", i, 1000.0 + 0.1 * i) for i in range(4)])
        replayed = PageCollectorFactory(["t"])
        run_role("sim", [ReplayerLoopFactory(path, exit_when_done=True), replayed])
        self.assertEqual(replayed.data(), [0, 1, 2, 3])
        span = replayed.arrived_s[-1] - replayed.arrived_s[0]
        self.assertGreaterEqual(span, 0.25)  # never early: 0.3 s recorded (a lower bound only)
        self.assertEqual(replayed.pages[3].created_at_s, 1000.3)

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


class TestRecorder(SNRTestCase):
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
        self.assertEqual(len(logs.output), 2)  # the second set is skipped quietly

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

    def test_period_spaces_the_lines(self) -> None:
        path = self.temp_file(".txt", "a\nb\nc\n")
        collected = PageCollectorFactory(["line"])
        run_role("t", [TextReplayerFactory(path, "line", 0.1, exit_when_done=True), collected])
        self.assertEqual(collected.data(), ["a", "b", "c"])
        self.assertGreaterEqual(collected.arrived_s[-1] - collected.arrived_s[0], 0.15)


class TestPageObjects(SNRTestCase):
    def test_pages_are_the_dataclass_students_know(self) -> None:
        path = self.temp_file(".jsonl")
        write_lines(path, [HEADER, page_line("x", [1, "two"], 3.5, origin="urov")])
        self.assertEqual(list(PageReader(path)), [Page("x", [1, "two"], "urov", 3.5, True)])
