"""MultiProcRunner leaves no orphans: stopping or killing the parent stops every child.

Each test runs a two-role system in a real subprocess (the parent), waits
until both child processes have written their pid, signals the parent only
(or, for Ctrl-C in a terminal, its process group) and checks that every
child is gone within the bound. A failing test still kills whatever it started.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from typing import Dict, List

from snr.core.runners import INTERRUPTED_MESSAGE
from tests.examples_support import script_env

ROLES = ("one", "two")

# The parent under test. Its children write their pid once their node runs,
# so the test knows whom to watch; the endpoints just idle.
SYSTEM = """
import os
import signal
import sys

import snr

folder = sys.argv[1]


class PidFile(snr.Endpoint):
    def begin(self):
        path = os.path.join(folder, self.parent.role + ".pid")
        with open(path + ".tmp", "w") as file:
            file.write(str(os.getpid()))
        os.replace(path + ".tmp", path)  # never seen half written


class PidFileFactory(snr.EndpointFactory):
    def get(self, parent):
        return PidFile(self, parent, "pid_file")


if __name__ == "__main__":
    # A shell starts background jobs with SIGINT ignored; a terminal does not.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    config = snr.Config({role: [PidFileFactory()] for role in ROLES}, mode=snr.Mode.DEBUG)
    runner = snr.MultiProcRunner(list(ROLES), config)
    runner.run()
    print("exitcodes", runner.exitcodes, "stopped by", runner.stopped_by, flush=True)
""".replace("ROLES", repr(ROLES))

START_LIMIT_S = 20.0  # python, snr and two children starting on a busy machine
STOP_SLACK_S = 2.0  # on top of each bound, for slow CI machines


def alive(pid: int) -> bool:
    """Whether ``pid`` still runs (a zombie, dead but not yet reaped, does not)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return False  # reused by another user's process: ours is gone
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return True  # no /proc (macOS): os.kill's answer stands


@unittest.skipIf(sys.platform == "win32", "POSIX signals")
class TestNoOrphans(unittest.TestCase):
    def setUp(self) -> None:
        self.folder = tempfile.TemporaryDirectory(prefix="snr-signals-")
        self.addCleanup(self.folder.cleanup)
        script = os.path.join(self.folder.name, "system.py")
        with open(script, "w") as file:
            file.write(SYSTEM)
        self.out_path = os.path.join(self.folder.name, "out.txt")
        self.err_path = os.path.join(self.folder.name, "err.txt")
        # Output to files, not pipes: children outliving the parent keep pipes
        # open, and nobody may block on them.
        with open(self.out_path, "w") as out, open(self.err_path, "w") as err:
            self.parent = subprocess.Popen(
                [sys.executable, script, self.folder.name],
                stdout=out,
                stderr=err,
                env=script_env(),
                start_new_session=True,  # its own process group, as a shell makes
            )
        self.children: Dict[str, int] = {}
        self.addCleanup(self.kill_everything)

    def kill_everything(self) -> None:
        for pid in [self.parent.pid, *self.children.values()]:  # killed one by one, by pid
            if alive(pid):
                try:
                    os.kill(pid, signal.SIGKILL)
                except OSError:
                    pass
        try:
            self.parent.wait(5)
        except subprocess.TimeoutExpired:
            pass

    def wait_for_children(self) -> None:
        deadline = time.monotonic() + START_LIMIT_S
        for _ in range(int(START_LIMIT_S / 0.02)):
            for role in ROLES:
                path = os.path.join(self.folder.name, f"{role}.pid")
                if role not in self.children and os.path.exists(path):
                    with open(path) as file:
                        self.children[role] = int(file.read())
            if len(self.children) == len(ROLES) or time.monotonic() > deadline:
                break
            self.assertIsNone(self.parent.poll(), self.output())
            time.sleep(0.02)
        self.assertEqual(sorted(self.children), sorted(ROLES), self.output())
        self.assertTrue(all(alive(pid) for pid in self.children.values()), self.output())
        # The pid is written once the child's node runs; the parent may still
        # be starting the other child before it sets its signal handlers.
        self.wait_for_parent_handlers()

    def wait_for_parent_handlers(self) -> None:
        """Wait until the parent catches SIGTERM: it sets SIGINT's handler just before."""
        status_path = f"/proc/{self.parent.pid}/status"
        if not os.path.exists(status_path):  # no /proc (macOS): give it a moment
            time.sleep(0.2)
            return
        deadline = time.monotonic() + START_LIMIT_S
        while time.monotonic() < deadline:
            with open(status_path) as status:
                caught = next(line for line in status if line.startswith("SigCgt:"))
            if int(caught.split()[1], 16) & (1 << (signal.SIGTERM - 1)):
                return
            time.sleep(0.005)
        self.fail(f"the parent set no SIGTERM handler\n{self.output()}")

    def seconds_until_children_gone(self, limit_s: float) -> float:
        """Seconds until no child runs; fails after ``limit_s``."""
        start = time.monotonic()
        for _ in range(int(limit_s / 0.01) + 1):
            if not any(alive(pid) for pid in self.children.values()):
                return time.monotonic() - start
            if time.monotonic() - start > limit_s:
                break
            time.sleep(0.01)
        running = [role for role, pid in self.children.items() if alive(pid)]
        self.fail(f"children {running} still run {limit_s} s after the signal\n{self.output()}")

    def output(self) -> str:
        with open(self.out_path) as out, open(self.err_path) as err:
            return f"stdout:\n{out.read()}\nstderr:\n{err.read()}"

    def stop_parent_with(self, signum: int, whole_group: bool = False) -> str:
        """Signal the parent (or its process group); check that all stops cleanly; the output."""
        self.wait_for_children()
        if whole_group:
            os.killpg(self.parent.pid, signum)  # the parent leads its own group
        else:
            os.kill(self.parent.pid, signum)
        self.seconds_until_children_gone(1.0 + STOP_SLACK_S)
        name = signal.Signals(signum).name
        self.assertEqual(self.parent.wait(5), 0, self.output())
        output = self.output()
        self.assertNotIn("Traceback", output)
        self.assertIn("exitcodes [0, 0]", output)
        self.assertIn(f"stopped by {name}", output)
        for role in ROLES:
            self.assertIn(f"Node {role!r} terminated: ", output)
        return output

    def test_sigterm_to_parent_stops_every_child(self) -> None:
        output = self.stop_parent_with(signal.SIGTERM)
        for role in ROLES:
            self.assertIn(f"Node {role!r} terminated: parent asked to stop (SIGTERM)", output)

    def test_sigint_to_parent_only_stops_every_child(self) -> None:
        output = self.stop_parent_with(signal.SIGINT)
        self.assertEqual(output.count(INTERRUPTED_MESSAGE), 1)
        for role in ROLES:
            self.assertIn(f"Node {role!r} terminated: parent asked to stop (SIGINT)", output)

    def test_ctrl_c_in_a_terminal_still_stops_everything_quietly(self) -> None:
        # A terminal's Ctrl-C sends SIGINT to the whole foreground group.
        output = self.stop_parent_with(signal.SIGINT, whole_group=True)
        self.assertEqual(output.count(INTERRUPTED_MESSAGE), 1)

    def test_sigkill_to_parent_children_notice_and_stop(self) -> None:
        self.wait_for_children()
        os.kill(self.parent.pid, signal.SIGKILL)
        self.parent.wait(5)
        self.seconds_until_children_gone(2.0 + STOP_SLACK_S)
        output = self.output()
        lines: List[str] = [line for line in output.splitlines() if "parent process died" in line]
        for role in ROLES:
            self.assertTrue(
                any(f"Node {role!r} terminated: parent process died" in line for line in lines),
                output,
            )


if __name__ == "__main__":
    unittest.main()
