"""Every name of the 2021 release's ``snr.__all__``, used the way 2021 code used it.

The 2021 release exported 57 names (``RELEASE_2021`` below). These tests are
written as code for that release was: ``from snr import *``, an
``SNRTestCase``, expectors, components subclassing the release's abstract
classes. They run unchanged on today's SNR, under ``python -m unittest``
and pytest. The names the thesis replaced on purpose are used too, and
must fail with an error that names the replacement.
"""

# ruff: noqa: F403, F405  (`from snr import *`, as 2021 code wrote it)
import ast
import collections
import io
import multiprocessing
import socket
import threading
import unittest
from pathlib import Path
from typing import Any, Callable, Deque, Dict, List, Optional

from snr import *

RELEASE_2021 = [
    "tasks",
    "Mode",
    "DataKey",
    "Page",
    "TaskType",
    "TaskName",
    "TaskId",
    "Task",
    "SomeTasks",
    "TaskHandlerMap",
    "ComponentsByRole",
    "AbstractComponent",
    "AbstractFactory",
    "AbstractEndpoint",
    "Endpoint",
    "EndpointFactory",
    "AbstractLoop",
    "ThreadLoop",
    "LoopFactory",
    "AbstractContext",
    "AbstractNode",
    "AbstractProfiler",
    "AbstractMultiRunner",
    "Context",
    "Timer",
    "Node",
    "Config",
    "TestRunner",
    "CliRunner",
    "MultiProcRunner",
    "Consumer",
    "SocketsWrapper",
    "MovingAvgFilter",
    "SocketsLoopFactory",
    "SocketsListenerFactory",
    "SocketsPair",
    "CommandReceiverFactory",
    "RemoteConsole",
    "LocalConsole",
    "MovingAvgFilterFactory",
    "PipeLoopFactory",
    "RecorderEndpointFactory",
    "TextReader",
    "PageReader",
    "TextReplayerFactory",
    "ReplayerLoopFactory",
    "ListReplayerFactory",
    "PrinterEndpointFactory",
    "StopwatchEndpointFactory",
    "SNRTestCase",
    "ExpectorProtocol",
    "Expector",
    "MPExpector",
    "OrderedExpector",
    "TaskExpectations",
    "ExpectorEndpointFactory",
    "TimeoutLoopFactory",
]
"""The release's ``snr.__all__``: its ``snr/__init__.py`` and the packages it star-imports."""

STOP_S = 5.0  # the longest a node of these tests may take to stop once asked


# -- components as 2021 students wrote them -------------------------------------
class MovingAvgEndpoint(Endpoint):
    """Listing A.1's endpoint: a MovingAvgFilter behind a store_page handler."""

    def __init__(
        self,
        factory: EndpointFactory,
        parent: AbstractNode,
        input: DataKey,
        output: DataKey,
        filter: MovingAvgFilter,
    ) -> None:
        super().__init__(factory, parent, "moving_avg")
        self.input = input
        self.output = output
        self.filter = filter
        handlers: TaskHandlerMap = {(TaskType.store_page, input): self.update_filter}
        self.task_handlers = handlers

    def update_filter(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        assert isinstance(page, Page)
        self.filter.update(page.data)
        return tasks.store_page(self.page(self.output, self.filter.avg()))


class MovingAvgFactory(EndpointFactory):
    """Keeps the filter's deque, so a reloaded endpoint keeps its samples (listing A.2)."""

    def __init__(self, input: DataKey, output: DataKey, length: int) -> None:
        super().__init__()
        self.input, self.output = input, output
        self.backing_deque: Deque[float] = collections.deque(maxlen=length)

    def get(self, parent: AbstractNode) -> MovingAvgEndpoint:
        filter = MovingAvgFilter(self.backing_deque)
        return MovingAvgEndpoint(self, parent, self.input, self.output, filter)


class EchoEndpoint(Endpoint):
    """Answers each page under ``ask`` with its data under ``answer``."""

    def __init__(
        self, factory: EndpointFactory, parent: AbstractNode, ask: DataKey, answer: DataKey
    ) -> None:
        super().__init__(factory, parent, "echo")
        self.answer = answer
        self.task_handlers = {(TaskType.process_data, ask): self.echo}

    def echo(self, task: Task, key: TaskId) -> SomeTasks:
        page = self.parent.get_page(task.name)
        assert page is not None
        return tasks.store_page(self.page(self.answer, page.data))


class EchoFactory(EndpointFactory):
    def __init__(self, ask: DataKey, answer: DataKey) -> None:
        super().__init__()
        self.ask, self.answer = ask, answer

    def get(self, parent: AbstractNode) -> EchoEndpoint:
        return EchoEndpoint(self, parent, self.ask, self.answer)


class LineReaderEndpoint(Endpoint):
    """Reads a text file when the node starts, with itself as the reader's parent."""

    def __init__(self, factory: "LineReaderFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "line_reader")
        self.filename = factory.filename
        self.task_handlers = {}

    def begin(self) -> None:
        with TextReader(self, "lines", self.filename) as reader:
            line = reader.read()
            while line is not None:
                self.store_data("line", line)
                line = reader.read()


class LineReaderFactory(EndpointFactory):
    def __init__(self, filename: str) -> None:
        super().__init__()
        self.filename = filename

    def get(self, parent: AbstractNode) -> LineReaderEndpoint:
        return LineReaderEndpoint(self, parent)


class CountdownLoop(ThreadLoop):
    """Stores 3, 2, 1 under "count", then stops itself."""

    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "countdown")
        self.count = 3

    def setup(self) -> None:
        pass

    def loop(self) -> None:
        self.store_data("count", self.count)
        self.count -= 1
        if self.count == 0:
            self.set_terminate_flag("counted down")

    def halt(self) -> None:
        pass

    def terminate(self) -> None:
        pass


class CountdownFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> CountdownLoop:
        return CountdownLoop(self, parent)


class NodesInThreads(AbstractMultiRunner):
    """A 2021-style multi-runner: several nodes of one config, one thread each.

    When the first node stops, the others are asked to stop too; an error in
    any node is raised by ``run()``.
    """

    def __init__(self, roles: List[str], config: Config) -> None:
        self.nodes = [Node(role, config) for role in roles]
        self.errors: List[BaseException] = []
        self.one_stopped = threading.Event()

    def run_one(self, node: Node) -> None:
        try:
            node.loop()
        except BaseException as error:
            self.errors.append(error)
        finally:
            self.one_stopped.set()

    def run(self) -> None:
        threads = [threading.Thread(target=self.run_one, args=(node,)) for node in self.nodes]
        for thread in threads:
            thread.start()
        self.one_stopped.wait(STOP_S * 2)
        for node in self.nodes:
            node.set_terminate_flag("another node stopped")
        for thread in threads:
            thread.join(STOP_S)
        assert not any(thread.is_alive() for thread in threads), "a node did not stop"
        if self.errors:
            raise self.errors[0]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def count_in_child(expector: ExpectorProtocol) -> None:
    expector.call("child")


# -- the tests --------------------------------------------------------------------
class TestTheNames(SNRTestCase):
    def test_from_snr_import_star_gives_all_57(self) -> None:
        namespace: Dict[str, Any] = {}
        exec("from snr import *", namespace)
        self.assertEqual(len(RELEASE_2021), 57)
        self.assertEqual(sorted(set(RELEASE_2021) - set(namespace)), [])

    def test_this_file_uses_every_one_of_them(self) -> None:
        tree = ast.parse(Path(__file__).read_text(encoding="utf-8"))
        read = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
        self.assertEqual(sorted(set(RELEASE_2021) - read), [])


class TestTheAbstractBaseClasses(SNRTestCase):
    def test_components_are_abstract_components(self) -> None:
        components: ComponentsByRole = {
            "test": [MovingAvgFactory("in", "out", 2), CountdownFactory()]
        }
        node = Node("test", Config(components, mode=Mode.TEST))
        parts: Dict[str, AbstractComponent] = dict(node.components)
        self.assertIsInstance(parts["moving_avg"], AbstractEndpoint)
        self.assertIsInstance(parts["moving_avg"], AbstractComponent)
        self.assertIsInstance(parts["countdown"], AbstractLoop)
        self.assertIsInstance(parts["countdown"], AbstractComponent)
        self.assertTrue(issubclass(Endpoint, AbstractComponent))
        self.assertTrue(issubclass(ThreadLoop, AbstractLoop))
        for factory in components["test"]:
            self.assertIsInstance(factory, AbstractFactory)

    def test_a_loop_missing_methods_is_refused_by_name(self) -> None:
        class HalfLoop(AbstractLoop):  # setup, loop, ... left out
            pass

        with self.assertRaises(SNRError) as ctx:
            HalfLoop()  # type: ignore[abstract]
        self.assertIn("HalfLoop", str(ctx.exception))

    def test_the_profiler_is_an_abstract_profiler(self) -> None:
        factories = [CountdownFactory(), TimeoutLoopFactory(ms=50)]
        config = Config({"test": factories}, mode=Mode.TEST, profile=True)
        profiler: Optional[AbstractProfiler] = config.get_profiler()
        self.assertIsInstance(profiler, AbstractProfiler)
        runner = TestRunner(config)
        runner.run()
        self.assertFalse(runner.timed_out)
        assert runner.node is not None
        profiler = runner.node.profiler
        assert isinstance(profiler, AbstractProfiler)
        self.assertIn("Loop(timeout_loop)", profiler.dump())

    def test_the_multi_runners_are_abstract_multi_runners(self) -> None:
        config = Config({"a": [TimeoutLoopFactory()], "b": [TimeoutLoopFactory()]}, mode=Mode.TEST)
        self.assertIsInstance(MultiProcRunner(["a", "b"], config), AbstractMultiRunner)
        runner: AbstractMultiRunner = NodesInThreads(["a", "b"], config)
        runner.run()


class TestRunners(SNRTestCase):
    def test_test_runner_runs_the_role_test(self) -> None:
        self.assertIsInstance(
            TestRunner(Config({"test": [CountdownFactory()]}, mode=Mode.TEST)), SynchronousRunner
        )
        self.assertFalse(TestRunner.__test__)
        with self.expector({(TaskType.store_page, "count"): 3}) as expector:
            runner = TestRunner(
                Config(
                    {"test": [CountdownFactory(), ExpectorEndpointFactory(expector, True)]},
                    mode=Mode.TEST,
                )
            )
            runner.run()
        assert runner.node is not None
        self.assertEqual(runner.node.role, "test")
        self.assertEqual(runner.node.get_data("count"), 1)

    def test_an_error_in_the_node_reaches_the_test(self) -> None:
        class Broken(ThreadLoop):
            def loop(self) -> None:
                raise ValueError("sensor unplugged")

        class BrokenFactory(LoopFactory):
            def get(self, parent: AbstractNode) -> Broken:
                return Broken(self, parent, "broken")

        with self.assertRaises(SNRError) as ctx, self.assertLogs("snr.test", "ERROR") as logs:
            TestRunner(Config({"test": [BrokenFactory()]}, mode=Mode.TEST)).run()
        self.assertIn("sensor unplugged", str(ctx.exception))
        self.assertIn("Loop 'broken'", "\n".join(logs.output))  # the node says why it stops

    def test_a_wrong_call_says_what_to_pass(self) -> None:
        with self.assertRaises(TypeError) as ctx:
            TestRunner("test")  # type: ignore[arg-type]
        self.assertIn("role first", str(ctx.exception))

    def test_cli_runner_and_a_node_and_a_timer(self) -> None:
        timer = Timer()
        times: List[float] = []
        config = Config(
            {
                "test": [
                    TimeoutLoopFactory(ms=20),
                    StopwatchEndpointFactory(times, [TaskType.terminate]),
                ]
            },
            mode=Mode.TEST,
        )
        CliRunner(config, ["robot.py", "test"]).run()
        self.assertEqual(len(times), 1)
        self.assertGreaterEqual(timer.current_s(), 0.02)
        node = Node("test", Config({"test": [TimeoutLoopFactory()]}, mode=Mode.TEST))
        node.loop()
        self.assertTrue(node.is_terminated())


class TestFilter(SNRTestCase):
    def test_moving_avg_filter_on_a_deque(self) -> None:
        filter = MovingAvgFilter(collections.deque(maxlen=2))
        self.assertEqual(filter.avg(), 0)
        for value in (1, 3, 5):
            filter.update(value)
        self.assertEqual(filter.avg(), 4.0)

    def test_listing_a1_endpoint_and_the_ready_made_factory_agree(self) -> None:
        for factory in (MovingAvgFactory("in", "out", 2), MovingAvgFilterFactory("in", "out", 2)):
            with self.subTest(factory=type(factory).__name__):
                with self.expector({(TaskType.store_page, "out"): 4}) as expector:
                    node = self.run_test_node(
                        [
                            ListReplayerFactory([0, 1, 2, 4], "in"),
                            factory,
                            ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                        ]
                    )
                self.assertEqual(node.get_data("out"), 3.0)


class TestExpectors(SNRTestCase):
    def test_ordered_expector_in_order(self) -> None:
        order: List[TaskId] = [(TaskType.store_page, "count")] * 3
        with OrderedExpector(order, self) as expector:
            self.run_test_node([CountdownFactory(), ExpectorEndpointFactory(expector, True)])
        self.assertIsInstance(expector, ExpectorProtocol)

    def test_ordered_expector_names_both_orders_when_wrong(self) -> None:
        first: TaskName = "first"
        second: TaskName = "second"
        expector = OrderedExpector([(TaskType.event, first), (TaskType.event, second)], self)
        expector.call((TaskType.event, second))
        expector.call((TaskType.event, first))
        with self.assertRaises(AssertionError) as ctx:
            expector.assert_satisfied()
        message = str(ctx.exception)
        self.assertIn("expected order: (event, 'first'), (event, 'second')", message)
        self.assertIn("seen order: (event, 'second'), (event, 'first')", message)

    def test_expector_of_task_expectations(self) -> None:
        expectations: TaskExpectations = {(TaskType.store_page, "count"): 3}
        with Expector(expectations, self) as expector:
            self.run_test_node([CountdownFactory(), ExpectorEndpointFactory(expector, True)])

    def test_mp_expector_counts_from_a_child_process(self) -> None:
        context = multiprocessing.get_context("spawn")
        with MPExpector[str]({"child": 1}, self, context=context) as expector:
            child = context.Process(target=count_in_child, args=(expector,))
            child.start()
            child.join(30)
            self.assertEqual(child.exitcode, 0)


class TestReadersAndReplayers(SNRTestCase):
    def test_text_reader_with_a_test_case_a_node_or_a_component_as_parent(self) -> None:
        path = self.temp_file("log.txt", "GPGGA,1\r\n\nGPGGA,2\n")
        node = Node("test", Config({"test": [TimeoutLoopFactory()]}, mode=Mode.TEST))
        for parent in (self, node, node.components["timeout_loop"]):
            with self.subTest(parent=type(parent).__name__):
                with TextReader(parent, "gps", path) as reader:
                    lines = [reader.read(), reader.read(), reader.read(), reader.read()]
                self.assertEqual(lines, ["GPGGA,1", "", "GPGGA,2", None])
                self.assertIsNone(reader.read())  # closed
        reader = TextReader(self, "gps", path)
        reader.open()
        self.assertEqual(reader.read(), "GPGGA,1")
        reader.close()

    def test_a_component_reads_a_text_file(self) -> None:
        path = self.temp_file("lines.txt", "a\nb\n")
        with self.expector({(TaskType.store_page, "line"): 2}) as expector:
            node = self.run_test_node(
                [LineReaderFactory(path), ExpectorEndpointFactory(expector, True)]
            )
        self.assertEqual(node.get_data("line"), "b")

    def test_text_replayer_stores_each_line_then_exits(self) -> None:
        path = self.temp_file("commands.txt", "forward\nleft\nstop\n")
        with self.expector({(TaskType.store_page, "command"): 3}) as expector:
            node = self.run_test_node(
                [TextReplayerFactory(path, "command", exit=True), ExpectorEndpointFactory(expector)]
            )
        self.assertEqual(node.get_data("command"), "stop")

    def test_text_replayer_of_an_empty_file_ends_at_once(self) -> None:
        path = self.temp_file("empty.txt", "")
        with self.expector({(TaskType.store_page, "command"): 0}) as expector:
            node = self.run_test_node(
                [TextReplayerFactory(path, "command", True), ExpectorEndpointFactory(expector)],
                timeout_s=2,
            )
        self.assertIn("replayed", str(node.terminate_reason))

    def test_record_then_read_pages_back(self) -> None:
        path = self.temp_file("run.jsonl")
        with self.expector({(TaskType.store_page, "count"): 3}) as expector:
            self.run_test_node(
                [
                    RecorderEndpointFactory(path, ["count"]),
                    CountdownFactory(),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )
        node = Node("test", Config({"test": [TimeoutLoopFactory()]}, mode=Mode.TEST))
        with PageReader(node, "pages", path) as reader:
            pages: List[Page] = []
            page = reader.read()
            while page is not None:
                pages.append(page)
                page = reader.read()
        self.assertEqual([p.data for p in pages], [3, 2, 1])
        self.assertEqual({p.origin for p in pages}, {"test"})

    def test_page_reader_reads_what_the_2021_recorder_wrote(self) -> None:
        lines = [Page("depth", 2.0 + i, "urov", 100.0 + i).serialize() for i in range(3)]
        path = self.temp_file("old.jsonl", "\n".join(lines) + "\n")
        with PageReader(self, "old", path) as reader:
            first = reader.read()
            self.assertEqual(first, Page("depth", 2.0, "urov", 100.0))
            self.assertEqual([reader.read(), reader.read(), reader.read()][-1], None)

    def test_replay_follows_created_at_s_not_the_file(self) -> None:
        made = [Page("depth", float(i), "urov", 100.0 + i / 100) for i in range(6)]
        shuffled = [made[i] for i in (1, 0, 3, 2, 5, 4)]  # newest-first pairs, as 2021 wrote
        path = self.temp_file("shuffled.jsonl", "".join(p.serialize() + "\n" for p in shuffled))
        with self.ordered_expector([(TaskType.store_page, "depth")] * 6) as expector:
            node = self.run_test_node(
                [
                    ReplayerLoopFactory(path, exit_when_done=True),
                    ExpectorEndpointFactory(expector),
                    PagesSeenFactory(self.seen),
                ]
            )
        self.assertEqual([p.data for p in self.seen], [0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
        self.assertEqual(node.get_data("depth"), 5.0)

    def setUp(self) -> None:
        self.seen: List[Page] = []


class PagesSeen(Endpoint):
    """Keeps every stored page, in the order the node stored them."""

    def __init__(self, factory: "PagesSeenFactory", parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pages_seen")
        self.seen = factory.seen
        self.task_handlers = {TaskType.store_page: self.keep}

    def keep(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]
        assert isinstance(page, Page)
        self.seen.append(page)
        return None


class PagesSeenFactory(EndpointFactory):
    def __init__(self, seen: List[Page]) -> None:
        super().__init__()
        self.seen = seen

    def get(self, parent: AbstractNode) -> PagesSeen:
        return PagesSeen(self, parent)


class TestBetweenNodes(SNRTestCase):
    def test_pipe_loops_forward_pages_both_ways(self) -> None:
        a_end, b_end = multiprocessing.Pipe()
        printed = io.StringIO()
        with self.expector({(TaskType.store_page, "pong"): 3}) as expector:
            config = Config(
                {
                    "a": [
                        ListReplayerFactory([1, 2, 3], "ping"),
                        PipeLoopFactory(a_end, ["ping"]),
                        PrinterEndpointFactory([(TaskType.store_page, "pong")], printed),
                        ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                    ],
                    "b": [PipeLoopFactory(b_end, ["pong"]), EchoFactory("ping", "pong")],
                },
                mode=Mode.TEST,
            )
            NodesInThreads(["a", "b"], config).run()
        self.assertEqual(len(printed.getvalue().splitlines()), 3, printed.getvalue())
        self.assertIn("Page 'pong' = 3 from 'b'", printed.getvalue())

    def test_a_pipe_loop_with_no_keys_ends_with_its_node(self) -> None:
        mine, theirs = multiprocessing.Pipe()
        node = self.run_test_node([PipeLoopFactory(mine), TimeoutLoopFactory(ms=20)])
        self.assertFalse(any(c.is_alive() for c in node.components.values()))
        with self.assertRaises(EOFError):
            while theirs.poll(STOP_S):
                theirs.recv_bytes()  # SNR's hello, then the end of the pipe

    def test_sockets_pair_between_two_nodes(self) -> None:
        sockets = SocketsPair(("127.0.0.1", free_port()))
        with self.expector({(TaskType.store_page, "ping"): 3}) as expector:
            config = Config(
                {
                    "topside": [sockets.client(["ping"]), PingsFactory()],
                    "urov": [sockets.server(), ExpectorEndpointFactory(expector, True)],
                },
                mode=Mode.TEST,
            )
            NodesInThreads(["urov", "topside"], config).run()

    def test_consoles_drive_a_node(self) -> None:
        for make in (
            lambda port: RemoteConsole(("127.0.0.1", port), ["task event beep", "exit"]),
            lambda port: LocalConsole(port, ["list endpoints", "exit"]),
        ):
            with self.subTest(console=make):
                self.run_console_against_a_node(make)

    def run_console_against_a_node(self, make: Callable[[int], RemoteConsole]) -> None:
        receiver = CommandReceiverFactory(port=0)
        output = io.StringIO()
        codes: List[int] = []

        def console() -> None:
            _, port = receiver.wait_until_listening(STOP_S)
            codes.append(make(port).run(output))

        thread = threading.Thread(target=console)
        thread.start()
        node = self.run_test_node([receiver, TimeoutLoopFactory(seconds=STOP_S)], timeout_s=10)
        thread.join(STOP_S)
        self.assertEqual(codes, [0], output.getvalue())
        self.assertIn("console", str(node.terminate_reason))


class PingsFactory(LoopFactory):
    """Stores 1, 2, 3 under "ping" once a comms link is up."""

    def get(self, parent: AbstractNode) -> "PingLoop":
        return PingLoop(self, parent)


class PingLoop(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "pings", max_tick_rate_hz=100)
        self.linked = threading.Event()
        self.sent = 0
        self.task_handlers = {(TaskType.event, COMMS_CONNECTED): self.on_link}

    def on_link(self, task: Task, key: TaskId) -> SomeTasks:
        self.linked.set()
        return None

    def loop(self) -> None:
        if self.linked.is_set() and self.sent < 3:
            self.sent += 1
            self.store_data("ping", self.sent)


class TestRefusedNames(SNRTestCase):
    def test_each_names_its_replacement(self) -> None:
        replacements: Dict[Any, str] = {
            Settings: "Config",
            Context: "self.parent",
            AbstractContext: "AbstractNode",
            Consumer: "ThreadLoop",
            SocketsWrapper: "SocketsPair",
            SocketsLoopFactory: "SocketsPair(server_tuple).client",
            SocketsListenerFactory: "SocketsPair(server_tuple).server",
        }
        for removed, replacement in replacements.items():
            with self.subTest(name=removed.__name__):
                with self.assertRaises(RemovedApiError) as ctx:
                    removed()
                self.assertIn(replacement, str(ctx.exception))
                self.assertIsInstance(ctx.exception, SNRError)


if __name__ == "__main__":
    unittest.main()
