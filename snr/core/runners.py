"""Runners: build nodes from a config and run them (thesis 4.2.1).

* `SynchronousRunner` runs one role in this process.
* `TestRunner` runs one node under a time limit, for tests.

`CliRunner` (the roles named on the command line) and `MultiProcRunner`
(several roles at once, one process each) build on these, in
``snr/std_mods/runners.py``.
"""

from __future__ import annotations

import sys
import threading
from typing import Callable, List, Mapping, Optional, Sequence, Union

from snr.core.checks import call_checks
from snr.core.checks.runner_checks import runner_built, runner_ran
from snr.core.config import Config
from snr.core.node import Node
from snr.prelude.abstract import AbstractConfig, AbstractFactory, AbstractRunner
from snr.prelude.errors import ConfigError, SNRError
from snr.prelude.names import Role

System = Union[AbstractConfig, Mapping[Role, Sequence[AbstractFactory]]]
"""What a runner runs: a `Config`, or each role's factories, ``{"robot": [...]}``.

A Mapping, as `Config` takes: mypy --strict would reject a plain dict for
``Dict`` (dicts are invariant)."""

__all__ = ["INTERRUPTED_MESSAGE", "System", "SynchronousRunner", "TestRunner", "as_config"]
__all__ += ["report_error"]

INTERRUPTED_MESSAGE = "Interrupted by user, exiting"
"""What a runner prints when Ctrl-C stops it (as in thesis figure 5.4)."""


def report_error(error: SNRError, role: Optional[Role] = None) -> None:
    """Print an SNR error for a person: its message, without a framework traceback.

    Example::

        except SNRError as error:
            report_error(error, "urov")   # HandlerError in node 'urov': Task handler ...
    """
    where = f" in node {role!r}" if role else ""
    print(f"{type(error).__name__}{where}: {error}", file=sys.stderr, flush=True)


def as_config(
    system: System, check: Callable[[], None] = lambda: None, exit_on_error: bool = False
) -> AbstractConfig:
    """``system`` as a config, once ``check()`` (of a runner's arguments) passed.

    With ``exit_on_error`` a `ConfigError` is printed without a traceback and
    the program exits with status 1: a runner is the top of a program.

    Example::

        as_config({"robot": [TimeoutLoopFactory(seconds=1)]})   # a Config
    """
    try:
        check()
        return system if isinstance(system, AbstractConfig) else Config(system)
    except ConfigError as error:
        if not exit_on_error:
            raise
        report_error(error)
        raise SystemExit(1) from None


class SynchronousRunner(AbstractRunner):
    """Runs the node for one role in this process until it stops.

    An SNR error is printed (it points at the student's code) and exits with
    status 1; ``exit_on_error=False`` raises it instead. ``announce_interrupt=False``
    stops quietly on Ctrl-C. ``on_node`` gets the node once built, before it runs.

    Example::

        snr.SynchronousRunner("lunar_module", config).run()

        watchdog = lambda node: threading.Timer(60, node.set_terminate_flag, ["1 min"]).start()
        snr.SynchronousRunner("lunar_module", config, on_node=watchdog).run()

    Attributes:
        node: the node, once ``run()`` has built it.
    """

    def __init__(
        self,
        role: Role,
        config: System,
        exit_on_error: bool = True,
        announce_interrupt: bool = True,
        on_node: Optional[Callable[[Node], None]] = None,
    ) -> None:
        self.role = role
        self.config = as_config(
            config,
            lambda: call_checks.check_runner_args(SynchronousRunner, role, config),
            exit_on_error,
        )
        self.exit_on_error = exit_on_error
        self.announce_interrupt = announce_interrupt
        self.on_node = on_node
        self.node: Optional[Node] = None
        runner_built(self, self.config)  # one never run is said at exit (checks/runner_checks)

    def run(self) -> None:
        """Build the node and run it; Ctrl-C stops it cleanly.

        Raises:
            SystemExit: with status 1 after printing an SNR error (see above).
        """
        runner_ran(self)
        try:
            self.node = Node(self.role, self.config)
            if self.on_node is not None:
                self.on_node(self.node)
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

    The node's exceptions reach the caller; a node still running at the limit
    is stopped, and ``timed_out`` says so.

    Example::

        runner = TestRunner("test", config, timeout_s=2)
        runner.run()
        runner.timed_out          # False when the node stopped on its own
        runner.alive_at_timeout   # names of the loops still running at the limit

    Attributes:
        node: the node, once ``run()`` has built it.
        timed_out: True when the time limit, not the node itself, ended the run.
        alive_at_timeout: the loops still running at the limit.
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
            components = list(node.components.values())
            self.alive_at_timeout = [c.name for c in components if c.is_alive()]
            self.timed_out = True
            node.set_terminate_flag(f"test time limit of {self.timeout_s} s reached")

        watchdog = threading.Timer(self.timeout_s, stop)
        watchdog.daemon = True
        watchdog.start()
        try:
            node.loop()
        finally:
            watchdog.cancel()
