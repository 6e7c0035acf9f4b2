"""Components and process helpers shared by the comms tests (not part of the library).

Nodes under test run in child processes; they report what they saw to the
test through a one-way pipe (`Reports`), one small message per event. What a
node prints (Ctrl-C's message, its warnings) goes to a file, not to the test
run's output; a report that never comes shows it in the failure.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import tempfile
import threading
import time
from multiprocessing.connection import Connection
from typing import Any, Callable, Dict, List, Optional, Sequence

from snr import (
    COMMS_CONNECTED,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    Mode,
    Page,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
    TimeoutLoopFactory,
    tasks,
)

SAFETY_S = 15.0  # every node in these tests stops by itself after this long


def context() -> Any:
    """fork when it is safe (one thread) and available, else spawn."""
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context("spawn")


class Reports:
    """A one-way pipe from node processes to the test."""

    def __init__(self, ctx: Any) -> None:
        self.reader, self.writer = ctx.Pipe(duplex=False)
        self.seen: List[Any] = []
        self.nodes: List[NodeProcess] = []
        """The nodes whose output a failure shows (see `NodeProcess.output`)."""

    def get(self, timeout_s: float) -> Any:
        if not self.reader.poll(timeout_s):
            raise AssertionError(
                f"no report within {timeout_s} s; so far: {self.seen[-5:]}{self.node_output()}"
            )
        item = self.reader.recv()
        self.seen.append(item)
        return item

    def wait_for(self, predicate: Callable[[Any], bool], timeout_s: float = 8.0) -> Any:
        """The first report matching ``predicate`` (earlier ones stay in ``seen``)."""
        deadline = time.monotonic() + timeout_s
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(
                    f"no matching report in {timeout_s} s: {self.seen[-5:]}{self.node_output()}"
                )
            item = self.get(remaining)
            if predicate(item):
                return item

    def node_output(self) -> str:
        """What each node in ``nodes`` printed, for a failure message."""
        return "".join(f"\nnode {n.role!r} printed:\n{n.output()}" for n in self.nodes)

    def close(self) -> None:
        self.reader.close()
        self.writer.close()


def run_role(role: str, config: Config, output_path: str) -> None:
    """Child process entry point: what the node prints goes to ``output_path``."""
    # A shell starts background jobs with SIGINT ignored, and a child inherits
    # that: Ctrl-C (`NodeProcess.ctrl_c`) must reach the node as in a terminal.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    with open(output_path, "wb") as output:  # file descriptors: C-level writes too
        os.dup2(output.fileno(), 1)
        os.dup2(output.fileno(), 2)
    SynchronousRunner(role, config).run()


class NodeProcess:
    """One node in a child process, stopped with Ctrl-C (SIGINT) or killed."""

    def __init__(self, ctx: Any, role: str, factories: Sequence[Any]) -> None:
        config = Config(
            {role: [*factories, TimeoutLoopFactory(seconds=SAFETY_S, name="safety_timeout")]},
            mode=Mode.TEST,
        )
        self.role = role
        handle, self.output_path = tempfile.mkstemp(prefix=f"snr-node-{role}-", suffix=".txt")
        os.close(handle)
        self.printed: Optional[str] = None
        """All the node printed, once `interrupt` has stopped it."""
        self.process = ctx.Process(
            target=run_role, args=(role, config, self.output_path), name=f"node-{role}"
        )

    def output(self) -> str:
        """What the node printed so far (stdout and stderr)."""
        if self.printed is not None:
            return self.printed
        with open(self.output_path, encoding="utf-8", errors="replace") as output:
            return output.read()

    def start(self) -> NodeProcess:
        self.process.start()
        return self

    def ctrl_c(self) -> None:
        """Send SIGINT, as Ctrl-C does, without waiting (`interrupt` waits)."""
        if self.process.is_alive() and self.process.pid is not None:
            os.kill(self.process.pid, signal.SIGINT)

    def interrupt(self, timeout_s: float = 5.0) -> Optional[int]:
        self.ctrl_c()
        self.process.join(timeout_s)
        self.kill()
        if self.printed is None:  # keep what it printed; its file goes
            self.printed = self.output()
            os.remove(self.output_path)
        code: Optional[int] = self.process.exitcode
        return code

    def kill(self) -> None:
        if self.process.is_alive():
            self.process.kill()
        self.process.join(5.0)

    def join(self, timeout_s: float) -> Optional[int]:
        self.process.join(timeout_s)
        code: Optional[int] = self.process.exitcode
        return code


# -- components ---------------------------------------------------------------
class SendOnConnect(Endpoint):
    """Stores ``count`` pages (data 0, 1, ...) the first time a link opens.

    Each page has ``created_at_s = 1000 + i`` so the receiver can check it.
    """

    def __init__(self, factory: SendOnConnectFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.spec = factory
        self.sent = False
        self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.send}

    def send(self, task: Task, key: TaskId) -> SomeTasks:
        if self.sent:
            return None
        self.sent = True
        spec = self.spec
        return [
            tasks.store_page(Page(spec.key, spec.first + i, self.parent.role, 1000.0 + i))
            for i in range(spec.count)
        ]


class SendOnConnectFactory(EndpointFactory):
    def __init__(self, key: str, count: int, first: int = 0, name: str = "send_on_connect"):
        super().__init__()
        self.key, self.count, self.first, self.name = key, count, first, name

    def get(self, parent: AbstractNode) -> SendOnConnect:
        return SendOnConnect(self, parent)


class Ticker(ThreadLoop):
    """Stores 0, 1, 2, ... under ``key`` at ``hz``."""

    def __init__(self, factory: TickerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, f"ticker_{factory.key}", max_tick_rate_hz=factory.hz)
        self.key = factory.key
        self.count = 0

    def loop(self) -> None:
        self.store_data(self.key, self.count)
        self.count += 1


class TickerFactory(LoopFactory):
    def __init__(self, key: str, hz: float) -> None:
        super().__init__()
        self.key, self.hz = key, hz

    def get(self, parent: AbstractNode) -> Ticker:
        return Ticker(self, parent)


class Reporter(Endpoint):
    """Reports every page processed under its keys: ``(role, key, data, origin, t)``."""

    def __init__(self, factory: ReporterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.writer = factory.writer
        self.task_handlers = {(TaskType.process_data, k): self.report for k in factory.keys}

    def report(self, task: Task, key: TaskId) -> SomeTasks:
        page: Page = task.val_list[0]
        self.writer.send((self.parent.role, page.key, page.data, page.origin, page.created_at_s))
        return None


class ReporterFactory(EndpointFactory):
    def __init__(self, writer: Connection, keys: Sequence[str], name: str = "reporter") -> None:
        super().__init__()
        self.writer, self.keys, self.name = writer, list(keys), name

    def get(self, parent: AbstractNode) -> Reporter:
        return Reporter(self, parent)


class OrderChecker(Endpoint):
    """Counts pages 0..count-1 under ``key``; reports a summary once all came.

    With ``slow_every`` it sleeps 20 ms every that many pages, so it falls
    behind a fast sender.
    """

    def __init__(self, factory: OrderCheckerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "order_checker")
        self.spec = factory
        self.received = 0
        self.out_of_order: List[Any] = []
        self.started = 0.0
        self.task_handlers = {(TaskType.process_data, factory.key): self.check}

    def check(self, task: Task, key: TaskId) -> SomeTasks:
        data = task.val_list[0].data
        if self.received == 0:
            self.started = time.perf_counter()
        if data != self.received and len(self.out_of_order) < 5:
            self.out_of_order.append((self.received, data))
        self.received += 1
        spec = self.spec
        if spec.slow_every and self.received % spec.slow_every == 0:
            time.sleep(0.02)
        if self.received == spec.count:
            took = time.perf_counter() - self.started
            spec.writer.send(("done", self.received, self.out_of_order, took))
        return None


class OrderCheckerFactory(EndpointFactory):
    def __init__(self, writer: Connection, key: str, count: int, slow_every: int = 0) -> None:
        super().__init__()
        self.writer, self.key, self.count, self.slow_every = writer, key, count, slow_every

    def get(self, parent: AbstractNode) -> OrderChecker:
        return OrderChecker(self, parent)


class Echo(Endpoint):
    """Stores every ``in_key`` page's data again under ``out_key``."""

    def __init__(self, factory: EchoFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "echo")
        self.out_key = factory.out_key
        self.task_handlers = {(TaskType.process_data, factory.in_key): self.echo}

    def echo(self, task: Task, key: TaskId) -> SomeTasks:
        return self.store_data_task(self.out_key, task.val_list[0].data)


class EchoFactory(EndpointFactory):
    def __init__(self, in_key: str, out_key: str) -> None:
        super().__init__()
        self.in_key, self.out_key = in_key, out_key

    def get(self, parent: AbstractNode) -> Echo:
        return Echo(self, parent)


class EventReporter(Endpoint):
    """Reports chosen events: ``("event", role, name, val_list)``."""

    def __init__(self, factory: EventReporterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "event_reporter")
        self.writer = factory.writer
        self.task_handlers = {(TaskType.event, name): self.report for name in factory.names}

    def report(self, task: Task, key: TaskId) -> SomeTasks:
        self.writer.send(("event", self.parent.role, task.name, list(task.val_list)))
        return None


class EventReporterFactory(EndpointFactory):
    def __init__(self, writer: Connection, names: Sequence[str]) -> None:
        super().__init__()
        self.writer, self.names = writer, list(names)

    def get(self, parent: AbstractNode) -> EventReporter:
        return EventReporter(self, parent)


class _ForwardLogs(logging.Handler):
    def __init__(self, writer: Connection, role: str) -> None:
        super().__init__(logging.WARNING)
        self.writer, self.role = writer, role

    def emit(self, record: logging.LogRecord) -> None:
        self.writer.send(("log", self.role, record.levelname, record.getMessage()[:300]))


class LogForwarder(Endpoint):
    """Sends the node's warnings and errors to the test."""

    def __init__(self, factory: LogForwarderFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "log_forwarder")
        self.handler = _ForwardLogs(factory.writer, parent.role)

    def begin(self) -> None:
        logging.getLogger("snr").addHandler(self.handler)


class LogForwarderFactory(EndpointFactory):
    def __init__(self, writer: Connection) -> None:
        super().__init__()
        self.writer = writer

    def get(self, parent: AbstractNode) -> LogForwarder:
        return LogForwarder(self, parent)


class CpuMeter(ThreadLoop):
    """Once a link is up and has settled, measures this process's CPU time."""

    def __init__(self, factory: CpuMeterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "cpu_meter")
        self.spec = factory
        self.connected = threading.Event()
        self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.on_connected}

    def on_connected(self, task: Task, key: TaskId) -> SomeTasks:
        self.connected.set()
        return None

    def loop(self) -> None:
        if not self.connected.wait(0.2):
            return
        if self.wait_s(0.25):  # let start-up work (hellos, first beats) finish
            return
        cpu, wall = time.process_time(), time.monotonic()
        if self.wait_s(self.spec.window_s):
            return
        used = time.process_time() - cpu
        self.spec.writer.send(("cpu", self.parent.role, used, time.monotonic() - wall))
        self.set_terminate_flag("measured")


class CpuMeterFactory(LoopFactory):
    def __init__(self, writer: Connection, window_s: float) -> None:
        super().__init__()
        self.writer, self.window_s = writer, window_s

    def get(self, parent: AbstractNode) -> CpuMeter:
        return CpuMeter(self, parent)


def pages_of(reports: List[Any], role: str, key: str) -> List[Any]:
    """The data of the pages ``role`` reported under ``key``, in order."""
    return [r[2] for r in reports if r[0] == role and r[1] == key]


def field_dict(report: Any) -> Dict[str, Any]:
    role, key, data, origin, created = report
    return {"role": role, "key": key, "data": data, "origin": origin, "created_at_s": created}


class StopAfter(Endpoint):
    """After ``count`` pages under ``key``: store ``then_store`` (True) or stop.

    Counts ``process_data`` tasks, or ``store_page`` ones with ``on_store``.
    """

    def __init__(self, factory: StopAfterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, f"stop_after_{factory.key}")
        self.spec = factory
        self.seen = 0
        kind = TaskType.store_page if factory.on_store else TaskType.process_data
        self.task_handlers = {(kind, factory.key): self.count}

    def count(self, task: Task, key: TaskId) -> SomeTasks:
        self.seen += 1
        if self.seen != self.spec.count:
            return None
        if self.spec.then_store:
            return self.store_data_task(self.spec.then_store, True)
        return tasks.terminate(f"got {self.spec.key}")


class StopAfterFactory(EndpointFactory):
    def __init__(
        self,
        key: str,
        count: int = 1,
        then_store: Optional[str] = None,
        on_store: bool = False,
    ) -> None:
        super().__init__()
        self.key, self.count, self.then_store, self.on_store = key, count, then_store, on_store

    def get(self, parent: AbstractNode) -> StopAfter:
        return StopAfter(self, parent)
