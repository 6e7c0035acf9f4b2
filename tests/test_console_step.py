"""Step mode from the console (docs/console.md, "Step mode"): pause, step, resume.

The transcript printed in the docs is run as printed, and every reply
compared; the other tests check what the transcript cannot show: a full
queue while paused (loops wait, then their tasks are dropped and counted),
``exit`` while paused, and the refusals.
"""

from __future__ import annotations

import logging
import re
import unittest
from pathlib import Path
from typing import Any, Dict, List, Tuple

import snr
from snr import AbstractNode, LoopFactory, ThreadLoop
from snr.std_mods.io.console_protocol import Status
from tests.console_helpers import NodeInThread
from tests.helpers import wait_until

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs" / "console.md"
PROMPT = "127.0.0.1:9123> "


def step_mode_section() -> str:
    text = DOCS.read_text("utf-8")
    start = text.index("### Step mode")
    return text[start : text.index("\n### ", start + 1)]


def documented_counter() -> Any:
    """The docs' CounterFactory, built from the page's own code."""
    code = re.search(r"```python\n(.*?)```", step_mode_section(), re.S)
    assert code is not None, "the step mode section has a python block"
    names: Dict[str, Any] = {name: getattr(snr, name) for name in snr.__all__}
    exec(compile(code.group(1), str(DOCS), "exec"), names)
    return names["CounterFactory"]


def documented_exchange() -> List[Tuple[str, str]]:
    """(command, reply) pairs of the docs' transcript."""
    block = re.search(r"```text\n(.*?)```", step_mode_section(), re.S)
    assert block is not None, "the step mode section has a transcript"
    pairs: List[Tuple[str, List[str]]] = []
    for line in block.group(1).splitlines():
        if line.startswith(PROMPT):
            pairs.append((line[len(PROMPT) :], []))
        else:
            pairs[-1][1].append(line)
    return [(command, "\n".join(reply)) for command, reply in pairs]


def same_moment(text: str) -> str:
    """Page ages vary with the machine's load: '0.0 s ago' and '0.1 s ago' are alike."""
    return re.sub(r"\d+\.\d s ago", "N s ago", text)


class Flood(ThreadLoop):
    """Stores a number as fast as its rate allows."""

    def __init__(self, factory: FloodFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "flood", max_tick_rate_hz=2000)
        self.n = 0

    def loop(self) -> None:
        self.n += 1
        self.store_data("n", self.n)


class FloodFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> Flood:
        return Flood(self, parent)


class TestTheDocumentedTranscript(unittest.TestCase):
    def test_every_reply_is_as_printed(self) -> None:
        exchange = documented_exchange()
        self.assertGreaterEqual(len(exchange), 8)
        with NodeInThread([documented_counter()()]) as run, run.console() as console:
            for command, expected in exchange:
                reply = console.send(command)
                self.assertEqual(
                    same_moment(reply.text), same_moment(expected), f"reply to {command!r}"
                )


class TestWhilePaused(unittest.TestCase):
    def test_a_full_queue_holds_loops_back_and_counts_what_it_drops(self) -> None:
        run = NodeInThread([FloodFactory()])
        queue = run.node.queue
        queue.high_water, queue.low_water, queue.max_wait_s = 40, 20, 0.02
        with self.assertLogs("snr.robot", logging.WARNING) as logs, run:
            with run.console() as console:
                self.assertEqual(console.send("pause").status, Status.OK)
                self.assertTrue(wait_until(lambda: queue.loss.total > 0), "nothing was dropped")
                # Bounded: the lane never grows past its mark (plus what was in flight).
                self.assertLessEqual(len(queue.normal), queue.high_water + 2)
                stats = console.send("stats").text  # a console command runs, queue full or not
                self.assertIn("The node is paused.", stats)
                dropped = re.search(r"(\d+) of their tasks were dropped", stats)
                self.assertIsNotNone(dropped, stats)
                assert dropped is not None
                self.assertGreater(int(dropped.group(1)), 0)
                # The oldest tasks may be process_data ones (their pages stored
                # before the pause); the loop's store_page tasks come soon after.
                step = console.send("step 100").text
                self.assertIn("Ran (store_page, 'n')", step)
                self.assertIn("went to: node_core.store_page_handler", step)
                resumed = console.send("resume").text
                self.assertIn("Resumed node 'robot'", resumed)
                self.assertTrue(wait_until(lambda: run.node.get_data("n") not in (None, 1)))
        self.assertTrue(
            any("the node is paused (step mode)" in line for line in logs.output), logs.output
        )

    def test_exit_stops_a_paused_node(self) -> None:
        with NodeInThread([FloodFactory()]) as run, run.console() as console:
            console.send("pause")
            self.assertEqual(console.send("exit").status, Status.BYE)
            run.wait_stopped()
            self.assertIn("exit command", str(run.node.terminate_reason))

    def test_step_and_resume_say_when_the_node_is_not_paused(self) -> None:
        with NodeInThread([]) as run, run.console() as console:
            refused = console.send("step")
            self.assertEqual(refused.status, Status.ERROR)
            self.assertIn("type `pause` first", refused.text)
            self.assertIn("is not paused", console.send("resume").text)
            console.send("pause")
            self.assertIn("already paused", console.send("pause").text)
            self.assertIn("takes N from 1 to 100", console.send("step 0").text)
            self.assertIn("Nothing to step", console.send("step 3").text)
