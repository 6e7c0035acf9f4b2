"""`CliRunner`, the roles named on the command line, and `MultiProcRunner`, a process each.

Built on `snr.core.runners`; docs/design.md ("Runners") tells how no child
outlives its parent.
"""

from __future__ import annotations

import contextlib
import copy
import logging
import signal
import sys
import threading
import time
from types import FrameType
from typing import TYPE_CHECKING, Any, List, Optional, Sequence

from snr.core.checks import call_checks
from snr.core.checks.runner_checks import no_role_given, runner_built, runner_ran
from snr.core.config import Config
from snr.core.node import Node
from snr.core.runners import INTERRUPTED_MESSAGE, SynchronousRunner, System, as_config, report_error
from snr.prelude.abstract import AbstractConfig, AbstractMultiRunner, AbstractRunner
from snr.prelude.errors import ConfigError, SNRError
from snr.prelude.names import Mode, Role

if TYPE_CHECKING:
    import argparse
    from multiprocessing.connection import Connection

__all__ = ["CliRunner", "MultiProcRunner"]


def _run_role(
    role: Role, config: AbstractConfig, link: Connection, inherited: Sequence[Connection]
) -> None:
    """Entry point of each MultiProcRunner child process.

    Its node stops when the parent asks, or when the parent dies: the parent writes
    a reason to the child's pipe; if it dies (even by SIGKILL) the OS closes the pipe
    and the child reads EOF: every OS, every start method.
    """
    # A forked child inherits every child's write end: while held, no child sees its parent die.
    for writer in inherited:
        writer.close()

    def watch_parent(node: Node) -> None:  # a thread's target
        try:
            reason = link.recv_bytes().decode("utf-8", "replace")
        except (EOFError, OSError):
            reason = "parent process died"
            logging.getLogger(f"snr.{role}").warning(
                "Node %r: its parent process died, stopping it.", role
            )
        node.set_terminate_flag(reason)  # thread-safe, unlike a signal handler

    def watch(node: Node) -> None:
        # Daemon: a child whose node stopped on its own must not wait for it.
        name = "snr-parent-watch"
        threading.Thread(target=watch_parent, args=(node,), name=name, daemon=True).start()

    # Ctrl-C reaches every process of the group; only the parent says so.
    SynchronousRunner(role, config, announce_interrupt=False, on_node=watch).run()


def _start_method(requested: Optional[str]) -> str:
    """The start method to use: ``requested``, else fork where it is safe, else spawn."""
    import multiprocessing  # lazily: it is slow to import and most programs run one node

    if requested is not None:
        return requested
    # fork is fast and pickles nothing, but forking a process with threads can deadlock.
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return "fork"
    return "spawn"


def _set_handlers(sigint: Any, sigterm: Any) -> None:
    """Set SIGINT's and SIGTERM's handlers (main thread only)."""
    for signum, handler in ((signal.SIGINT, sigint), (signal.SIGTERM, sigterm)):
        if handler is not None:  # None: set outside Python, cannot be restored
            signal.signal(signum, handler)


class MultiProcRunner(AbstractMultiRunner):
    """Runs several roles at once, each node in its own process.

    Ctrl-C or SIGTERM to the parent stops every child's node (``join_timeout_s``
    bounds the wait); if the parent dies, each child stops its node too.

    Example::

        runner = snr.MultiProcRunner(["topside", "urov"], config)
        runner.run()
        runner.exitcodes   # [0, 0]
        runner.stopped_by  # "SIGINT" after Ctrl-C, "SIGTERM" after kill, else None

    Attributes:
        exitcodes: each role's process exit code, after ``run()``.
        stopped_by: the signal that stopped ``run()`` early ("SIGINT" or
            "SIGTERM"), or None when every node stopped on its own.
    """

    def __init__(
        self,
        roles: Sequence[Role],
        config: System,
        start_method: Optional[str] = None,
        join_timeout_s: float = 5.0,
    ) -> None:
        self.config = as_config(config)
        call_checks.no_sim_clock_across_processes(self.config)
        known = self.config.roles()
        for role in roles:
            if role not in known:
                self.config.get(role)  # raises the friendly unknown-role error
        self.roles = list(roles)
        self.start_method = start_method
        self.join_timeout_s = join_timeout_s
        self.exitcodes: List[Optional[int]] = []
        self.stopped_by: Optional[str] = None

    def run(self) -> None:
        """Start every role's process and wait for all of them to end.

        Ctrl-C prints `INTERRUPTED_MESSAGE`; Ctrl-C and SIGTERM then stop every
        child and return normally (see `stopped_by`).
        """
        import multiprocessing  # lazily: see _start_method

        method = _start_method(self.start_method)
        ctx: Any = multiprocessing.get_context(method)
        self.stopped_by = None
        pipes = [ctx.Pipe(duplex=False) for _ in self.roles]
        writers: List[Connection] = [writer for _, writer in pipes]
        # Only a forked child shares the parent's open files; spawn pickles the arguments.
        inherited = writers if method == "fork" else []
        procs = [
            ctx.Process(
                target=_run_role, args=(role, self.config, reader, inherited), name=f"snr-{role}"
            )
            for role, (reader, _) in zip(self.roles, pipes)
        ]
        # Only the main thread may set signal handlers; elsewhere they stay as they are.
        main = threading.current_thread() is threading.main_thread()
        previous = [signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)]
        requested: List[str] = []

        def note(signum: int, frame: Optional[FrameType]) -> None:
            requested.append(signal.Signals(signum).name)

        try:
            try:
                for proc in procs:
                    proc.start()
                if main:  # after forking, so children keep the default actions
                    _set_handlers(note if previous[0] is signal.default_int_handler else None, note)
                self._wait(procs, requested)
            except KeyboardInterrupt:  # Ctrl-C while the children were starting
                requested.append("SIGINT")
            if requested:
                self.stopped_by = requested[0]
                if self.stopped_by == "SIGINT":
                    print(INTERRUPTED_MESSAGE, flush=True)
                if main:  # a second Ctrl-C must not break off the bounded wait
                    _set_handlers(signal.SIG_IGN, signal.SIG_IGN)
                self._stop_children(procs, writers, f"parent asked to stop ({self.stopped_by})")
        finally:
            self._reap(procs)
            for reader, writer in pipes:  # the children had their own copies
                reader.close()
                writer.close()
            if main:
                _set_handlers(*previous)
        self.exitcodes = [proc.exitcode for proc in procs]

    @staticmethod
    def _wait(procs: Sequence[Any], requested: List[str]) -> None:
        """Wait until every child has ended or a signal asked the parent to stop.

        The signal handlers only note the signal: an exception raised inside
        a wait for a child could lose that child's exit status.
        """
        from multiprocessing.connection import wait

        while not requested:
            running = [proc.sentinel for proc in procs if proc.exitcode is None]
            if not running:
                return
            wait(running, timeout=0.1)  # a noted signal is seen within 0.1 s

    def _stop_children(self, procs: Sequence[Any], writers: Sequence[Connection], why: str) -> None:
        """Ask each child to stop (through its pipe), then wait for all, within the join timeout."""
        for writer in writers:
            with contextlib.suppress(OSError):  # OSError: that child has already gone
                writer.send_bytes(why.encode("utf-8"))
        deadline = time.monotonic() + self.join_timeout_s
        for proc in procs:
            if proc.pid is not None:  # started
                proc.join(max(0.0, deadline - time.monotonic()))

    def _reap(self, procs: Sequence[Any]) -> None:
        """Terminate, then kill, any child still running; never leave one behind."""
        for proc in procs:
            if proc.is_alive():
                proc.terminate()
                proc.join(self.join_timeout_s)
            if proc.is_alive():
                proc.kill()
                proc.join(self.join_timeout_s)


class CliRunner(AbstractRunner):
    """Runs the role(s) named on the command line (thesis listing 5.1).

    ``python main.py urov`` runs the ``urov`` node; ``python main.py topside
    urov`` runs both, each in its own process. ``--mode deployed`` overrides
    the config's mode; an unknown role prints the known ones.

    Example::

        if __name__ == "__main__":
            snr.CliRunner(components, sys.argv).run()
    """

    def __init__(
        self,
        components_or_config: System,
        argv: Optional[Sequence[str]] = None,
    ) -> None:
        self.config = as_config(
            components_or_config,
            lambda: call_checks.check_cli_args(CliRunner, components_or_config, argv),
            exit_on_error=True,
        )
        self.argv = list(sys.argv if argv is None else argv)
        runner_built(self, self.config)

    def parse(self) -> argparse.Namespace:
        """The parsed command line; exits with a clear message when it is wrong."""
        import argparse  # only a command line needs it: kept out of `import snr`

        roles = self.config.roles()
        known = ", ".join(roles)
        prog = self.argv[0] if self.argv else "snr"
        parser = argparse.ArgumentParser(
            prog=prog,
            description="Run one or more nodes of this SNR system.",
            epilog=f"roles in this config: {known or '(none)'}",
        )
        parser.add_argument("roles", nargs="+", metavar="ROLE", help=f"the role(s) to run: {known}")
        modes = [m.value for m in Mode]
        parser.add_argument("--mode", choices=modes, help="override the config's mode")
        parser.add_argument("--verbose", action="store_true", help=argparse.SUPPRESS)  # excepthook
        if len(self.argv) < 2:
            no_role_given(parser, prog, roles)  # usage, the roles and an example; exit status 2
        args = parser.parse_args(self.argv[1:])
        for role in args.roles:
            try:
                self.config.get(role)
            except ConfigError as error:
                parser.error(str(error))
        return args

    def run(self) -> None:
        """Run the chosen role(s); Ctrl-C exits cleanly."""
        runner_ran(self)
        args = self.parse()
        config = self.config
        if args.mode is not None and isinstance(config, Config):
            config = copy.copy(config)  # all of it (clock, datastore, node core) but the mode
            config.mode = Mode(args.mode)
        try:
            if len(args.roles) == 1:
                SynchronousRunner(args.roles[0], config).run()
            else:
                MultiProcRunner(args.roles, config).run()
        except SNRError as error:
            report_error(error)
            raise SystemExit(1) from None
