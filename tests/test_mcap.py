"""MCAP recordings: written by the recorder, read by the mcap package, replayed, converted."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
import os
import shutil
import sys
import tempfile
import unittest
from typing import Any, Dict, List, Tuple
from unittest import mock

from snr import ListReplayerFactory, Page, RecorderEndpointFactory, ReplayerLoopFactory, SNRTestCase
from snr.__main__ import main
from snr.extras.viz.convert import convert_recording
from snr.extras.viz.mcap_files import (
    INSTALL_HINT,
    MCAP_MAGIC,
    McapPageWriter,
    log_time_ns,
    page_schema,
)
from snr.extras.viz.page_schema import data_schema as infer_schema
from snr.prelude import ConfigError
from snr.std_mods.codec import MAX_DEPTH, header_line, page_to_line
from snr.std_mods.io import PageReader
from tests.optional import HealthCheck, given, reason, settings, st
from tests.page_collector import PageCollectorFactory
from tests.test_recorder_replayer import ReloadAtFactory, bad_lines_of_every_kind, run_role

HAS_MCAP = importlib.util.find_spec("mcap") is not None
NEEDS_MCAP = reason("mcap")


def mcap_contents(path: str) -> Tuple[Any, List[Tuple[Any, Any, Any]]]:
    """The summary and (schema, channel, message) of every message, read by the mcap package."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = list(reader.iter_messages(log_time_order=False))
    return summary, messages


def write_jsonl(path: str, pages: List[Page]) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("".join(line + "\n" for line in [header_line(), *map(page_to_line, pages)]))


@unittest.skipUnless(HAS_MCAP, NEEDS_MCAP)
class TestRecordMcap(SNRTestCase):
    def test_the_mcap_package_reads_channels_schemas_messages_and_times(self) -> None:
        path = self.temp_file(".mcap")
        modes: List[object] = [{"lights": True, "pwm": [1, 2]}, "surface", None]
        recorded = PageCollectorFactory(["depth_m", "mode"], stop_after=6)
        run_role(
            "robot",
            [
                ListReplayerFactory([0, 0.5, 1.25], "depth_m", period_s=0.002),
                ListReplayerFactory(modes, "mode", period_s=0.002),
                RecorderEndpointFactory(path, ["depth_m", "mode"]),
                recorded,
            ],
        )
        summary, messages = mcap_contents(path)
        self.assertEqual(summary.statistics.message_count, 6)
        channels = {c.topic: c for c in summary.channels.values()}
        self.assertEqual(set(channels), {"/depth_m", "/mode"})
        for key in ("depth_m", "mode"):
            channel = channels["/" + key]
            self.assertEqual(channel.message_encoding, "json")
            self.assertEqual(channel.metadata["origin"], "robot")
            self.assertEqual(channel.metadata["key"], key)
            schema = summary.schemas[channel.schema_id]
            self.assertEqual(schema.encoding, "jsonschema")
            self.assertEqual(json.loads(schema.data)["type"], "object")
        depth_schema = json.loads(summary.schemas[channels["/depth_m"].schema_id].data)
        self.assertEqual(depth_schema["properties"]["data"], {"type": "number"})  # 0, then 0.5
        mode_schema = json.loads(summary.schemas[channels["/mode"].schema_id].data)
        self.assertEqual(
            mode_schema["properties"]["data"]["properties"]["pwm"]["items"], {"type": "number"}
        )
        by_message = {(m.log_time, c.topic): json.loads(m.data) for _, c, m in messages}
        for page in recorded.pages:  # every page, at its created_at_s, as its JSON line
            body = by_message[(log_time_ns(page.created_at_s), "/" + page.key)]
            self.assertEqual(body, json.loads(page_to_line(page)))
        self.assertEqual(list(PageReader(path)), recorded.pages)

    def test_replay_from_mcap_gives_the_recorded_pages_fast_and_timed(self) -> None:
        path = self.temp_file(".mcap")
        pages = [Page("t", i, "urov" if i % 2 else "sim", 1000.0 + 0.05 * i) for i in range(4)]
        with open(path, "wb") as f:
            writer = McapPageWriter(f)
            for page in pages:
                writer.write(page)
            writer.close()
        fast = PageCollectorFactory(["t"])
        run_role("sim", [ReplayerLoopFactory(path, fast=True, exit_when_done=True), fast])
        self.assertEqual(fast.pages, pages)  # origins and times too
        timed = PageCollectorFactory(["t"])
        run_role("sim", [ReplayerLoopFactory(path, exit_when_done=True), timed])
        self.assertEqual(timed.pages, pages)
        # Each origin's clock on its own: "sim" pages 0 and 2 are 0.1 s apart.
        self.assertGreaterEqual(timed.arrived_s[2] - timed.arrived_s[0], 0.08)

    def test_later_pages_that_do_not_fit_the_schema_are_still_recorded(self) -> None:
        path = self.temp_file(".mcap")
        values: List[object] = [None, 1, "two", [3], {"four": 4}, True]
        run_role(
            "robot",
            [
                ListReplayerFactory(values, "k"),
                RecorderEndpointFactory(path, "k"),
                PageCollectorFactory(["k"], stop_after=len(values)),
            ],
        )
        self.assertEqual([p.data for p in PageReader(path)], values)
        summary, _ = mcap_contents(path)
        (schema,) = summary.schemas.values()
        self.assertEqual(json.loads(schema.data)["properties"]["data"], {})  # None: any value

    def test_a_reload_goes_on_writing_the_same_file(self) -> None:
        path = self.temp_file(".mcap")
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
        summary, messages = mcap_contents(path)  # one finished file: its index counts all six
        self.assertEqual(summary.statistics.message_count, 6)
        self.assertEqual([json.loads(m.data)["data"] for _, _, m in messages], list(range(6)))

    def test_a_previous_recording_is_kept_and_compression_works(self) -> None:
        path = self.temp_file(".mcap")
        for values, compression in (([1, 2], None), ([3], "zstd")):
            factory = RecorderEndpointFactory(path, ["n"], compression=compression)
            run_role(
                "robot",
                [
                    ListReplayerFactory(values, "n"),
                    factory,
                    PageCollectorFactory(["n"], stop_after=len(values)),
                ],
            )
        assert factory.kept is not None
        self.assertEqual([p.data for p in PageReader(factory.kept)], [1, 2])
        self.assertEqual([p.data for p in PageReader(path)], [3])
        summary, _ = mcap_contents(path)
        self.assertEqual(summary.chunk_indexes[0].compression, "zstd")

    def test_options_that_do_not_fit_the_format_are_config_errors(self) -> None:
        for kwargs in (
            {"filename": "run.mcap", "append": True},
            {"filename": "run.jsonl", "compression": "zstd"},
            {"filename": "run.mcap", "compression": "gzip"},
            {"filename": "run.jsonl", "file_format": "bag"},
        ):
            with self.subTest(**kwargs), self.assertRaises(ConfigError):
                RecorderEndpointFactory(keys=["n"], **kwargs)
        explicit = RecorderEndpointFactory("run.log", ["n"], file_format="mcap")
        self.assertEqual(explicit.file_format, "mcap")

    def test_a_missing_compression_package_is_named_and_nothing_is_moved(self) -> None:
        path = self.temp_file(".mcap")
        with open(path, "wb") as f:
            f.write(MCAP_MAGIC)  # a recording: kept by renaming, if the recorder got that far
        with mock.patch.dict(sys.modules, {"zstandard": None}):
            with self.assertRaises(ConfigError) as caught:
                run_role("robot", [RecorderEndpointFactory(path, ["n"], compression="zstd")])
        message = str(caught.exception)
        self.assertIn("needs the zstandard package: " + INSTALL_HINT, message)
        self.assertIn("sudo apt install python3-lz4 python3-zstandard", message)
        self.assertEqual(os.listdir(os.path.dirname(path)), [os.path.basename(path)])


@unittest.skipUnless(HAS_MCAP, NEEDS_MCAP)
class TestReadMcap(SNRTestCase):
    def test_bad_messages_and_foreign_channels_are_reported_and_skipped(self) -> None:
        from mcap.writer import Writer

        path = self.temp_file(".mcap")
        bad = bad_lines_of_every_kind()
        with open(path, "wb") as f:
            writer = Writer(f)
            writer.start()
            snr_meta = {"key": "n", "origin": "robot", "format": "snr-pages", "version": "1"}
            snr = writer.register_channel("/n", "json", 0, snr_meta)
            other = writer.register_channel("/imu", "json", 0, {"origin": "px4"})
            cdr = writer.register_channel("/scan", "cdr", 0)
            for i, line in enumerate(bad):
                good = page_to_line(Page("n", i, "robot", 1.0 + i)).encode()
                writer.add_message(snr, log_time=i, data=good, publish_time=i)
                writer.add_message(snr, log_time=i, data=line, publish_time=i)
            writer.add_message(other, log_time=2_500_000_000, data=b'{"ax":1}', publish_time=0)
            writer.add_message(cdr, log_time=0, data=b"\x00\x01", publish_time=0)
            writer.finish()
        reader = PageReader(path)
        with self.assertLogs("snr.replay", "WARNING") as logs:
            pages = list(reader)
        self.assertEqual([p.data for p in pages[:-1]], list(range(len(bad))))
        self.assertEqual(pages[-1], Page("imu", {"ax": 1}, "px4", 2.5))
        self.assertEqual(reader.bad_lines, len(bad) + 1)
        self.assertIn("message 2: skipped a bad message", reader.problems[0])
        self.assertIn("'cdr' messages; SNR reads JSON channels only", reader.problems[-1])
        self.assertIn(f"skipped {len(bad) + 1} bad messages in all", logs.output[-1])

    def test_a_file_cut_short_gives_every_message_before_the_cut(self) -> None:
        path = self.temp_file(".mcap")
        f = open(path, "wb")  # noqa: SIM115 - left unfinished, as by a killed recorder
        writer = McapPageWriter(f)
        for i in range(5):
            writer.write(Page("n", i, "robot", float(i)))
        f.close()
        for cut in (0, 7):  # no index; or the last message half written
            with self.subTest(cut=cut):
                if cut:
                    os.truncate(path, os.path.getsize(path) - cut)
                reader = PageReader(path)
                with self.assertLogs("snr.replay", "WARNING"):
                    data = [p.data for p in reader]
                self.assertEqual(data, list(range(5 if not cut else 4)))
                self.assertEqual(reader.bad_lines, 1)
                self.assertIn("cut short", reader.problems[0])


# Every value a JSON-lines file can hold, as read back: the wire format's JSON.
json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(min_value=-(10**40), max_value=10**40)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(), inner, max_size=4),
    max_leaves=12,
)
pages = st.builds(
    Page,
    key=st.text(min_size=1, max_size=8),
    data=json_values,
    origin=st.text(max_size=8),
    created_at_s=st.floats(allow_nan=False, allow_infinity=False),
    process=st.booleans(),
)


@unittest.skipUnless(HAS_MCAP, NEEDS_MCAP)
class TestConvert(unittest.TestCase):
    def setUp(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-mcap-")
        self.addCleanup(shutil.rmtree, self.folder, True)

    def path(self, name: str) -> str:
        return os.path.join(self.folder, name)

    def round_trip(self, recorded: List[Page], compression: str = "none") -> None:
        source, mcap, back = self.path("a.jsonl"), self.path("a.mcap"), self.path("b.jsonl")
        write_jsonl(source, recorded)
        there = convert_recording(source, mcap, compression, overwrite=True)
        again = convert_recording(mcap, back, overwrite=True)
        self.assertEqual((there.pages, again.pages), (len(recorded), len(recorded)))
        with open(source, "rb") as a, open(back, "rb") as b:
            self.assertEqual(a.read(), b.read())  # byte for byte
        self.assertEqual(list(PageReader(mcap)), list(PageReader(source)))
        summary, messages = mcap_contents(mcap)
        self.assertEqual(summary.statistics.message_count, len(recorded))
        times = [m.log_time for _, _, m in messages]
        self.assertEqual(times, [log_time_ns(p.created_at_s) for p in recorded])

    @settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.lists(pages, min_size=1, max_size=4))
    def test_jsonl_to_mcap_to_jsonl_is_lossless(self, recorded: List[Page]) -> None:
        self.round_trip(recorded)

    def test_the_extremes_of_the_wire_format_survive(self) -> None:
        deep: Any = 0
        for _ in range(MAX_DEPTH - 2):  # data may nest 99 deep, the page object included
            deep = [deep]
        extremes = [
            Page("deep", deep, "robot", 0.0),
            Page("big", 10**4000, "", -1e300, False),  # times MCAP's clock cannot hold
            Page("\u00e9t\u00e9 \U0001f600", {"\u2603": 5e-324, "": -0.0}, "\n", 1e300),
            Page("/odd/topic", [1, 2.5, None, "x"], "urov", 1700000000.123456),
        ]
        self.round_trip(extremes, compression="lz4")

    def test_the_command_converts_and_refuses_to_overwrite(self) -> None:
        source = self.path("run.jsonl")
        write_jsonl(source, [Page("depth_m", 2.5, "urov", 1.0)])
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            self.assertEqual(main(["convert", source, self.path("run.mcap")]), 0)
            self.assertEqual(main(["convert", source, self.path("run.mcap")]), 1)
            self.assertEqual(main(["convert", source, source]), 1)
        self.assertIn("Converted 1 pages from", out.getvalue())
        self.assertIn("(JSON lines) to", out.getvalue())
        lines = err.getvalue().splitlines()
        self.assertEqual(len(lines), 2)
        self.assertIn("--overwrite", lines[0])
        self.assertIn("into itself", lines[1])


class TestWithoutMcap(SNRTestCase):
    """What someone who did not install the mcap extra sees: one line naming the command."""

    def setUp(self) -> None:
        hidden: Dict[str, Any] = {name: None for name in sys.modules if name.startswith("mcap")}
        hidden.update({"mcap": None, "mcap.writer": None, "mcap.stream_reader": None})
        patcher = mock.patch.dict(sys.modules, hidden)
        patcher.start()
        self.addCleanup(patcher.stop)

    def test_recording_to_mcap_says_what_to_install(self) -> None:
        path = self.temp_file(".mcap")
        with self.assertRaises(ConfigError) as caught:
            run_role("robot", [RecorderEndpointFactory(path, ["n"])])
        message = str(caught.exception)
        self.assertIn(INSTALL_HINT, message)
        self.assertNotIn("\n", message)
        self.assertFalse(os.path.exists(path))  # no empty file left behind

    def test_converting_says_what_to_install_in_one_line(self) -> None:
        source = self.temp_file(".jsonl", header_line() + "\n")
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            code = main(["convert", source, source[: -len(".jsonl")] + ".mcap"])
        self.assertEqual(code, 1)
        self.assertEqual(err.getvalue().count("\n"), 1)
        self.assertIn(INSTALL_HINT, err.getvalue())

    def test_reading_an_mcap_file_says_what_to_install(self) -> None:
        path = self.temp_file(".mcap")
        with open(path, "wb") as f:
            f.write(MCAP_MAGIC)
        with self.assertRaises(ConfigError) as caught:
            PageReader(path)
        self.assertIn(INSTALL_HINT, str(caught.exception))
        self.assertNotIn("\n", str(caught.exception))

    def test_json_lines_need_no_mcap(self) -> None:
        path = self.temp_file(".jsonl")
        run_role(
            "robot",
            [
                ListReplayerFactory([1], "n"),
                RecorderEndpointFactory(path, ["n"]),
                PageCollectorFactory(["n"], stop_after=1),
            ],
        )
        self.assertEqual([p.data for p in PageReader(path)], [1])


class TestSchemaInference(unittest.TestCase):
    def test_each_kind_of_value(self) -> None:
        cases: List[Tuple[object, Dict[str, Any]]] = [
            (2.5, {"type": "number"}),
            (3, {"type": "number"}),  # may be 3.5 next time
            (True, {"type": "boolean"}),
            ("dive", {"type": "string"}),
            (None, {}),
            ([], {"type": "array", "items": {}}),
            ([1, 2.5], {"type": "array", "items": {"type": "number"}}),
            ([1, "x"], {"type": "array", "items": {}}),
            (
                {"pose": {"x": 1.0}, "ok": False},
                {
                    "type": "object",
                    "properties": {
                        "pose": {"type": "object", "properties": {"x": {"type": "number"}}},
                        "ok": {"type": "boolean"},
                    },
                },
            ),
        ]
        for value, expected in cases:
            with self.subTest(value=value):
                self.assertEqual(infer_schema(value), expected)
        self.assertEqual(page_schema("d", 1.0)["properties"]["data"], {"type": "number"})
