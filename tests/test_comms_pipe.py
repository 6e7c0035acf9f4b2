"""Pipe comms between nodes run by MultiProcRunner, and in one process."""

from __future__ import annotations

import threading
import time
import unittest

from snr import Config, Mode, MultiProcRunner, Node, PipeLoopFactory, TimeoutLoopFactory
from snr.prelude import ConfigError
from snr.std_mods.comms import PipeLoop
from tests.comms_helpers import (
    EchoFactory,
    ReporterFactory,
    Reports,
    SendOnConnectFactory,
    StopAfterFactory,
    context,
    pages_of,
)


class TestPipeComms(unittest.TestCase):
    def test_ping_pong_between_two_processes(self) -> None:
        ctx = context()
        reports = Reports(ctx)
        self.addCleanup(reports.close)
        here, there = ctx.Pipe()
        self.addCleanup(here.close)
        self.addCleanup(there.close)
        writer = reports.writer
        count = 100
        config = Config(
            {
                "topside": [
                    PipeLoopFactory(here, ["ping", "done"]),
                    SendOnConnectFactory("ping", count),
                    ReporterFactory(writer, ["pong"]),
                    StopAfterFactory("pong", count, then_store="done"),
                    StopAfterFactory("done"),
                    TimeoutLoopFactory(seconds=10),
                ],
                "urov": [
                    PipeLoopFactory(there, "pong"),
                    EchoFactory("ping", "pong"),
                    ReporterFactory(writer, ["ping"]),
                    StopAfterFactory("done"),
                    TimeoutLoopFactory(seconds=10),
                ],
            },
            mode=Mode.TEST,
        )
        runner = MultiProcRunner(["topside", "urov"], config, start_method=ctx.get_start_method())
        runner.run()
        self.assertEqual(runner.exitcodes, [0, 0])
        while reports.reader.poll(0):
            reports.get(0)
        self.assertEqual(pages_of(reports.seen, "topside", "pong"), list(range(count)))
        self.assertEqual(pages_of(reports.seen, "urov", "ping"), list(range(count)))
        origins = {r[3] for r in reports.seen if r[0] == "urov"}
        self.assertEqual(origins, {"topside"})

    def test_a_closed_pipe_is_logged_once_and_the_node_keeps_running(self) -> None:
        here, there = context().Pipe()
        self.addCleanup(here.close)
        config = Config(
            {
                "stays": [PipeLoopFactory(here, "a"), TimeoutLoopFactory(seconds=5)],
                # Long enough for the hello on a busy machine: a goodbye before it is a fault.
                "leaves": [PipeLoopFactory(there, "b"), TimeoutLoopFactory(seconds=0.5)],
            },
            mode=Mode.TEST,
        )
        stays, leaves = Node("stays", config), Node("leaves", config)
        pipe_loop = stays.components["pipe_loop"]
        assert isinstance(pipe_loop, PipeLoop)
        thread = threading.Thread(target=stays.loop)
        with self.assertLogs("snr.stays", "INFO") as logs:
            thread.start()
            leaves.loop()  # stops after 0.5 s, says goodbye and closes its end of the pipe
            deadline = time.monotonic() + 3
            while pipe_loop.is_alive() and time.monotonic() < deadline:
                time.sleep(0.02)
        self.assertFalse(pipe_loop.is_alive())
        self.assertFalse(stays.is_terminated(), "the node itself keeps running")
        stays.set_terminate_flag("test over")
        thread.join(5)
        closed = [line for line in logs.output if "pipe" in line and "closed" in line]
        self.assertEqual(len(closed), 1, logs.output)
        self.assertTrue(closed[0].startswith("INFO:"), "a goodbye is no fault")
        self.assertIn("said goodbye", closed[0])

    def test_not_a_connection(self) -> None:
        with self.assertRaises(ConfigError) as ctx:
            PipeLoopFactory("pipe", "a")  # type: ignore[arg-type]
        self.assertIn("multiprocessing.Pipe()", str(ctx.exception))


if __name__ == "__main__":
    unittest.main()
