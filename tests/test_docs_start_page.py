"""The API reference's start page lists every export by topic; the guide ships with SNR."""

import shutil
import tempfile
import unittest
from pathlib import Path

from snr.extras.docs import docsite
from snr.extras.docs.api_topics import TOPICS, Topic, check_topics, full_entry, summary
from tests.examples_support import ROOT
from tests.optional import needs


def _temp_dir(test: unittest.TestCase) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="snr-docs-"))
    test.addCleanup(shutil.rmtree, folder, True)
    return folder


class TestTopics(unittest.TestCase):
    def test_every_export_is_in_exactly_one_topic(self) -> None:
        self.assertEqual(check_topics(), [])

    def test_an_export_left_out_a_name_twice_and_a_stray_name_are_reported(self) -> None:
        first, second, *rest = TOPICS
        without_node = Topic(first.title, first.about, tuple(n for n in first.names if n != "Node"))
        twice = Topic(second.title, second.about, (*second.names, "Config", "Nodes"))
        problems = check_topics([without_node, twice, *rest])
        self.assertEqual(len(problems), 3, problems)
        self.assertTrue(any("Config is in two topics" in p for p in problems), problems)
        self.assertTrue(any("lists Nodes, which is not in snr.__all__" in p for p in problems))
        self.assertTrue(any("snr.__all__ has Node, which no topic" in p for p in problems))

    def test_each_name_links_to_its_defining_layer(self) -> None:
        self.assertEqual(full_entry("Node"), "snr/core.html#Node")
        self.assertEqual(full_entry("Page"), "snr/prelude.html#Page")
        # A component: the page of its sub-package, which exports it.
        self.assertEqual(full_entry("SocketsPair"), "snr/std_mods/comms.html#SocketsPair")
        self.assertEqual(full_entry("COMMS_CONNECTED"), "snr/std_mods/comms.html#COMMS_CONNECTED")
        self.assertEqual(full_entry("MPExpector"), "snr/extras/compat2021.html#MPExpector")
        self.assertEqual(full_entry("tasks"), "snr/core/tasks.html")
        self.assertEqual(full_entry("Settings"), "snr/extras/compat2021.html#Settings")

    @needs("websockets")  # summary() imports every module of snr, the live view's server too
    def test_an_alias_is_summed_up_by_the_docstring_under_it(self) -> None:
        # DataKey is str: its summary must not be str's docstring.
        self.assertTrue(summary("DataKey").startswith("The name a page is stored under"))
        self.assertIn("comms loop", summary("COMMS_CONNECTED"))
        self.assertTrue(summary("Node").startswith("Builds its components"))


@needs("pdoc")
class TestStartPage(unittest.TestCase):
    def test_the_start_page_lists_names_by_topic_with_links(self) -> None:
        output = _temp_dir(self)
        self.assertEqual(docsite.render_api_start_page(output), [])
        page = (output / "snr.html").read_text("utf-8")
        self.assertIn('<h3 id="building-a-robot">Building a robot</h3>', page)
        self.assertIn('<a href="snr/core.html#Node"><code>Node</code></a>: Builds its', page)
        self.assertIn('href="snr/utils.html"', page)  # each layer in full
        self.assertLess(len(page), 200_000)  # not every entry in full, as pdoc's was
        self.assertIn('url=snr.html"', (output / "index.html").read_text("utf-8"))

    def test_a_link_to_an_entry_a_built_page_lacks_is_reported(self) -> None:
        output = _temp_dir(self)
        (output / "snr").mkdir()
        (output / "snr" / "utils.html").write_text('<div id="Expector"></div>', "utf-8")
        problems = docsite.render_api_start_page(output)
        missing = "The start page links to snr/utils.html#ListReplayerFactory, which"
        self.assertIn(missing, "\n".join(problems))


class TestGuideLookup(unittest.TestCase):
    def test_a_checkout_uses_its_docs_folder(self) -> None:
        self.assertEqual(docsite.find_guide(Path(ROOT, "snr")), Path(ROOT, "docs"))

    def test_an_installed_package_uses_its_shipped_copy(self) -> None:
        site = _temp_dir(self)
        package = site / "snr"
        (package / "guide").mkdir(parents=True)
        (package / "__init__.py").write_text("", "utf-8")
        self.assertIsNone(docsite.find_guide(package))
        (package / "guide" / "index.md").write_text("# Home\n", "utf-8")
        self.assertEqual(docsite.find_guide(package), package / "guide")

    @needs("pdoc")
    def test_the_shipped_copy_names_the_examples_it_cannot_link_to(self) -> None:
        package = _temp_dir(self) / "snr"
        (package / "guide").mkdir(parents=True)
        (package / "__init__.py").write_text("", "utf-8")
        (package / "guide" / "index.md").write_text(
            "# Home\n[the filter](../examples/filter/README.md) [`examples/`](../examples/)"
            " [gone](gone.md)\n",
            "utf-8",
        )
        output = package / "built"
        problems = docsite.render_guide(package / "guide", output)
        self.assertEqual(len(problems), 1, problems)  # only the page missing from the guide
        self.assertIn("'gone.md'", problems[0])
        page = (output / "guide" / "index.html").read_text("utf-8")
        self.assertIn("the filter (<code>examples/filter/README.md</code> in SNR's source)", page)
        self.assertIn("<code>examples/</code> ", page)
        self.assertNotIn('href="../../examples', page)


if __name__ == "__main__":
    unittest.main()
