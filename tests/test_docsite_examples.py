"""Docstring examples ("Example::" + an indented block) render as Python code."""

import shutil
import tempfile
import unittest
from pathlib import Path

from snr.extras.docs.docsite import build, literal_blocks_to_fences
from tests.optional import needs


class TestLiteralBlocks(unittest.TestCase):
    def test_example_block_becomes_fenced_python(self) -> None:
        text = (
            "Starts the node.\n\nExample::\n\n    node = Node('robot', config)\n    node.loop()\n"
        )
        self.assertEqual(
            literal_blocks_to_fences(text),
            "Starts the node.\n\nExample:\n\n```python\n"
            "node = Node('robot', config)\nnode.loop()\n```\n\n",
        )

    def test_nested_indentation_and_blank_lines_are_kept(self) -> None:
        text = "Run it::\n\n    for x in xs:\n        print(x)\n\n    done()\n\nAfter.\n"
        self.assertEqual(
            literal_blocks_to_fences(text),
            "Run it:\n\n```python\nfor x in xs:\n    print(x)\n\ndone()\n```\n\nAfter.\n",
        )

    def test_text_without_a_literal_block_is_unchanged(self) -> None:
        text = "Args:\n    key: the data key.\n\nReturns the page, or None: nothing else."
        self.assertEqual(literal_blocks_to_fences(text), text)


@needs("pdoc")
class TestRenderedPage(unittest.TestCase):
    def test_no_literal_example_marker_on_the_page(self) -> None:
        output = Path(tempfile.mkdtemp(prefix="snr-docs-examples-"))
        try:
            build(output, guide_dir=None, show_source=False, modules=("snr.core.timer",))
            page = (output / "snr" / "core" / "timer.html").read_text("utf-8")
        finally:
            shutil.rmtree(output, ignore_errors=True)
        self.assertNotIn("Example::", page)
        self.assertIn('class="pdoc-code codehilite"', page)


class TestExtrasWarnings(unittest.TestCase):
    def test_a_missing_extra_behind_type_checking_is_not_a_problem(self) -> None:
        from snr.extras.docs.docsite import _extra_not_installed

        prefix = "Failed to run TYPE_CHECKING code while parsing X for snr.m.f: "
        self.assertTrue(_extra_not_installed(prefix + "No module named 'zenoh'"))
        self.assertFalse(_extra_not_installed(prefix + "No module named 'snr.missing'"))
        self.assertFalse(_extra_not_installed("Error parsing type annotation for snr.x"))


if __name__ == "__main__":
    unittest.main()
