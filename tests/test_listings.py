"""Every code listing of the thesis runs as printed (the files in tests/listings/).

Each file in tests/listings/ is one listing as printed, with only the PDF's
artefacts repaired (indentation, lines broken by the typesetting) and the few
changes docs/deviations.md lists, each marked ``DEVIATION [tag]`` on its line.
The listings import each other by bare module name (``import
control_processor_endpoint``), as files in one folder do, so the tests put
that folder first on sys.path, as ``python listing_5_3.py`` would. The folder
has no ``__init__.py`` and no ``test_*.py`` file, so neither pytest nor
unittest collects the listings themselves; A.3 and A.5, which are test
modules, are run from here.
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import io
import logging
import os
import re
import sys
import threading
import time
import unittest
from types import ModuleType
from typing import Any, Callable, Dict, Iterator, List, Tuple
from unittest import mock

import snr
from snr import AbstractNode, Node, SNRTestCase, Task, TaskType, tasks
from snr.utils import ExpectorEndpointFactory, ListReplayerFactory
from tests.helpers import free_port
from tests.optional import reason
from tests.quiet import capture_test_logs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LISTINGS = os.path.join(ROOT, "tests", "listings")
UROV_EXAMPLE = os.path.join(ROOT, "examples", "urov")
DEVIATIONS_MD = os.path.join(ROOT, "docs", "deviations.md")

# Every code listing of the thesis and the file that holds it.
CATALOG: Dict[str, str] = {
    "5.1": "listing_5_1.py",
    "5.3": "listing_5_3.py",
    "6.1": "listing_6_1.py",
    "6.2": "listing_6_2.py",
    "6.3": "listing_6_3.py",
    "6.4": "listing_6_4.py",
    "A.1": "moving_avg/moving_avg_endpoint.py",
    "A.2": "moving_avg/moving_avg_endpoint_factory.py",
    "A.3": "listing_a3.py",
    "A.4": "listing_a4.py",
    "A.5": "bench_stress_endpoint_fac.py",
    "A.6": "control_processor_factory.py",
    "A.7": "control_processor_endpoint.py",
    "A.8": "controller_loop.py",
    "A.9": "controller_loop_factory.py",
    "A.10": "input_mapping_factory.py",
    "A.11": "input_mapping_endpoint.py",
}
# Listing 5.2 is the shell output of A.5 (checked in TestBenchmarkListing); the
# B listings are shell sessions, 7.1 an error message.


@contextlib.contextmanager
def on_path(*folders: str) -> Iterator[None]:
    """``folders`` first on sys.path for the duration, as for ``python file.py``."""
    sys.path[:0] = folders
    try:
        yield
    finally:
        for folder in folders:
            sys.path.remove(folder)


def fresh_import(name: str, *extra_folders: str) -> ModuleType:
    """Run listing ``name`` anew (the sibling listings it imports may come from
    sys.modules; a package's modules are all run anew)."""
    package = name.split(".")[0]
    for loaded in [m for m in sys.modules if m == package or m.startswith(package + ".")]:
        del sys.modules[loaded]
    with on_path(LISTINGS, *extra_folders):
        return importlib.import_module(name)


@contextlib.contextmanager
def sockets_on_free_local_ports() -> Iterator[List[Tuple[str, int]]]:
    """Run a listing with every ``snr.SocketsPair`` on 127.0.0.1 and a free port.

    Listings 5.1 and 5.3 print fixed addresses (another machine, or port 9000,
    which another program may hold). The listing's text is left alone: while
    it runs, ``snr.SocketsPair`` is a subclass that keeps everything but the
    address. Yields the addresses the listing asked for.
    """
    printed: List[Tuple[str, int]] = []
    real = snr.SocketsPair

    class LocalSocketsPair(real):  # type: ignore[misc, valid-type]
        def __init__(self, server_tuple: Tuple[str, int], *args: Any, **kwargs: Any) -> None:
            printed.append(server_tuple)
            super().__init__(("127.0.0.1", free_port()), *args, **kwargs)

    with mock.patch.object(snr, "SocketsPair", LocalSocketsPair):
        yield printed


class RolesInThreads:
    """Runs roles of a listing's config, each node on its own thread, as
    ``SynchronousRunner`` does for one role (what ``CliRunner`` runs per role)."""

    def __init__(self, components: snr.ComponentsByRole, roles: List[str]) -> None:
        self.nodes: Dict[str, Node] = {}
        self.errors: List[BaseException] = []
        self.stopping = threading.Event()
        self.threads = [
            threading.Thread(target=self._run, args=(components, role), name=f"listing-{role}")
            for role in roles
        ]

    def _run(self, components: snr.ComponentsByRole, role: str) -> None:
        def keep(node: Node) -> None:
            self.nodes[role] = node
            if self.stopping.is_set():  # stop() came before this node was built
                node.set_terminate_flag("the test has ended")

        try:
            snr.SynchronousRunner(role, components, exit_on_error=False, on_node=keep).run()
        except BaseException as error:  # reported by stop()
            self.errors.append(error)

    def start(self) -> None:
        for thread in self.threads:
            thread.start()

    def wait_for(self, condition: Callable[[], bool], timeout_s: float = 10.0) -> bool:
        """Poll ``condition`` until it holds or ``timeout_s`` passes."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if condition() or self.errors:
                return condition()
            time.sleep(0.01)
        return False

    def data(self, role: str, key: str) -> Any:
        node = self.nodes.get(role)
        return None if node is None else node.get_data(key)

    def stop(self) -> None:
        self.stopping.set()
        for node in list(self.nodes.values()):
            node.set_terminate_flag("the test has seen what it waited for")
        for thread in self.threads:
            thread.join(10)
        alive = [thread.name for thread in self.threads if thread.is_alive()]
        if alive or self.errors:
            raise AssertionError(f"nodes did not stop cleanly: alive {alive}, {self.errors!r}")


def run_test_cases(case: type) -> Tuple[unittest.TestResult, str]:
    """Run a listing's ``SNRTestCase`` as ``python -m unittest`` would; and its stdout."""
    suite = unittest.defaultTestLoader.loadTestsFromTestCase(case)
    result = unittest.TestResult()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        suite.run(result)
    return result, out.getvalue()


class TestListingFiles(unittest.TestCase):
    def test_every_listing_has_one_file_that_names_it(self) -> None:
        found = sorted(
            os.path.relpath(os.path.join(folder, name), LISTINGS).replace(os.sep, "/")
            for folder, _, names in os.walk(LISTINGS)
            for name in names
            if name.endswith(".py") and name != "__init__.py"
        )
        self.assertEqual(found, sorted(CATALOG.values()))
        for number, path in CATALOG.items():
            with open(os.path.join(LISTINGS, path), encoding="utf-8") as file:
                first_line = file.readline()
            self.assertTrue(first_line.startswith(f'"""Thesis listing {number}: '), path)

    def test_deviations_md_matches_the_listing_files(self) -> None:
        """Each deviation docs/deviations.md lists for a listing file is marked
        in that file, and the file marks no other; files without one say so."""
        with open(DEVIATIONS_MD, encoding="utf-8") as file:
            text = file.read()
        section = text.split("## Running the listings as printed", 1)[1].split("\n## ", 1)[0]
        rows = re.findall(
            r"^\| `([\w.-]+)` \| ([\w.]+) \| `tests/listings/([\w/.]+)` \|", section, re.M
        )
        self.assertGreater(len(rows), 0, "no deviation rows found in deviations.md")
        listed: Dict[str, List[str]] = {}
        for tag, number, path in rows:
            self.assertEqual(
                CATALOG.get(number), path, f"row {tag}: listing {number} is not {path}"
            )
            self.assertTrue(tag.startswith(number + "-"), tag)
            listed.setdefault(path, []).append(tag)
        for path in CATALOG.values():
            with open(os.path.join(LISTINGS, path), encoding="utf-8") as file:
                source = file.read()
            header = source.split('"""', 2)[1]
            in_header = re.findall(r"^- \[([\w.-]+)\]", header, re.M)
            on_lines = set(re.findall(r"# DEVIATION \[([\w.-]+)\]", source))
            expected = listed.get(path, [])
            with self.subTest(path=path):
                self.assertEqual(in_header, expected)
                self.assertEqual(on_lines, set(expected))
                self.assertEqual("Deviations: none" in header, not expected)


class TestMovingAverageListings(SNRTestCase):
    """A.1 (endpoint), A.2 (factory) and A.3 (its test), as printed."""

    def listing_a2(self) -> ModuleType:
        return fresh_import("moving_avg.moving_avg_endpoint_factory")

    def test_a1_a2_filter_and_its_state_on_the_factory(self) -> None:
        # The same checks pass for SNR's own MovingAvgFilterFactory.
        for factory_class in [self.listing_a2().MovingAvgFilterFactory, snr.MovingAvgFilterFactory]:
            with self.subTest(factory=factory_class.__module__):
                factory = factory_class("in", "out", 2)
                node = self.mock_node()
                endpoint = factory.get(node)
                outputs = []
                for value in [0, 1, 2, 4]:
                    result = endpoint.update_filter(
                        tasks.store_data("in", value), (TaskType.store_page, "in")
                    )
                    assert isinstance(result, Task)
                    outputs.append(result.val_list[0].data)
                self.assertEqual(outputs, [0.0, 0.5, 1.5, 3.0])
                # A new endpoint from the same factory (as after a reload) keeps the samples.
                self.assertEqual(factory.get(node).filter.avg(), 3.0)
                with self.assertLogs("snr.mock", "WARNING"):
                    self.assertIsNone(
                        endpoint.update_filter(
                            tasks.store_data("in", "abc"), (TaskType.store_page, "in")
                        )
                    )

    def test_a2_reloads_the_endpoint_and_the_2021_filter_module(self) -> None:
        a2 = self.listing_a2()
        factory = a2.MovingAvgFilterFactory("in", "out", 3)
        from snr.core import MovingAvgFilter, moving_avg_filter

        self.assertEqual(factory.reload_targets, [a2.moving_avg_endpoint, moving_avg_filter])
        self.assertIs(a2.moving_avg_filter.MovingAvgFilter, MovingAvgFilter)

    def test_a2_in_a_node_as_a3_tests_it(self) -> None:
        expectations = {(TaskType.store_page, "out"): 4, (TaskType.process_data, "out"): 4}
        with self.expector(expectations) as expector:
            node = self.run_test_node([
                ListReplayerFactory([0, 1, 2, 4], "in"),
                self.listing_a2().MovingAvgFilterFactory("in", "out", 2),
                ExpectorEndpointFactory(expector, exit_when_satisfied=True),
            ])  # fmt: skip
        self.assertEqual(node.get_data("out"), 3.0)

    def test_a3_passes(self) -> None:
        result, _ = run_test_cases(fresh_import("listing_a3").TestMovingAvgEndpoint)
        self.assertEqual((result.testsRun, result.errors, result.failures), (1, [], []))


class TestLunarLanderListing(unittest.TestCase):
    def test_a4_flies_until_it_crashes(self) -> None:
        """As printed, no throttle can land it; the flight ends in the listing's exception."""
        a4 = fresh_import("listing_a4")
        loop_factory, controller_factory = a4.config.get("lunar_module")
        readings: List[Any] = []

        # The loop ticks at 0.5 Hz, so the flight takes four seconds; run it at
        # 200 Hz. And note what the controller's Q function is asked about.
        def fast_loop(parent: AbstractNode) -> Any:
            loop = type(loop_factory).get(loop_factory, parent)
            loop.max_tick_rate_hz = 200.0
            return loop

        def noted_controller(parent: AbstractNode) -> Any:
            endpoint = type(controller_factory).get(controller_factory, parent)
            rate = endpoint.q_function

            def noted_rate(data: Any, action: Any) -> Any:
                readings.append(data)
                return rate(data, action)

            endpoint.q_function = noted_rate
            return endpoint

        err = io.StringIO()
        with (
            mock.patch.object(loop_factory, "get", fast_loop),
            mock.patch.object(controller_factory, "get", noted_controller),
            contextlib.redirect_stderr(err),
            self.assertRaises(SystemExit) as exit,
            self.assertLogs("snr.lunar_module", "ERROR") as logs,
        ):
            a4.main()
        self.assertEqual(exit.exception.code, 1)
        self.assertIn("Stopping node 'lunar_module': Loop 'radar_sensor_endpoint'", logs.output[0])
        self.assertIn("LoopError in node 'lunar_module'", err.getvalue())
        self.assertIn("raised Exception: High velocity impact", err.getvalue())
        # Four actions rated per reading; (altitude, velocity) falls by 9.8 m/s a tick.
        self.assertGreaterEqual(len(readings), 4)
        for got, expected in zip(readings, [(40.2, -9.8)] * 4 + [(20.6, -19.6)] * 4):
            self.assertEqual(len(got), 2)
            for value, want in zip(got, expected):
                self.assertAlmostEqual(value, want)


class TestBenchmarkListing(unittest.TestCase):
    def test_a5_runs_and_prints_listing_5_2(self) -> None:
        bench = fresh_import("bench_stress_endpoint_fac")

        def short_timeout(seconds: float) -> snr.TimeoutLoopFactory:
            return snr.TimeoutLoopFactory(seconds=min(seconds, 0.2))

        # The only change: the printed 2 s run is ended after 0.2 s (see the file's header).
        with (
            mock.patch.object(bench, "TimeoutLoopFactory", short_timeout),
            self.assertLogs("snr", "INFO") as logs,
        ):
            logging.getLogger("snr").info("listing A.5 starts")
            result, out = run_test_cases(bench.BenchStressEndpointFac)
        self.assertEqual((result.testsRun, result.errors, result.failures), (2, [], []))
        # Its factory returns None once it has made enough endpoints, as the
        # documented "add nothing": no warning for each of them.
        self.assertEqual([line for line in logs.output if "returned None" in line], [])
        # The shape of listing 5.2.
        lines = [line.strip() for line in out.splitlines()]
        self.assertIn("Stressed with:", lines)
        self.assertIn("Terminate expected at 2000 ms", lines)
        made_line = re.search(r"(\d+) stressor endpoints", out)
        calls_line = re.search(r"(\d+) stressor factory calls", out)
        assert made_line and calls_line, out
        made, calls = int(made_line.group(1)), int(calls_line.group(1))
        self.assertGreaterEqual(calls, made)
        self.assertGreaterEqual(made, 1)  # more in 0.2 s, unless the machine is busy
        self.assertRegex(out, r"[\d.]+ ms terminate handled\n")
        self.assertRegex(out, r"[\d.]+ ms total time\n")
        self.assertIn("Times called,", out)
        self.assertRegex(out, r"\d+ x +[\d.]+ us -> +[\d.]+%: \(event, 'stress'\):bench_stress")
        self.assertRegex(out, r"\(event, 'add_component'\):snr.core.node")


class TestControllerListings(SNRTestCase):
    """A.6-A.11 and listing 5.3, the game controller over sockets."""

    def test_a10_a11_give_the_controls_their_names(self) -> None:
        a10 = fresh_import("input_mapping_factory")
        endpoint = a10.InputMappingFactory("raw", "named").get(self.mock_node())
        raw = {"button_2": 1, "button_5": 0, "axis_0": 0.5, "button_20": 1, "dhat_0": [0, 1]}
        result = endpoint.map_raw_input(tasks.store_data("raw", raw), (TaskType.store_page, "raw"))
        self.assertEqual(result.name, "named")
        self.assertEqual(result.val_list[0].data, {"A": 1, "Y": 0, "left_stick_X": 0.5})

    def test_a6_a7_compare_with_the_previous_input(self) -> None:
        a6 = fresh_import("control_processor_factory")
        node = self.mock_node()
        endpoint = a6.ControlProcessorFactory("named").get(node)
        self.assertEqual(endpoint.name, "input_processor_endpoint")
        task = tasks.store_data("named", {"A": 1, "B": 0, "X": 1})
        with self.assertLogs("snr.mock", "INFO") as logs:
            self.assertIsNone(endpoint.process_input(task, (TaskType.store_page, "named")))
        self.assertIn("No previous input data", logs.output[0])
        # Nothing in the listings stores "named_prev"; when something does:
        node.store_data("named_prev", {"A": 0, "B": 1, "X": 1})
        events = endpoint.process_input(task, (TaskType.store_page, "named"))
        self.assertEqual(
            [(e.name, e.val_list) for e in events],
            [("button_pressed", ["A"]), ("button_released", ["B"])],
        )

    def test_5_3_with_a8_on_a_virtual_pad_sends_the_input_to_the_receiver(self) -> None:
        capture_test_logs(self)  # the listing's DEBUG nodes log INFO lines
        os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # no screen, no sound
        os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        try:
            pygame: Any = importlib.import_module("pygame")
        except ImportError:
            self.skipTest(reason("pygame"))
        # As a module, not its names: its test classes must not be collected twice.
        from tests import test_controller_pygame as virtual_pads

        sdl = virtual_pads.loaded_sdl_library()
        if sdl is None:
            self.skipTest("cannot reach the SDL library pygame loaded to plug in a virtual pad")
        pygame.display.init()
        pygame.joystick.init()  # SDL's joystick system must be up to attach a pad
        self.addCleanup(pygame.quit)
        pad = virtual_pads.VirtualPad(sdl)
        self.addCleanup(pad.unplug)
        if pygame.joystick.get_count() != 1:
            self.skipTest("another game controller is connected to this machine")
        with sockets_on_free_local_ports() as printed:
            listing = fresh_import("listing_5_3")
        self.assertEqual(printed, [("localhost", 9000)])
        nodes = RolesInThreads(listing.components, ["receiver", "input_device"])
        out = io.StringIO()
        with contextlib.redirect_stdout(out), self.assertLogs("snr.receiver", "INFO") as logs:
            nodes.start()
            pressed = False

            def a_arrived() -> bool:
                # A.8 stores only on controller events, and a page stored before the
                # link is up is not sent (pages go live): press and release A until
                # the receiver has the input with A down.
                nonlocal pressed
                data = nodes.data("receiver", "controller_data")
                if data is not None and data.get("A") == 1:
                    return True
                pressed = not pressed
                pad.set_button(2, pressed)  # A on a Steam controller (listing A.11)
                time.sleep(0.02)
                return False

            try:
                arrived = nodes.wait_for(a_arrived)
            finally:
                # A.8's halt() calls pygame.quit(), which would free the pad under
                # its thread: let go of the test's handle and stop the loop first.
                sdl.SDL_JoystickClose(pad.handle)
                pad.handle = None
                if "input_device" in nodes.nodes:
                    loop = nodes.nodes["input_device"].components["controller_loop"]
                    assert isinstance(loop, snr.ThreadLoop)  # A.9 builds a ThreadLoop
                    loop.set_terminate_flag("the test is done")
                    loop.join(2.0)
                nodes.stop()
        self.assertTrue(arrived, f"no input with A down reached the receiver: {nodes.errors}")
        self.assertEqual(nodes.data("receiver", "controller_data")["A"], 1)
        # A.7 got the input: as printed it has no previous input to compare with.
        self.assertIn("No previous input data", "\n".join(logs.output))
        self.assertIn("Using joystick: Virtual Controller", out.getvalue())
        self.assertIn("Loop terminated", out.getvalue())


class TestUrovListing(unittest.TestCase):
    def test_5_1_with_the_urov_example_shows_telemetry(self) -> None:
        capture_test_logs(self)  # the listing's DEBUG nodes log INFO lines
        with sockets_on_free_local_ports() as printed:
            listing = fresh_import("listing_5_1", UROV_EXAMPLE)
        self.assertEqual(printed, [("192.168.1.10", 9000), ("192.168.1.11", 9001)])
        nodes = RolesInThreads(listing.components, ["urov", "topside"])
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            nodes.start()
            try:
                shown = nodes.wait_for(lambda: "depth" in out.getvalue())
            finally:
                nodes.stop()
        self.assertTrue(shown, f"no telemetry shown: {out.getvalue()!r} {nodes.errors}")
        # The topside display's line, from the urov node's sensors over TCP.
        self.assertRegex(out.getvalue(), r"t=\s*[\d.]+ s \| depth\s+[\d.]+ m \| heading")
        self.assertIsInstance(nodes.data("topside", "sensor_data"), dict)


class TestPseudoCodeListings(unittest.TestCase):
    """Listings 6.1-6.4 are pseudo code: check the methods they name exist as named."""

    SIGNATURE = re.compile(r"^(\w+)\((.*?)\)\s*->\s*(.+?):?$")

    @staticmethod
    def normal(annotation: str) -> str:
        return re.sub(r"\s+", "", annotation).replace("Tuple[", "tuple[")

    def test_6_1_to_6_4_name_the_methods_of_node(self) -> None:
        checked = 0
        for number in ["6.1", "6.2", "6.3", "6.4"]:
            printed = fresh_import(CATALOG[number][:-3]).PRINTED
            # A line starting with a space continues the one before (6.2, handle_task).
            joined = re.sub(r"\n\s+", " ", printed.strip())
            for line in joined.splitlines():
                match = self.SIGNATURE.match(line.strip())
                assert match is not None, f"listing {number}: cannot read {line!r}"
                name, params, returns = match.groups()
                wanted = [tuple(p.split(":")) for p in params.split(",") if p.strip()]
                for cls in [AbstractNode, Node]:
                    with self.subTest(listing=number, method=f"{cls.__name__}.{name}"):
                        signature = inspect.signature(getattr(cls, name))
                        got = list(signature.parameters.values())[1:]  # after self
                        self.assertEqual(
                            [(p.name, self.normal(str(p.annotation))) for p in got],
                            [(n.strip(), self.normal(t)) for n, t in wanted],
                        )
                        self.assertEqual(
                            self.normal(str(signature.return_annotation)), self.normal(returns)
                        )
                checked += 1
        self.assertEqual(checked, 14)

    def test_6_3_names_are_aliases_of_the_store_task_builders(self) -> None:
        node = Node("robot", snr.Config({"robot": [snr.TimeoutLoopFactory(seconds=1)]}))
        page = node.page("depth", 2.5)
        self.assertEqual(node.task_store_page(page), node.store_page_task(page))
        by_thesis, by_snr = node.task_store_data("depth", 2.5), node.store_data_task("depth", 2.5)
        self.assertEqual((by_thesis.type, by_thesis.name), (by_snr.type, by_snr.name))
        self.assertEqual(by_thesis.val_list[0].data, 2.5)


if __name__ == "__main__":
    unittest.main()
