"""Config, roles on the command line, Ctrl-C, and running several roles."""

import contextlib
import io
import os
import signal
import subprocess
import sys
import textwrap
import time
import unittest
from typing import Any, List, Tuple, Union

from snr import (
    AbstractNode,
    CliRunner,
    Config,
    Mode,
    MultiProcExpector,
    MultiProcRunner,
    SNRTestCase,
    SynchronousRunner,
    TaskType,
    TimeoutLoopFactory,
)
from snr.core import TestRunner
from snr.prelude import ConfigError
from snr.utils import DummyEndpointFactory, ExpectorEndpointFactory, ListReplayerFactory
from tests.comms_helpers import StopAfterFactory
from tests.helpers import catches_signal

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class TestConfig(unittest.TestCase):
    def test_get_and_roles(self) -> None:
        fac = TimeoutLoopFactory(seconds=1)
        config = Config({"urov": [fac], "topside": [fac]})
        self.assertEqual(config.roles(), ["urov", "topside"])
        self.assertEqual(config.get("urov"), [fac])
        self.assertIs(config.mode, Mode.DEBUG)
        self.assertIsNotNone(config.get_profiler())
        self.assertIsNone(Config({}, mode=Mode.DEPLOYED).get_profiler())

    def test_unknown_role_lists_roles_and_closest(self) -> None:
        config = Config({"urov": [TimeoutLoopFactory(seconds=1)], "topside": []})
        with self.assertRaises(ConfigError) as ctx:
            config.get("urv")
        self.assertIn("'urov', 'topside'", str(ctx.exception))
        self.assertIn("Did you mean 'urov'?", str(ctx.exception))

    def test_empty_role(self) -> None:
        with self.assertRaises(ConfigError) as ctx:
            Config({"robot": []}).get("robot")
        self.assertIn("no components", str(ctx.exception))

    def test_not_a_factory(self) -> None:
        with self.assertRaises(ConfigError) as ctx:
            Config({"robot": [TimeoutLoopFactory]})  # type: ignore[list-item]
        self.assertIn("add ()", str(ctx.exception))
        with self.assertRaises(ConfigError):
            Config({"robot": TimeoutLoopFactory(seconds=1)})  # type: ignore[dict-item]


# The start of a script whose node prints "ready" once it runs: listed last,
# the endpoint's begin() comes after every other component has started, so the
# test knows when Ctrl-C finds the node running.
READY = textwrap.dedent(
    """
    import sys
    import snr


    class Ready(snr.Endpoint):
        def begin(self):
            # One write: with PYTHONUNBUFFERED, print() writes the newline on
            # its own, and two nodes' lines on one pipe may interleave.
            sys.stdout.write("ready\\n")
            sys.stdout.flush()


    class ReadyFactory(snr.EndpointFactory):
        def get(self, parent):
            return Ready(self, parent, "ready")
    """
)


class TestCliRunner(unittest.TestCase):
    components = {
        "urov": [TimeoutLoopFactory(seconds=0.05)],
        "topside": [TimeoutLoopFactory(seconds=0.05)],
    }

    def run_cli(self, argv: List[str]) -> Tuple[Union[str, int, None], str]:
        """The exit code and standard error of a CliRunner that exits."""
        err = io.StringIO()
        with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as ctx:
            CliRunner(self.components, argv).run()
        return ctx.exception.code, err.getvalue()

    def test_no_role(self) -> None:
        code, err = self.run_cli(["main.py"])
        self.assertEqual(code, 2)
        self.assertIn("no role given", err)
        self.assertIn("urov, topside", err)

    def test_unknown_role(self) -> None:
        code, err = self.run_cli(["main.py", "urv"])
        self.assertEqual(code, 2)
        self.assertIn("Unknown role 'urv'", err)
        self.assertIn("Did you mean 'urov'?", err)

    def test_runs_the_role(self) -> None:
        built: List[Tuple[str, Mode]] = []  # (role, mode) of each node the timeout was built for

        class Noted(TimeoutLoopFactory):
            def get(self, parent: AbstractNode) -> Any:
                built.append((parent.role, Mode(parent.mode)))
                return super().get(parent)

        components = {"urov": [Noted(seconds=0.05)], "topside": [Noted(seconds=0.05)]}
        CliRunner(components, ["main.py", "urov", "--mode", "test"]).run()
        self.assertEqual(built, [("urov", Mode.TEST)])

    def test_the_mode_option_keeps_the_rest_of_the_config(self) -> None:
        made: List[str] = []  # one entry for each datastore the config's class made

        class Store(dict):  # type: ignore[type-arg]
            def __init__(self) -> None:
                super().__init__()
                made.append("store")

        config = Config({"urov": [TimeoutLoopFactory(seconds=0.05)]}, datastore=Store)
        CliRunner(config, ["main.py", "urov", "--mode", "test"]).run()
        self.assertEqual(made, ["store"])

    def test_ctrl_c_exits_cleanly(self) -> None:
        script = READY + textwrap.dedent(
            """
            components = {"robot": [snr.TimeoutLoopFactory(seconds=20), ReadyFactory()]}
            snr.CliRunner(components, sys.argv).run()
            """
        )
        env = dict(os.environ, PYTHONPATH=ROOT)
        proc = subprocess.Popen(
            [sys.executable, "-c", script, "robot"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        try:
            assert proc.stdout is not None
            self.assertEqual(proc.stdout.readline().strip(), "ready")  # the node runs
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        self.assertEqual(proc.returncode, 0, err)
        self.assertIn("Interrupted by user, exiting", out)
        self.assertNotIn("Traceback", err)

    def test_ctrl_c_stops_every_role_and_says_so_once(self) -> None:
        script = READY + textwrap.dedent(
            """
            components = {
                "a": [snr.TimeoutLoopFactory(seconds=20), ReadyFactory()],
                "b": [snr.TimeoutLoopFactory(seconds=20), ReadyFactory()],
            }
            snr.CliRunner(components, sys.argv).run()
            """
        )
        env = dict(os.environ, PYTHONPATH=ROOT)
        proc = subprocess.Popen(
            [sys.executable, "-c", script, "a", "b"], stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True, env=env, start_new_session=True,
        )  # fmt: skip
        try:
            assert proc.stdout is not None
            readies = 0
            for _ in range(4):  # both roles' nodes run (their lines may come in any mix)
                line = proc.stdout.readline()
                self.assertIn("ready", line, "a child ended before its node ran")
                readies += line.count("ready")
                if readies >= 2:
                    break
            self.assertEqual(readies, 2)
            # The parent sets its handlers (SIGINT's, then SIGTERM's) once it has
            # started every child, which may be after the children's nodes run.
            if catches_signal(proc.pid, signal.SIGTERM) is None:  # no /proc: give it time
                time.sleep(0.5)
            os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C reaches the whole group
            out, err = proc.communicate(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        self.assertEqual(proc.returncode, 0, err)
        self.assertEqual(out.count("Interrupted by user, exiting"), 1, out)
        # Each child gets the Ctrl-C itself and also hears the parent stop it;
        # whichever comes first names the reason, and both are right.
        stopped = err.count("terminated: interrupted by user (Ctrl-C)") + err.count(
            "terminated: parent asked to stop (SIGINT)"
        )
        self.assertEqual(stopped, 2, err)
        self.assertNotIn("Traceback", err)


class TestRunners(SNRTestCase):
    def test_synchronous_runner(self) -> None:
        runner = SynchronousRunner(
            "r", Config({"r": [TimeoutLoopFactory(seconds=0.05)]}, mode=Mode.TEST)
        )
        runner.run()
        assert runner.node is not None
        self.assertEqual(runner.node.terminate_reason, "Timeout")

    def test_test_runner_time_limit(self) -> None:
        runner = TestRunner("test", self.get_config([DummyEndpointFactory()]), timeout_s=0.1)
        runner.run()
        self.assertTrue(runner.timed_out)

    def test_multiproc_runner_runs_every_role(self) -> None:
        expector = MultiProcExpector({(TaskType.store_page, "a"): 3, (TaskType.store_page, "b"): 2})
        config = Config(
            {
                # Each node stops after its last page; the timeouts are a backstop.
                "one": [
                    ListReplayerFactory([1, 2, 3], "a"),
                    ExpectorEndpointFactory(expector),
                    StopAfterFactory("a", 3, on_store=True),
                    TimeoutLoopFactory(seconds=10),
                ],
                "two": [
                    ListReplayerFactory([1, 2], "b"),
                    ExpectorEndpointFactory(expector),
                    StopAfterFactory("b", 2, on_store=True),
                    TimeoutLoopFactory(seconds=10),
                ],
            },
            mode=Mode.TEST,
        )
        with expector:
            runner = MultiProcRunner(["one", "two"], config)
            runner.run()
        self.assertEqual(runner.exitcodes, [0, 0])

    def test_multiproc_runner_unknown_role(self) -> None:
        with self.assertRaises(ConfigError):
            MultiProcRunner(["nope"], Config({"a": [TimeoutLoopFactory(seconds=1)]}))


if __name__ == "__main__":
    unittest.main()
