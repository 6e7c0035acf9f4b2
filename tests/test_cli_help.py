"""The command line's own words: ``snr --help``, each command's help, the console's name.

``snr console`` and ``snr-console`` are one program reached by two names; its
usage line and messages must show the name that was typed. Every command of
``snr`` (``python -m snr``) says what it does, in the list and in its own help.
"""

from __future__ import annotations

import contextlib
import io
import re
import unittest
from typing import Callable, Dict, List, Sequence, Tuple

import snr
import snr.console
from snr.__main__ import main as snr_main

COMMANDS = [
    "demo",
    "console",
    "docs",
    "graph",
    "convert",
    "lesson",
    "plot",
    "router",
    "secret",
    "version",
]
"""The commands of ``snr``, as ``snr --help`` lists them."""


def run(entry: Callable[[List[str]], int], argv: Sequence[str]) -> Tuple[int, str, str]:
    """Run a command line's ``main`` in this process: its exit code, stdout and stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = entry(list(argv))
        except SystemExit as stop:  # argparse's --help and usage errors
            code = stop.code if isinstance(stop.code, int) else 1
    return code, out.getvalue(), err.getvalue()


def snr_help(*argv: str) -> str:
    """What ``snr ARGV... --help`` prints (it must exit 0)."""
    code, out, err = run(snr_main, [*argv, "--help"])
    if code != 0 or err:
        raise AssertionError(f"snr {' '.join(argv)} --help: exit {code}, stderr {err!r}")
    return out


def description(help_text: str) -> str:
    """The paragraph between a help's usage lines and its first list of arguments."""
    paragraphs = re.split(r"\n\s*\n", help_text.strip())
    if len(paragraphs) < 2 or paragraphs[1].endswith(":") or ":\n" in paragraphs[1]:
        return ""  # straight from the usage to "options:": no description
    return " ".join(paragraphs[1].split())


def listed_commands(help_text: str) -> Dict[str, str]:
    """The commands ``snr --help`` lists, each with its help (joined onto one line)."""
    section = help_text.split("commands:", 1)[1].split("\n\n", 1)[0]
    listed: Dict[str, str] = {}
    name = ""
    for line in section.splitlines()[2:]:  # after "commands:" and the COMMAND line
        match = re.match(r"\s{4}(\w+)\s+(.*)", line)
        if match:
            name = match.group(1)
            listed[name] = match.group(2)
        elif name:
            listed[name] += " " + line.strip()
    return listed


class TestTheConsoleSaysItsName(unittest.TestCase):
    """One console program, two names: the help and the errors show the one typed."""

    def test_help_shows_snr_console_through_snr_and_snr_console_alone(self) -> None:
        through_snr = snr_help("console")
        alone = run(snr.console.main, ["--help"])[1]
        self.assertTrue(through_snr.startswith("usage: snr console [-h]"), through_snr)
        self.assertNotIn("snr-console", through_snr)
        self.assertTrue(alone.startswith("usage: snr-console [-h]"), alone)
        # Both tell how to reach a node over Zenoh, in the words of their own name.
        self.assertIn("snr console --zenoh SYSTEM", " ".join(through_snr.split()))
        self.assertIn("snr-console --zenoh SYSTEM", " ".join(alone.split()))

    def test_the_zenoh_form_shows_the_name_typed_and_zenoh_once(self) -> None:
        through_snr = snr_help("console", "--zenoh", "team7")
        alone = run(snr.console.main, ["--zenoh", "team7", "--help"])[1]
        self.assertTrue(through_snr.startswith("usage: snr console [-h] --zenoh SYSTEM"))
        self.assertTrue(alone.startswith("usage: snr-console [-h] --zenoh SYSTEM"), alone)

    def test_a_usage_error_names_the_command_typed(self) -> None:
        code, _, err = run(snr_main, ["console", "no-port-here:"])
        self.assertEqual(code, 2, err)
        self.assertTrue(err.startswith("usage: snr console "), err)
        self.assertIn("snr console: error: 'no-port-here:' is not a console address", err)
        code, _, err = run(snr.console.main, ["no-port-here:"])
        self.assertEqual(code, 2, err)
        self.assertIn("snr-console: error: 'no-port-here:'", err)


class TestEveryCommandSaysWhatItDoes(unittest.TestCase):
    def test_snr_help_lists_every_command_with_what_it_does(self) -> None:
        text = snr_help()
        self.assertTrue(text.startswith("usage: snr "), text)
        self.assertIn("SNR is Not ROS: a pure-Python robotics framework", text)
        listed = listed_commands(text)
        self.assertEqual(list(listed), COMMANDS, text)
        for command, words in listed.items():
            with self.subTest(command=command):
                self.assertGreaterEqual(len(words.split()), 4, f"{command}: {words!r}")
        self.assertIn("--zenoh", listed["console"])  # the way to a node by its role
        self.assertIn("--sim", listed["demo"])
        self.assertIn("snr COMMAND --help", " ".join(text.split()))

    def test_each_command_has_a_description_in_its_own_help(self) -> None:
        for command in COMMANDS:
            with self.subTest(command=command):
                text = snr_help(command)
                self.assertTrue(text.startswith(f"usage: snr {command} "), text)
                said = description(text)
                self.assertGreaterEqual(len(said.split()), 6, f"snr {command} --help:\n{text}")

    def test_the_docs_and_convert_descriptions_say_what_they_do(self) -> None:
        docs = description(snr_help("docs"))
        self.assertIn("Build SNR's documentation", docs)
        self.assertIn("--serve", docs)
        convert = description(snr_help("convert"))
        self.assertIn("JSON lines to MCAP", convert)

    def test_lesson_describes_itself_and_its_actions(self) -> None:
        text = snr_help("lesson")
        self.assertIn("'start N' writes lesson N's starter file", description(text))
        for action in ("list", "start", "grade"):
            self.assertIn(f"    {action} ", text)
        grade = snr_help("lesson", "grade")
        self.assertIn("--solution", grade)
        self.assertIn("One file: each check, passed or failed", description(grade))


class TestUsageAnswersWhileParsing(unittest.TestCase):
    """``--version`` and wrong option pairs end the program before any command runs."""

    def test_version_answers_whatever_follows_it(self) -> None:
        expected = f"snr-robotics {snr.__version__}\n"
        for argv in (["--version"], ["--version", "graph"], ["--version", "demo", "--sim"]):
            with self.subTest(argv=argv):
                self.assertEqual(run(snr_main, argv), (0, expected, ""))

    def test_version_exits_during_parsing(self) -> None:
        with contextlib.redirect_stdout(io.StringIO()), self.assertRaises(SystemExit) as stop:
            snr_main(["--version"])
        self.assertEqual(stop.exception.code, 0)

    def test_demo_options_that_do_not_go_together_are_usage_errors(self) -> None:
        wrong = {
            ("--sim", "--view"): "--view watches the UROV demo; it does not go with --sim",
            ("--frames", "out"): "--frames goes with --sim",
        }
        for options, message in wrong.items():
            with self.subTest(options=options):
                code, out, err = run(snr_main, ["demo", *options])
                self.assertEqual((code, out), (2, ""), err)
                self.assertTrue(err.startswith("usage: snr demo "), err)
                self.assertTrue(err.endswith(f"snr demo: error: {message}\n"), err)


if __name__ == "__main__":
    unittest.main()
