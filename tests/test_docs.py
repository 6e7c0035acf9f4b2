"""The docs: the API reference builds with no warnings, and the guide's links work."""

import contextlib
import io
import os
import shutil
import sys
import tempfile
import threading
import time
import types
import unittest
import urllib.request
from pathlib import Path
from typing import List
from unittest import mock

from snr.__main__ import main
from snr.extras.docs import docsite
from snr.prelude.install import install_hint
from tests.examples_support import ROOT
from tests.optional import needs

DOCS = Path(ROOT, "docs")


@needs("pdoc")
class TestDocsBuild(unittest.TestCase):
    output: Path
    problems: List[str]

    @classmethod
    def setUpClass(cls) -> None:
        cls.output = Path(tempfile.mkdtemp(prefix="snr-docs-"))
        # Without source listings and with one small API page: the same checks
        # in a fraction of the time (the `snr` page documents every export).
        # CI's `python -m snr docs --build-only` step builds all of it.
        cls.problems = docsite.build(cls.output, DOCS, show_source=False, modules=("snr.utils",))

    @classmethod
    def tearDownClass(cls) -> None:
        shutil.rmtree(cls.output, ignore_errors=True)

    def test_builds_with_no_warnings(self) -> None:
        self.assertEqual(self.problems, [])
        page = self.output / "snr" / "utils.html"
        self.assertTrue(page.is_file(), page)
        self.assertIn("SNRTestCase", page.read_text("utf-8"))

    def test_every_page_of_docs_is_in_the_guide(self) -> None:
        for page in DOCS.glob("*.md"):
            self.assertTrue((self.output / "guide" / f"{page.stem}.html").is_file(), page)
        index = (self.output / "guide" / "index.html").read_text("utf-8")
        self.assertIn('href="concepts.html"', index)  # .md links point to the HTML
        self.assertIn('href="../snr.html"', index)  # and api/ links into the reference

    def test_a_clean_build_is_not_rebuilt(self) -> None:
        self.assertFalse(docsite.is_stale(self.output, DOCS))
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = main(["docs", "--no-open", "--output", str(self.output)])
        self.assertEqual(code, 0)
        self.assertNotIn("Building", out.getvalue())
        self.assertIn("guide/index.html", out.getvalue())

    def test_served_on_localhost(self) -> None:
        with docsite.make_server(self.output, 0) as server:
            host, port = server.server_address[:2]
            self.assertEqual(host, "127.0.0.1")
            # serve_forever checks for shutdown() every poll_interval (0.5 s by default).
            thread = threading.Thread(target=server.serve_forever, args=(0.02,), daemon=True)
            thread.start()
            try:
                url = f"http://127.0.0.1:{port}/guide/index.html"
                with urllib.request.urlopen(url, timeout=5) as response:
                    self.assertIn(b"SNR documentation", response.read())
            finally:
                server.shutdown()
                thread.join(5)

    def test_a_changed_page_makes_the_build_stale(self) -> None:
        guide = Path(tempfile.mkdtemp(prefix="snr-guide-"))
        self.addCleanup(shutil.rmtree, guide, True)
        (guide / "index.md").write_text("# Home\n", encoding="utf-8")
        output = guide / "api"
        docsite.render_guide(guide, output)
        (output / docsite.STAMP_FILE).write_text(docsite._fingerprint(guide), "utf-8")
        self.assertFalse(docsite.is_stale(output, guide))
        later = time.time() + 5
        os.utime(guide / "index.md", (later, later))
        self.assertTrue(docsite.is_stale(output, guide))


class TestDocsChecks(unittest.TestCase):
    def test_without_pdoc_the_error_says_what_to_install(self) -> None:
        with mock.patch.dict(sys.modules, {"pdoc": None, "pdoc.render": None}):
            with self.assertRaises(docsite.DocsBuildError) as caught:
                docsite.build(Path(tempfile.mkdtemp(prefix="snr-docs-")), None)
        self.assertIn(install_hint("docs"), str(caught.exception))

    def test_a_misspelt_name_in_a_docstring_is_reported(self) -> None:
        module = types.ModuleType("student_module")

        def handler() -> None:
            """Uses `Endpont` and `Task.val_lst`, but `Endpoint` and ``Nonsense`` are fine."""

        handler.__module__ = "student_module"
        vars(module)["handler"] = handler
        problems = docsite.check_docstring_references([module])
        self.assertEqual(len(problems), 2, problems)
        self.assertIn("`Endpont`", problems[0])
        self.assertIn("`Task.val_lst`", problems[1])

    @needs("pdoc")
    def test_a_broken_link_in_a_page_is_reported(self) -> None:
        guide = Path(tempfile.mkdtemp(prefix="snr-guide-"))
        self.addCleanup(shutil.rmtree, guide, True)
        (guide / "index.md").write_text(
            "# Home\n[ok](other.md) [web](https://example.org) [gone](missing.md#top)\n",
            encoding="utf-8",
        )
        (guide / "other.md").write_text("# Other\n[back](index.md#home)\n", encoding="utf-8")
        problems = docsite.render_guide(guide, guide / "api")
        self.assertEqual(len(problems), 1, problems)
        self.assertIn("'missing.md#top'", problems[0])
        other = (guide / "api" / "guide" / "other.html").read_text("utf-8")
        self.assertIn('href="index.html#home"', other)

    @needs("pdoc")
    def test_a_link_to_a_module_that_does_not_exist_is_reported(self) -> None:
        guide = Path(tempfile.mkdtemp(prefix="snr-guide-"))
        self.addCleanup(shutil.rmtree, guide, True)
        (guide / "index.md").write_text(
            "# Home\n[node](api/snr/core/node.html) [nope](api/snr/core/nodes.html)\n",
            encoding="utf-8",
        )
        problems = docsite.render_guide(guide, guide / "api")
        self.assertEqual(len(problems), 1, problems)
        self.assertIn("'api/snr/core/nodes.html'", problems[0])


if __name__ == "__main__":
    unittest.main()
