"""Runners: build nodes from a config and run them (thesis 4.2.1).

* `SynchronousRunner` runs one role in this process.
* `CliRunner` reads the role(s) from the command line: ``python main.py urov``.
* `MultiProcRunner` runs several roles at once, one process each.
* `TestRunner` runs one node under a time limit, for tests.
"""

from __future__ import annotations

import argparse
import multiprocessing
import sys
import threading
from typing import Any, List, Optional, Sequence, Union

from snr.core.config import Config
from snr.core.node import Node
from snr.prelude import (
    AbstractConfig,
    AbstractMultiRunner,
    AbstractRunner,
    ComponentsByRole,
    ConfigError,
    Mode,
    Role,
    SNRError,
)

__all__ = [
    "INTERRUPTED_MESSAGE",
    "CliRunner",
    "MultiProcRunner",
    "SynchronousRunner",
    "TestRunner",
    "report_error",
]

INTERRUPTED_MESSAGE = "Interrupted by user, exiting"
"""What a runner prints when Ctrl-C stops it (as in thesis figure 5.4)."""


def report_error(error: SNRError, role: Optional[Role] = None) -> None:
    """Print an SNR error for a person: its message, without a framework traceback.

    The message already names the student's file, class or handler and shows
    their traceback frames; SNR's own frames would only hide it.

    Example::

        except SNRError as error:
            report_error(error, "urov")   # HandlerError in node 'urov': Task handler ...
    """
    where = f" in node {role!r}" if role else ""
    print(f"{type(error).__name__}{where}: {error}", file=sys.stderr, flush=True)


def _as_config(components_or_config: Union[AbstractConfig, ComponentsByRole]) -> AbstractConfig:
    if isinstance(components_or_config, AbstractConfig):
        return components_or_config
    return Config(components_or_config)


def _config_or_exit(
    components_or_config: Union[AbstractConfig, ComponentsByRole], exit_on_error: bool
) -> AbstractConfig:
    """The config; a wrong one is reported without a traceback (the runner is top level)."""
    try:
        return _as_config(components_or_config)
    except ConfigError as error:
        if not exit_on_error:
            raise
        report_error(error)
        raise SystemExit(1) from None


class SynchronousRunner(AbstractRunner):
    """Runs the node for one role in this process until it stops.

    It is the top of a student's program, so when the node stops with an
    SNR error (a handler raised, a component is written wrongly, ...) it
    prints the error's message, which points at the student's code, and
    exits with status 1, instead of a traceback through SNR's internals.
    Pass ``exit_on_error=False`` to get the exception instead, and
    ``announce_interrupt=False`` to stop quietly on Ctrl-C (as `MultiProcRunner`
    children do, so the message is printed once).

    Example::

        snr.SynchronousRunner("lunar_module", config).run()

    Attributes:
        node: the node, once ``run()`` has built it.
    """

    def __init__(
        self,
        role: Role,
        config: Union[AbstractConfig, ComponentsByRole],
        exit_on_error: bool = True,
        announce_interrupt: bool = True,
    ) -> None:
        self.role = role
        self.config = _config_or_exit(config, exit_on_error)
        self.exit_on_error = exit_on_error
        self.announce_interrupt = announce_interrupt
        self.node: Optional[Node] = None

    def run(self) -> None:
        """Build the node and run it; Ctrl-C stops it cleanly.

        Raises:
            SystemExit: with status 1 after printing an SNR error (see above).
        """
        try:
            self.node = Node(self.role, self.config)
            self.node.loop()
        except KeyboardInterrupt:
            if self.announce_interrupt:
                print(INTERRUPTED_MESSAGE, flush=True)
        except SNRError as error:
            if not self.exit_on_error:
                raise
            report_error(error, self.role)
            raise SystemExit(1) from None


class TestRunner(AbstractRunner):
    """Runs one node in the calling thread, stopping it after ``timeout_s``.

    Exceptions from the node (e.g. a failing handler in TEST mode) reach the
    caller, so a test fails with the handler's name. A node that is still
    running when the time limit comes is stopped, and ``timed_out`` says so;
    `SNRTestCase.run_test_node` turns that into a failed test.

    Example::

        runner = TestRunner("test", config, timeout_s=2)
        runner.run()
        runner.timed_out          # False when the node stopped on its own
        runner.alive_at_timeout   # names of the loops still running at the limit

    Attributes:
        node: the node, once ``run()`` has built it.
        timed_out: True when the time limit, not the node itself, ended the run.
        alive_at_timeout: the names of the loops whose threads were still
            running when the time limit came (empty when it did not).
    """

    __test__ = False  # not a pytest test class despite the name

    def __init__(self, role: Role, config: AbstractConfig, timeout_s: float = 10.0) -> None:
        self.role = role
        self.config = config
        self.timeout_s = timeout_s
        self.timed_out = False
        self.alive_at_timeout: List[str] = []
        self.node: Optional[Node] = None

    def run(self) -> None:
        """Build and run the node; a watchdog stops it after ``timeout_s``."""
        node = Node(self.role, self.config)
        self.node = node

        def stop() -> None:
            if node.is_terminated():
                return  # it stopped by itself just before the limit
            for component in list(node.components.values()):
                is_alive = getattr(component, "is_alive", None)
                if callable(is_alive) and is_alive():
                    self.alive_at_timeout.append(component.name)
            self.timed_out = True
            node.set_terminate_flag(f"test time limit of {self.timeout_s} s reached")

        watchdog = threading.Timer(self.timeout_s, stop)
        watchdog.daemon = True
        watchdog.start()
        try:
            node.loop()
        finally:
            watchdog.cancel()


def _run_role(role: Role, config: AbstractConfig) -> None:
    """Entry point of each MultiProcRunner child process."""
    # Ctrl-C reaches every process of the group; only the parent says so.
    SynchronousRunner(role, config, announce_interrupt=False).run()


def _start_method(requested: Optional[str]) -> str:
    if requested is not None:
        return requested
    # fork is fast and needs nothing picklable, but forking a process that
    # runs threads can deadlock; fall back to spawn then.
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return "fork"
    return "spawn"


class MultiProcRunner(AbstractMultiRunner):
    """Runs several roles at once, each node in its own process.

    Handy for trying a whole system on one machine, e.g. with pipe comms.

    Example::

        snr.MultiProcRunner(["topside", "urov"], config).run()

    Attributes:
        exitcodes: each role's process exit code, after ``run()``.
    """

    def __init__(
        self,
        roles: Sequence[Role],
        config: Union[AbstractConfig, ComponentsByRole],
        start_method: Optional[str] = None,
        join_timeout_s: float = 5.0,
    ) -> None:
        self.config = _as_config(config)
        known = self.config.roles()
        for role in roles:
            if role not in known:
                self.config.get(role)  # raises the friendly unknown-role error
        self.roles = list(roles)
        self.start_method = start_method
        self.join_timeout_s = join_timeout_s
        self.exitcodes: List[Optional[int]] = []

    def run(self) -> None:
        """Start every role's process and wait for all of them to end."""
        ctx: Any = multiprocessing.get_context(_start_method(self.start_method))
        procs = [
            ctx.Process(target=_run_role, args=(role, self.config), name=f"snr-{role}")
            for role in self.roles
        ]
        for proc in procs:
            proc.start()
        try:
            for proc in procs:
                proc.join()
        except KeyboardInterrupt:
            print(INTERRUPTED_MESSAGE, flush=True)
            for proc in procs:
                proc.join(self.join_timeout_s)
        finally:
            for proc in procs:
                if proc.is_alive():
                    proc.terminate()
                    proc.join(self.join_timeout_s)
        self.exitcodes = [proc.exitcode for proc in procs]


class CliRunner(AbstractRunner):
    """Runs the role(s) named on the command line (thesis listing 5.1).

    ``python main.py urov`` runs the ``urov`` node; ``python main.py topside
    urov`` runs both, each in its own process. ``--mode deployed`` overrides
    the config's mode. An unknown or missing role prints the known roles; a
    wrong config or an SNR error while running prints its message (no
    traceback through SNR) and exits with status 1.

    Example::

        if __name__ == "__main__":
            snr.CliRunner(components, sys.argv).run()
    """

    def __init__(
        self,
        components_or_config: Union[AbstractConfig, ComponentsByRole],
        argv: Optional[Sequence[str]] = None,
    ) -> None:
        self.config = _config_or_exit(components_or_config, exit_on_error=True)
        self.argv = list(sys.argv if argv is None else argv)

    def parse(self) -> argparse.Namespace:
        """The parsed command line; exits with a clear message when it is wrong."""
        roles = self.config.roles()
        prog = self.argv[0] if self.argv else "snr"
        parser = argparse.ArgumentParser(
            prog=prog,
            description="Run one or more nodes of this SNR system.",
            epilog=f"roles in this config: {', '.join(roles) or '(none)'}",
        )
        parser.add_argument(
            "roles",
            nargs="+",
            metavar="ROLE",
            help="the role(s) to run: " + ", ".join(roles),
        )
        parser.add_argument(
            "--mode",
            choices=[m.value for m in Mode],
            default=None,
            help="override the config's mode",
        )
        if len(self.argv) < 2:
            parser.print_usage(sys.stderr)
            print(
                f"{prog}: error: no role given. Choose one of: {', '.join(roles)}. "
                f"For example: python {prog} {roles[0] if roles else 'ROLE'}",
                file=sys.stderr,
            )
            raise SystemExit(2)
        args = parser.parse_args(self.argv[1:])
        for role in args.roles:
            try:
                self.config.get(role)
            except ConfigError as error:
                parser.error(str(error))
        return args

    def run(self) -> None:
        """Run the chosen role(s); Ctrl-C exits cleanly."""
        args = self.parse()
        config = self.config
        if args.mode is not None and isinstance(config, Config):
            config = Config(config.factories, mode=Mode(args.mode), profile=config.profile)
        try:
            if len(args.roles) == 1:
                SynchronousRunner(args.roles[0], config).run()
            else:
                MultiProcRunner(args.roles, config).run()
        except SNRError as error:
            report_error(error)
            raise SystemExit(1) from None
