"""Pictures of a run: `read_recording`'s columns and ``python -m snr plot``'s PNG files."""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import shutil
import sys
import tempfile
import unittest
from typing import Any, List, Optional, Sequence, Tuple
from unittest import mock

import snr
from snr.__main__ import main as snr_main
from snr.extras.plot import read_recording
from snr.prelude import ConfigError, Page
from snr.prelude.install import install_hint
from snr.std_mods.codec import header_line, page_to_line
from tests.optional import needs

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
DOCS_PAGE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs")


def dive_pages() -> List[Page]:
    """A short run: a number, a dict of numbers, a list of numbers and a string, interleaved."""
    pages: List[Page] = []
    for i in range(5):
        t = 1000.0 + i
        pages.append(Page("depth_m", 1.0 + i, "urov", t))
        pages.append(Page("pos", {"x": i, "y": 2.5 * i}, "urov", t + 0.25))
        pages.append(Page("imu", [i, -i, 0.5], "urov", t + 0.5))
        pages.append(Page("mode", "dive", "topside", t + 0.75))
    return pages


def run_snr(argv: Sequence[str]) -> Tuple[int, str, str]:
    """``python -m snr ARGV`` in this process: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = snr_main(list(argv))
        except SystemExit as stop:
            code = stop.code if isinstance(stop.code, int) else 1
    return code, out.getvalue(), err.getvalue()


class TempFolder(unittest.TestCase):
    folder: str

    def setUp(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="snr-plot-")
        self.addCleanup(shutil.rmtree, self.folder, ignore_errors=True)

    def path(self, name: str) -> str:
        return os.path.join(self.folder, name)

    def write_jsonl(self, name: str, pages: List[Page], extra: Optional[List[str]] = None) -> str:
        """A recording as the recorder writes it: the header, then a page per line."""
        lines = [header_line(), *map(page_to_line, pages), *(extra or [])]
        with open(self.path(name), "w", encoding="ascii") as file:
            file.write("\n".join(lines) + "\n")
        return self.path(name)


class TestReadRecording(TempFolder):
    def test_columns_hold_times_data_origins_and_numeric_fields(self) -> None:
        run = read_recording(self.write_jsonl("dive.jsonl", dive_pages()))
        self.assertEqual(list(run), ["depth_m", "pos", "imu", "mode"])
        self.assertEqual(run.start_s, 1000.0)
        self.assertEqual(run.problems, [])
        depth = run["depth_m"]
        self.assertEqual(depth.t_s, [0.0, 1.0, 2.0, 3.0, 4.0])
        self.assertEqual(depth.data, [1.0, 2.0, 3.0, 4.0, 5.0])
        self.assertEqual(depth.fields, {"depth_m": [1.0, 2.0, 3.0, 4.0, 5.0]})
        self.assertEqual(run["pos"].t_s[:2], [0.25, 1.25])
        self.assertEqual(run["pos"].fields["y"], [0.0, 2.5, 5.0, 7.5, 10.0])
        self.assertEqual(run["pos"].data[1], {"x": 1, "y": 2.5})
        self.assertEqual(list(run["imu"].fields), ["0", "1", "2"])
        self.assertEqual(run["imu"].fields["1"], [0.0, -1.0, -2.0, -3.0, -4.0])
        mode = run["mode"]
        self.assertEqual(mode.origin, ["topside"] * 5)
        self.assertEqual(mode.fields, {})
        self.assertEqual(mode.not_numeric, "page 1 of 'mode' holds 'dive' (str)")

    def test_snr_exports_it_and_keys_limit_what_is_read(self) -> None:
        path = self.write_jsonl("dive.jsonl", dive_pages())
        run = snr.read_recording(path, ["pos"])
        self.assertEqual(list(run), ["pos"])

    def test_a_field_missing_from_a_page_is_nan_and_bad_lines_are_listed(self) -> None:
        pages = [Page("pos", {"x": 1}, "urov", 5.0), Page("pos", {"x": 2, "y": 3}, "urov", 6.0)]
        with self.assertLogs("snr.replay", "WARNING"):  # the bad line, logged as a replay does
            run = read_recording(self.write_jsonl("gap.jsonl", pages, ["{not json"]))
        self.assertEqual(run["pos"].fields["x"], [1.0, 2.0])
        self.assertTrue(math.isnan(run["pos"].fields["y"][0]), run["pos"].fields)
        self.assertEqual(run["pos"].fields["y"][1], 3.0)
        self.assertEqual(len(run.problems), 1, run.problems)
        self.assertIn("gap.jsonl:4", run.problems[0])

    def test_a_key_not_in_it_names_the_keys_that_are(self) -> None:
        path = self.write_jsonl("dive.jsonl", dive_pages())
        expected = (
            f"{path!r} holds no page of key 'dept_m'; its keys are 'depth_m', 'pos', 'imu', "
            "'mode'. Did you mean 'depth_m'?"
        )
        with self.assertRaises(ConfigError) as asked:
            read_recording(path)["dept_m"]
        self.assertEqual(str(asked.exception), expected)
        self.assertNotIn("dept_m", read_recording(path))
        with self.assertRaises(ConfigError) as filtered:
            read_recording(path, ["dept_m"])
        self.assertEqual(str(filtered.exception), expected)
        self.assertIsNone(read_recording(path).get("dept_m"))

    def test_a_missing_file_and_a_file_that_is_not_a_recording_are_named(self) -> None:
        with self.assertRaises(ConfigError) as missing:
            read_recording(self.path("nope.jsonl"))
        self.assertIn("'nope.jsonl'", str(missing.exception).replace(self.folder + os.sep, ""))
        self.assertIn("no such file", str(missing.exception))
        notes = self.path("notes.txt")
        with open(notes, "w", encoding="utf-8") as file:
            file.write("depth was fine\n" * 50)
        with self.assertRaises(ConfigError) as not_one:
            read_recording(notes)  # refused at line 1, without a warning per line
        text = str(not_one.exception)
        self.assertTrue(text.startswith(f"{notes!r} is not a recording: its first line"), text)
        self.assertIn("'depth was fine'", text)
        self.assertIn("RecorderEndpointFactory", text)

    @needs("mcap")
    def test_an_mcap_recording_gives_the_same_columns(self) -> None:
        from snr.extras.viz.mcap_files import McapPageWriter

        path = self.path("dive.mcap")
        with open(path, "wb") as file:
            writer = McapPageWriter(file)
            for page in dive_pages():
                writer.write(page)
            writer.close()
        from_mcap = read_recording(path)
        from_lines = read_recording(self.write_jsonl("dive.jsonl", dive_pages()))
        self.assertEqual(list(from_mcap), list(from_lines))
        for key in from_lines:
            self.assertEqual(from_mcap[key], from_lines[key], key)


class TestPlotCommand(TempFolder):
    @needs("matplotlib")
    def test_it_writes_a_png_with_a_subplot_per_key(self) -> None:
        path = self.write_jsonl("dive.jsonl", dive_pages())
        target = self.path("out.png")
        code, out, err = run_snr(["plot", path, "depth_m", "pos", "imu", "-o", target])
        self.assertEqual((code, err), (0, ""), err)
        self.assertEqual(out, f"Drew depth_m, pos, imu from {path} in {target}\n")
        with open(target, "rb") as file:
            png = file.read()
        self.assertTrue(png.startswith(PNG_SIGNATURE), png[:16])
        self.assertGreater(len(png), 10_000)  # three subplots with lines, not an empty image

    @needs("matplotlib")
    def test_by_default_it_writes_the_recording_s_name_here(self) -> None:
        path = self.write_jsonl("dive.jsonl", dive_pages())
        here = os.getcwd()
        os.chdir(self.folder)
        self.addCleanup(os.chdir, here)
        code, out, err = run_snr(["plot", path, "depth_m"])
        self.assertEqual(code, 0, err)
        written = os.path.join(os.path.realpath(self.folder), "dive.png")
        self.assertTrue(os.path.isfile(written), os.listdir(self.folder))
        self.assertTrue(out.rstrip().endswith("dive.png"), out)

    @needs("matplotlib")
    def test_a_key_that_is_not_numbers_or_not_there_is_refused(self) -> None:
        path = self.write_jsonl("dive.jsonl", dive_pages())
        code, _, err = run_snr(["plot", path, "depth_m", "mode", "-o", self.path("x.png")])
        self.assertEqual(code, 1)
        self.assertEqual(
            err,
            f"snr plot: Cannot draw 'mode': only numbers, or dicts or lists of numbers, are "
            f"drawn, and in {path!r} page 1 of 'mode' holds 'dive' (str). Draw another key, or "
            "read it with snr.read_recording and plot it your way.\n",
        )
        code, _, err = run_snr(["plot", path, "pso", "-o", self.path("x.png")])
        self.assertEqual(code, 1)
        self.assertIn("holds no page of key 'pso'", err)
        self.assertIn("Did you mean 'pos'?", err)
        self.assertFalse(os.path.exists(self.path("x.png")))

    def test_without_matplotlib_it_says_how_to_install_it(self) -> None:
        path = self.write_jsonl("dive.jsonl", dive_pages())
        hidden: Any = {name: None for name in sys.modules if name.split(".")[0] == "matplotlib"}
        hidden.update({"matplotlib": None, "matplotlib.figure": None})
        with mock.patch.dict(sys.modules, hidden):
            code, out, err = run_snr(["plot", path, "depth_m", "-o", self.path("x.png")])
        self.assertEqual((code, out), (1, ""))
        self.assertEqual(
            err,
            "snr plot: drawing a recording needs matplotlib, which is not installed: "
            f"{install_hint('plot')}\n",
        )
        self.assertFalse(os.path.exists(self.path("x.png")))

    def test_help_says_what_it_does(self) -> None:
        code, out, err = run_snr(["plot", "--help"])
        self.assertEqual((code, err), (0, ""))
        self.assertTrue(out.startswith("usage: snr plot [-h] [-o FILE] recording KEY"), out)
        self.assertIn("one subplot per key", " ".join(out.split()))


class TestTheDocsSection(TempFolder):
    """docs/recording.md, "Pictures of a run": its commands and its notebook code run."""

    section: str

    def setUp(self) -> None:
        super().setUp()
        with open(os.path.join(DOCS_PAGE, "recording.md"), encoding="utf-8") as file:
            page = file.read()
        self.section = page.split("## Pictures of a run", 1)[1].split("\n## ", 1)[0]
        pages = [Page("depth_m", 0.1 * i, "urov", 50.0 + i) for i in range(5)]
        pages += [Page("imu", {"pitch": i, "roll": -i}, "urov", 50.5 + i) for i in range(5)]
        pages += [Page("mode", "dive", "urov", 51.0)]
        self.write_jsonl("dive.jsonl", pages)
        here = os.getcwd()
        os.chdir(self.folder)
        self.addCleanup(os.chdir, here)

    @needs("matplotlib")
    def test_each_plot_command_writes_its_picture(self) -> None:
        commands = re.findall(r"^python -m snr (plot .*)$", self.section, re.M)
        self.assertEqual(len(commands), 2, self.section)
        for command in commands:
            with self.subTest(command=command):
                code, out, err = run_snr(command.split())
                self.assertEqual((code, err), (0, ""), command)
                written = out.rstrip().rsplit(" in ", 1)[1]
                with open(written, "rb") as file:
                    self.assertTrue(file.read(8) == PNG_SIGNATURE, written)
        self.assertEqual(sorted(os.listdir(".")), ["dive.jsonl", "dive.png", "dive_imu.png"])

    @needs("matplotlib")
    def test_the_notebook_code_runs(self) -> None:
        import matplotlib

        matplotlib.use("Agg")  # no window in a test
        import matplotlib.pyplot as plt

        blocks = re.findall(r"```python\n(.*?)```", self.section, re.S)
        self.assertEqual(len(blocks), 1, self.section)
        printed = io.StringIO()
        with mock.patch.object(plt, "show"), contextlib.redirect_stdout(printed):
            exec(compile(blocks[0], "recording.md", "exec"), {})
        plt.close("all")
        self.assertEqual(printed.getvalue(), "['depth_m', 'imu', 'mode']\n")


if __name__ == "__main__":
    unittest.main()
