"""The data-flow graph of a config: ``python -m snr graph`` (no node runs)."""

from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
import unittest
from typing import List, Optional

import snr
from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    SocketsPair,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    ThreadLoop,
)
from snr.__main__ import main as snr_main
from snr.extras.graph import (
    UNKNOWN_PEER,
    SystemGraph,
    config_from_script,
    graph_of_config,
    render,
    to_dot,
    to_mermaid,
    to_text,
)
from snr.prelude import ConfigError

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UROV_MAIN = os.path.join(ROOT, "examples", "urov", "main.py")
UROV_GRAPH_DOC = os.path.join(ROOT, "docs", "graph.md")


class Sensor(ThreadLoop):
    """Stores ``depth`` (a literal key) and whatever ``self.extra`` names."""

    def __init__(self, factory: SensorFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "sensor")
        self.extra = factory.extra

    def loop(self) -> None:
        self.store_data("depth", 1.0)
        if self.extra is not None:
            self.store_data(self.extra, 2.0)


class SensorFactory(LoopFactory):
    def __init__(self, extra: Optional[str] = None) -> None:
        super().__init__()
        self.extra = extra

    def get(self, parent: AbstractNode) -> Sensor:
        return Sensor(self, parent)


class Listener(Endpoint):
    """Handles ``key``; reads ``heading`` with get_data."""

    def __init__(self, factory: ListenerFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.task_handlers = {(TaskType.store_page, factory.key): self.on_page}

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        return self.store_data_task("alarm", self.get_data("heading"))


class ListenerFactory(EndpointFactory):
    def __init__(self, key: str, name: str = "listener") -> None:
        super().__init__()
        self.key, self.name = key, name

    def get(self, parent: AbstractNode) -> Listener:
        return Listener(self, parent)


class Computed(Endpoint):
    """Stores keys made while running: the graph cannot see them unless declared."""

    def __init__(self, factory: ComputedFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "computed")
        if factory.declared is not None:
            self.produces = factory.declared

    def store_all(self) -> None:
        for side in ("left", "right"):
            self.store_data(f"motor_{side}", 0)


class ComputedFactory(EndpointFactory):
    def __init__(self, declared: Optional[List[str]] = None) -> None:
        super().__init__()
        self.declared = declared

    def get(self, parent: AbstractNode) -> Computed:
        return Computed(self, parent)


def urov_graph() -> SystemGraph:
    return graph_of_config(config_from_script(UROV_MAIN))


class UrovGraphTest(unittest.TestCase):
    graph: SystemGraph

    @classmethod
    def setUpClass(cls) -> None:
        cls.graph = urov_graph()

    def test_nodes_components_and_keys(self) -> None:
        self.assertEqual([n.role for n in self.graph.nodes], ["topside", "urov"])
        topside, urov = self.graph.nodes
        self.assertIn("input_processor", [c.name for c in topside.components])
        self.assertNotIn("node_core", [c.name for c in urov.components])
        controls = urov.component("controls_processor")
        assert controls is not None
        self.assertEqual(controls.handles, ["controller_input"])
        self.assertEqual(controls.produces, ["motor_speed"])
        telemetry = urov.component("telemetry")
        assert telemetry is not None
        self.assertEqual(telemetry.produces, ["sensor_data"])  # store_data_task(self.output)
        self.assertEqual(telemetry.reads, ["heading", "motor_speed", "speed"])
        reader = urov.component("sensor_reader")
        assert reader is not None
        self.assertEqual(reader.produces, ["depth_raw", "heading", "speed"])
        self.assertEqual(reader.unresolved, [])  # self.output is None: nothing stored there
        avg = urov.component("moving_avg_filter")
        assert avg is not None
        self.assertEqual((avg.handles, avg.produces), (["depth_raw"], ["depth"]))

    def test_tcp_links_carry_the_keys(self) -> None:
        links = {
            (link.a_role, link.a_component, link.b_role, link.b_component): link
            for link in self.graph.links
        }
        up = links[("topside", "sockets_client_9000", "urov", "sockets_server_9000")]
        down = links[("urov", "sockets_client_9001", "topside", "sockets_server_9001")]
        self.assertEqual(
            (up.label, up.a_to_b, up.b_to_a), ("TCP 127.0.0.1:9000", ["controller_input"], [])
        )
        self.assertEqual(down.a_to_b, ["sensor_data"])
        self.assertEqual(self.graph.arriving("urov"), {"controller_input": ["sockets_server_9000"]})

    def test_the_urov_has_no_orphaned_keys(self) -> None:
        self.assertEqual(self.graph.problems(), [])
        self.assertIn("No key is read without a producer", to_text(self.graph))

    def test_mermaid_and_dot_draw_every_key_and_link(self) -> None:
        for text in (to_mermaid(self.graph), to_dot(self.graph)):
            for word in (
                "topside",
                "urov",
                "controller_input",
                "motor_speed",
                "sensor_data",
                "depth",
                "TCP 127.0.0.1:9000",
                "TCP 127.0.0.1:9001",
            ):
                self.assertIn(word, text)
        mermaid = to_mermaid(self.graph)
        self.assertTrue(mermaid.startswith("flowchart LR"))
        self.assertRegex(mermaid, r'n\d+ ==>\|"controller_input \[TCP 127.0.0.1:9000\]"\| n\d+')
        dot = to_dot(self.graph)
        self.assertTrue(dot.startswith("digraph snr {") and dot.endswith("}"))
        self.assertEqual(dot.count("subgraph cluster_"), 2)

    def test_the_docs_show_the_graph_the_tool_draws_now(self) -> None:
        with open(UROV_GRAPH_DOC, encoding="utf-8") as doc:
            text = doc.read()
        blocks = re.findall(r"```mermaid\n(.*?)\n```", text, re.S)
        self.assertEqual(
            blocks[:1],
            [to_mermaid(self.graph)],
            "docs/graph.md is out of date: regenerate its block with "
            "`python -m snr graph examples/urov/main.py`",
        )

    def test_one_role_draws_its_peers_as_plain_nodes(self) -> None:
        graph = graph_of_config(config_from_script(UROV_MAIN), ["urov"])
        self.assertEqual([n.role for n in graph.nodes], ["urov"])
        mermaid = to_mermaid(graph)
        self.assertIn('["node topside"]', mermaid)
        self.assertNotIn("input_processor", mermaid)


class OrphanedKeysTest(unittest.TestCase):
    def test_a_misspelt_key_is_flagged_both_ways(self) -> None:
        # The sensor stores "depth"; the listener waits for "depht".
        config = Config({"robot": [SensorFactory(), ListenerFactory("depht")]})
        graph = graph_of_config(config)
        found = {(p.kind, p.key): p.components for p in graph.problems()}
        self.assertEqual(found[("never_produced", "depht")], ("listener",))
        self.assertEqual(found[("never_read", "depth")], ("sensor",))
        self.assertIn(("never_produced", "heading"), found)  # get_data("heading")
        self.assertIn(("never_read", "alarm"), found)  # store_data_task("alarm", ...)
        text = to_text(graph)
        self.assertIn("'depht' is read by listener, but nothing on the node stores it", text)
        self.assertIn("'depth' is stored by sensor, but nothing on the node reads it", text)
        mermaid = to_mermaid(graph)
        self.assertIn('["(!) depht<br/>never produced"]', mermaid)
        self.assertIn('["(!) depth<br/>never read"]', mermaid)
        self.assertRegex(mermaid, r"class n\d+(,n\d+)* problem")
        self.assertIn("color=red", to_dot(graph))

    def test_a_key_crossing_a_link_is_produced_on_the_far_side(self) -> None:
        pair = SocketsPair(("127.0.0.1", 9999))
        config = Config(
            {
                "a": [SensorFactory(extra="heading"), pair.client(["depth", "heading"])],
                "b": [pair.server(), ListenerFactory("depth")],
            }
        )
        graph = graph_of_config(config)
        problems = {(p.role, p.kind, p.key) for p in graph.problems()}
        self.assertEqual(problems, {("b", "never_read", "alarm")})

    def test_a_link_to_an_unknown_peer_may_bring_any_key(self) -> None:
        pair = SocketsPair(("127.0.0.1", 9999))
        graph = graph_of_config(Config({"b": [pair.server(), ListenerFactory("depth")]}))
        self.assertEqual(graph.links[0].b_role, UNKNOWN_PEER)
        self.assertNotIn("never_produced", [p.kind for p in graph.problems()])
        self.assertIn('["unknown peer"]', to_mermaid(graph))

    def test_keys_computed_at_run_time_are_noted_until_declared(self) -> None:
        graph = graph_of_config(Config({"robot": [ComputedFactory()]}))
        computed = graph.nodes[0].components[0]
        self.assertEqual(computed.produces, [])
        self.assertEqual(computed.unresolved, ["Computed.store_all: store_data(f'motor_{side}')"])
        self.assertIn("name it in `produces`", to_text(graph))
        declared = graph_of_config(Config({"robot": [ComputedFactory(["motor_left"])]}))
        component = declared.nodes[0].components[0]
        self.assertEqual((component.produces, component.unresolved), (["motor_left"], []))

    def test_unknown_format_is_refused_with_the_choices(self) -> None:
        with self.assertRaisesRegex(ValueError, "mermaid, dot, text"):
            render(SystemGraph(), "png")


class ScriptTest(unittest.TestCase):
    def script(self, body: str) -> str:
        folder = tempfile.mkdtemp()
        self.addCleanup(shutil.rmtree, folder, True)
        path = os.path.join(folder, "main.py")
        with open(path, "w", encoding="utf-8") as file:
            file.write(textwrap.dedent(body))
        return path

    def test_a_runner_hands_over_its_config_instead_of_running(self) -> None:
        path = self.script("""
            import sys
            import snr
            config = snr.Config({"robot": [snr.TimeoutLoopFactory(seconds=60)]})
            if __name__ == "__main__":
                snr.CliRunner(config, sys.argv).run()
                raise SystemExit("the node ran")
        """)
        config = config_from_script(path)
        self.assertEqual(config.roles(), ["robot"])

    def test_a_drawn_runner_is_not_said_to_have_never_run(self) -> None:
        # At exit SNR names a runner a program built and never ran (checks/runner_checks.py);
        # a runner the graph tool stopped, or read from a name, did run as far as it matters.
        for body in [
            "import sys, snr\nsnr.CliRunner({'robot': [snr.TimeoutLoopFactory(seconds=60)]},"
            " sys.argv).run()\n",
            "import sys, snr\nrunner = snr.CliRunner({'robot': [snr.TimeoutLoopFactory()]},"
            " sys.argv)\nconfig = runner.config\n",
        ]:
            with self.subTest(body=body):
                path = self.script(body)
                code = (
                    "import sys\nfrom snr.extras.graph.script import config_from_script\n"
                    "print(config_from_script(sys.argv[1]).roles())\n"
                )
                done = subprocess.run(
                    [sys.executable, "-c", code, path],
                    capture_output=True,
                    text=True,
                    timeout=30,
                    check=False,
                )
                self.assertEqual((done.returncode, done.stdout), (0, "['robot']\n"), done.stderr)
                self.assertNotIn("never ran", done.stderr)

    def test_keys_are_found_in_the_classes_of_the_script_itself(self) -> None:
        # The script runs as __main__, which is not the module Python would search.
        path = self.script("""
            import snr

            class Sensor(snr.ThreadLoop):
                def __init__(self, factory, parent):
                    super().__init__(factory, parent, "sensor")

                def loop(self):
                    self.store_data("depth", 1.0)

            class SensorFactory(snr.LoopFactory):
                def get(self, parent):
                    return Sensor(self, parent)

            if __name__ == "__main__":
                snr.CliRunner({"robot": [SensorFactory()]}).run()
        """)
        graph = graph_of_config(config_from_script(path))
        self.assertEqual(graph.nodes[0].components[0].produces, ["depth"])

    def test_a_module_level_config_is_found_without_a_runner(self) -> None:
        path = self.script("""
            import snr
            components = {"robot": [snr.TimeoutLoopFactory(seconds=60)]}
        """)
        self.assertEqual(config_from_script(path).roles(), ["robot"])

    def test_a_file_without_a_system_says_what_to_do(self) -> None:
        with self.assertRaisesRegex(ConfigError, "module-level `config`"):
            config_from_script(self.script("x = 1\n"))
        with self.assertRaisesRegex(ConfigError, "exited .* before it started any SNR node"):
            config_from_script(self.script("raise SystemExit(2)\n"))
        with self.assertRaisesRegex(ConfigError, "No such file"):
            config_from_script("no/such/main.py")

    def test_runners_are_restored_afterwards(self) -> None:
        run = snr.CliRunner.run
        config_from_script(UROV_MAIN)
        self.assertIs(snr.CliRunner.run, run)

    def test_command_line(self) -> None:
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = snr_main(["graph", UROV_MAIN, "--format", "text", "--role", "urov"])
            bad = snr_main(["graph", UROV_MAIN, "--role", "urv"])
            moved = snr_main(["graph", UROV_MAIN, "--format", "dot", "--", "--port", "9100"])
        self.assertEqual((code, bad, moved), (0, 1, 0))
        self.assertIn("TCP 127.0.0.1:9100", out.getvalue())  # the arguments after -- reach FILE
        self.assertIn("Node 'urov' (7 components):", out.getvalue())
        self.assertNotIn("Node 'topside'", out.getvalue())
        self.assertIn("Unknown role 'urv'", err.getvalue())
        self.assertIn("Did you mean 'urov'?", err.getvalue())


if __name__ == "__main__":
    unittest.main()
