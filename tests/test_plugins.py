"""The kernel's extension points (snr/core/plugins.py): what the extras declare loads."""

from __future__ import annotations

import unittest

from snr.core import plugins
from snr.prelude import ConfigError
from snr.std_mods.io import recording_formats

__all__ = ["PluginsTest"]

DECLARED = {
    "snr.commands": ("convert", "demo", "docs", "graph", "lesson", "plot", "router"),
    "snr.console_transports": ("zenoh",),
    "snr.console_commands": ("console_tools", "graph"),
    "snr.recording_formats": ("mcap",),
    "snr.json_backends": ("orjson",),
}
"""What SNR's pyproject.toml declares, group by group."""


class PluginsTest(unittest.TestCase):
    def test_every_group_has_what_pyproject_declares(self) -> None:
        self.assertEqual(sorted(plugins.GROUPS), sorted(DECLARED))
        for group, names in DECLARED.items():
            with self.subTest(group=group):
                self.assertEqual(plugins.names(group), names)

    def test_every_entry_point_loads_from_an_extra(self) -> None:
        for group, names in DECLARED.items():
            for name in names:
                with self.subTest(group=group, name=name):
                    loaded = plugins.load(group, name, "this test")
                    where = getattr(loaded, "__module__", None) or loaded.__name__
                    if not isinstance(where, str) or where == "builtins":
                        where = type(loaded).__module__
                    self.assertTrue(where.startswith("snr.extras."), where)

    def test_an_unknown_name_says_what_there_is_and_how_to_register(self) -> None:
        with self.assertRaises(ConfigError) as caught:
            plugins.load("snr.recording_formats", "bag", "Reading dive.bag")
        text = str(caught.exception)
        self.assertIn("Reading dive.bag needs 'bag'", text)
        self.assertIn("it has: mcap", text)
        self.assertIn("pip install -e .", text)

    def test_the_recording_format_comes_from_the_file_name_and_bytes(self) -> None:
        self.assertEqual(recording_formats.format_of_name("dive.MCAP"), "mcap")
        self.assertEqual(recording_formats.format_of_name("dive.jsonl"), "jsonl")
        self.assertEqual(recording_formats.format_of_name("dive"), "jsonl")
        mcap = recording_formats.get("mcap", "this test")
        self.assertEqual(recording_formats.format_of_bytes(mcap.magic + b"rest"), "mcap")
        self.assertEqual(recording_formats.format_of_bytes(b'{"format":"snr-pages"}'), "jsonl")


if __name__ == "__main__":
    unittest.main()
