"""examples/zenoh_team: a robot, a laptop and a logger, three processes over Zenoh.

Run as the example's README says for three machines, with 127.0.0.1 for the
machines' addresses and ports chosen now: the robot listens, the laptop
listens and connects to the robot, the logger connects to both. Skipped
when the Zenoh extra is not installed.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from typing import Any, Callable, Dict, List, Optional

from tests.examples_support import ROOT, example_path, load_module, script_env
from tests.helpers import free_port
from tests.optional import needs

TEAM = example_path("zenoh_team", "team.py")
# The whole test's bound: three Pythons importing Zenoh, meeting, and all that
# follows, on a busy 2-core machine. It takes about 3 s alone.
TIME_LIMIT_S = 12.0
INTERRUPTED = "Interrupted by user, exiting"


def endpoint(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def python_blocks(path: str) -> List[str]:
    with open(path, encoding="utf-8") as file:
        return re.findall(r"```python\n(.*?)```", file.read(), re.DOTALL)


class TestTeamFile(unittest.TestCase):
    """The program's plan, and the pages that quote it (no Zenoh needed)."""

    team: Any

    @classmethod
    def setUpClass(cls) -> None:
        cls.team = load_module(TEAM, "zenoh_team_team")

    def test_the_laptop_drives_forward_stops_backs_and_stops_again(self) -> None:
        speeds = [self.team.planned_speed(n) for n in range(1, 31)]  # 6 s of commands
        self.assertEqual(speeds, [0.25] * 10 + [0.0] * 5 + [-0.25] * 10 + [0.0] * 5)
        self.assertEqual(self.team.planned_speed(31), 0.25, "and again")

    def test_docs_comms_quotes_make_components_as_it_is(self) -> None:
        with open(TEAM, encoding="utf-8") as file:
            source = file.read()
        blocks = python_blocks(os.path.join(ROOT, "docs", "comms.md"))
        quoted = [block for block in blocks if "def make_components(" in block]
        self.assertEqual(len(quoted), 1, "docs/comms.md quotes make_components once")
        # (assertTrue: assertIn would print both texts whole)
        self.assertTrue(
            quoted[0] in source, "docs/comms.md: copy make_components from team.py again"
        )

    def test_the_readmes_robot_comms_are_what_team_py_builds_there(self) -> None:
        block = python_blocks(example_path("zenoh_team", "README.md"))[0]
        names: Dict[str, Any] = {}
        exec("from snr import ZenohCommsFactory\n" + block, names)
        robot = self.team.make_components("team7", listen=["tcp/0.0.0.0:7447"])["robot"][0]
        for setting in ["system", "publish", "subscribe", "mode", "listen", "connect", "scouting"]:
            self.assertEqual(
                getattr(names["zenoh"], setting), getattr(robot, setting), f"README: {setting}"
            )


@needs("zenoh")
class TestZenohTeam(unittest.TestCase):
    def setUp(self) -> None:
        folder = tempfile.TemporaryDirectory(prefix="snr-zenoh-team-")
        self.addCleanup(folder.cleanup)
        self.folder = folder.name
        self.log_file = os.path.join(self.folder, "team_log.jsonl")
        # A system of its own: no other test's nodes are heard, whatever they scout.
        self.system = f"team-test-{os.getpid()}"
        self.processes: Dict[str, subprocess.Popen[bytes]] = {}
        self.deadline = time.monotonic() + TIME_LIMIT_S

    def start(self, role: str, *options: str) -> None:
        """``python team.py <role> ...``, its output to files (nobody blocks on a pipe)."""
        args = [TEAM, role, "--system", self.system, "--log-file", self.log_file]
        # A safety net: a node left behind by a failed test stops by itself.
        args += ["--seconds", "20", *options]
        with (
            open(self.output_path(role, "out"), "wb") as out,
            open(self.output_path(role, "err"), "wb") as err,
        ):
            process = subprocess.Popen(
                [sys.executable, *args], cwd=self.folder, stdout=out, stderr=err, env=script_env()
            )
        self.processes[role] = process
        self.addCleanup(self.kill, process)

    @staticmethod
    def kill(process: subprocess.Popen[bytes]) -> None:
        if process.poll() is None:
            process.kill()
            process.wait()

    def output_path(self, role: str, stream: str) -> str:
        return os.path.join(self.folder, f"{role}.{stream}")

    def output(self, role: str) -> str:
        with open(self.output_path(role, "out"), encoding="utf-8") as out:
            text = out.read()
        with open(self.output_path(role, "err"), encoding="utf-8") as err:
            return text + err.read()

    def outputs(self) -> str:
        return "".join(f"\n--- {role}:\n{self.output(role)}" for role in self.processes)

    def logged(self) -> List[Dict[str, Any]]:
        """The pages in the logger's file so far (a last line still being written is left out)."""
        try:
            with open(self.log_file, encoding="utf-8") as file:
                lines = file.read().split("\n")[:-1]
        except FileNotFoundError:
            return []
        return [page for page in map(json.loads, lines) if "key" in page]

    def wait_for(self, what: str, found: Callable[[], Optional[Any]]) -> Any:
        """``found()``'s answer once it is true; fails if a node stops or time runs out."""
        while True:
            answer = found()
            if answer:
                return answer
            for role, process in self.processes.items():
                self.assertIsNone(process.poll(), f"{role} stopped early:{self.outputs()}")
            if time.monotonic() > self.deadline:
                self.fail(f"never saw {what} within {TIME_LIMIT_S} s:{self.outputs()}")
            time.sleep(0.05)

    def wait_for_log(
        self, what: str, found: Callable[[List[Dict[str, Any]]], Optional[Any]]
    ) -> Any:
        """``found(pages)``'s answer once it is true, for the pages logged so far."""
        return self.wait_for(f"{what} in the log", lambda: found(self.logged()))

    def wait_for_output(self, role: str, pattern: str) -> None:
        self.wait_for(
            f"{pattern!r} printed by {role}", lambda: re.search(pattern, self.output(role))
        )

    def ctrl_c(self, role: str) -> None:
        process = self.processes[role]
        process.send_signal(signal.SIGINT)
        try:
            process.wait(max(1.0, self.deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            self.fail(f"{role} did not stop on Ctrl-C within {TIME_LIMIT_S} s:{self.outputs()}")
        self.assertEqual(process.returncode, 0, self.outputs())
        self.assertIn(INTERRUPTED, self.output(role))

    def test_three_machines_over_explicit_endpoints(self) -> None:
        robot, laptop = free_port(), free_port()
        self.start("robot", "--listen", endpoint(robot))
        self.start("laptop", "--listen", endpoint(laptop), "--connect", endpoint(robot))
        self.start("logger", "--connect", endpoint(robot), "--connect", endpoint(laptop))

        def obeyed(pages: List[Dict[str, Any]]) -> Optional[Dict[str, Any]]:
            """A status page of the robot moving as a logged command of the laptop said."""
            commands = {
                page["data"]["n"]: page["data"]
                for page in pages
                if page["key"] == "commands/drive" and page["origin"] == "laptop"
            }
            for page in pages:
                status: Dict[str, Any] = page["data"]
                if page["key"] != "robot/status" or status["command"] not in commands:
                    continue
                said = commands[status["command"]]["speed_m_s"]
                if page["origin"] == "robot" and status["speed_m_s"] == said != 0:
                    return status
            return None

        status = self.wait_for_log("the robot obeying a command to move", obeyed)

        def moved(pages: List[Dict[str, Any]]) -> bool:
            """The robot's sensors, from the robot, once it has moved off its start."""
            ranges = [p["data"] for p in pages if p["key"] == "sensors/range"]
            batteries = [p for p in pages if p["key"] == "sensors/battery"]
            robots = {p["origin"] for p in pages if p["key"].startswith("sensors/")}
            return robots == {"robot"} and bool(batteries) and any(r != 2.0 for r in ranges)

        self.wait_for_log("the robot's sensors after it moved", moved)
        # What the laptop and the robot printed is what README.md shows.
        self.assertIn(f"robot: driving at {status['speed_m_s']:+.2f} m/s", self.output("robot"))

        self.wait_for_output(
            "laptop", r"laptop: wall \d\.\d\d m ahead, battery 12\.\d\d V, robot at"
        )

        # The laptop goes: the robot stops, and says why in a page the logger records.
        self.ctrl_c("laptop")

        def stopped(pages: List[Dict[str, Any]]) -> bool:
            return any(p["data"] == {"speed_m_s": 0.0, "command": None, "why": "the laptop left"}
                       for p in pages if p["key"] == "robot/status")  # fmt: skip

        self.wait_for_log("the robot stopping as the laptop left", stopped)
        self.assertIn("robot: driving at +0.00 m/s (the laptop left)", self.output("robot"))
        self.ctrl_c("robot")
        self.ctrl_c("logger")
        logger = self.output("logger")
        self.assertRegex(logger, r"Recorded \d+ pages to .*team_log\.jsonl \(0 skipped\)")
        for role in self.processes:
            self.assertNotIn("Traceback", self.output(role))
            self.assertNotIn("Did you mean", self.output(role))


if __name__ == "__main__":
    unittest.main()
