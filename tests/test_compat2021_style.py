"""Tests in the style of the 2021 release: they must run unchanged on today's SNR.

Written the way students and teachers wrote tests against the original
course's 2021 release: ``from snr import *``, ``Expector[str]`` and
``MPExpector`` made with the test case, ``temp_file()`` as a context manager,
``MovingAvgEndpointFactory`` and a bare ``TimeoutLoopFactory()`` for a start
and stop check, with nodes held to ``pytest.mark.timeout(0.2)``. Run with
``python -m unittest`` or pytest.
"""

# ruff: noqa: F403, F405  (`from snr import *`, as 2021 code wrote it)
import multiprocessing as mp
import unittest
from typing import Any, Optional

try:
    import pytest
except ImportError:  # a plain install: unittest runs these the same, marks are pytest's
    from tests.optional import (  # type: ignore[no-redef]  # a stand-in for its marks
        pytest_marks_only as pytest,
    )

from snr import *

BEEP: TaskName = "beep"


class BeepEndpoint(Endpoint):
    """A student's endpoint that reports to an expector, as 2021 code did."""

    def __init__(
        self,
        factory: EndpointFactory,
        parent: AbstractNode,
        expector: Optional[ExpectorProtocol],
    ) -> None:
        super().__init__(factory, parent, "beep_endpoint")
        self.expector = expector
        self.task_handlers = {(TaskType.event, BEEP): self.on_beep}

    def on_beep(self, task: Task, key: TaskId) -> SomeTasks:
        if self.expector:
            self.expector.call("beeped")
        return tasks.terminate("beeped")


class BeepEndpointFactory(EndpointFactory):
    def __init__(self, expector: Optional[ExpectorProtocol] = None) -> None:
        super().__init__()
        self.expector = expector

    def get(self, parent: AbstractNode) -> BeepEndpoint:
        return BeepEndpoint(self, parent, self.expector)


class BeepLoop(ThreadLoop):
    def loop(self) -> None:
        self.schedule(tasks.event(BEEP))
        self.set_terminate_flag("beeped once")


class BeepLoopFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> BeepLoop:
        return BeepLoop(self, parent, "beep_loop")


def beep_from_a_child(expector: Any) -> None:
    expector.call("child")


class TestStartAndStop(SNRTestCase):
    @pytest.mark.timeout(0.2)
    def test_timeout_loop_with_no_time(self) -> None:
        self.run_test_node([TimeoutLoopFactory()])

    @pytest.mark.timeout(0.2)
    def test_endpoint_starts_and_stops(self) -> None:
        self.run_test_node([BeepEndpointFactory(), TimeoutLoopFactory()])


class TestExpectors(SNRTestCase):
    @pytest.mark.timeout(0.2)
    def test_loop_and_expector(self) -> None:
        with Expector[str]({"beeped": 1}, self) as expector:
            self.run_test_node([BeepLoopFactory(), BeepEndpointFactory(expector)])

    def test_unmet_expectation_fails_naming_key_and_counts(self) -> None:
        expector = Expector[str]({"beeped": 2}, self)
        expector.call("beeped")
        with self.assertRaises(AssertionError) as ctx:
            expector.assert_satisfied()
        self.assertIn("'beeped': expected 2, saw 1", str(ctx.exception))

    @pytest.mark.timeout(0.2)
    def test_task_expector(self) -> None:
        expectations: TaskExpectations = {(TaskType.event, BEEP): 1}
        with TaskExpector(expectations, self) as expector:
            self.run_test_node(
                [
                    BeepLoopFactory(),
                    BeepEndpointFactory(),
                    ExpectorEndpointFactory(expector),
                ]
            )

    def test_mp_expector_counts_in_child_processes(self) -> None:
        with MPExpector[str]({"child": 2}, self) as expector:
            children = [mp.Process(target=beep_from_a_child, args=(expector,)) for _ in range(2)]
            for child in children:
                child.start()
            for child in children:
                child.join(10)
                self.assertEqual(child.exitcode, 0)


class TestFilter(SNRTestCase):
    @pytest.mark.timeout(0.2)
    def test_moving_avg_endpoint_factory(self) -> None:
        out: TaskId = (TaskType.store_page, "out")
        with self.expector({out: 4}) as expector:
            node = self.run_test_node(
                [
                    ListReplayerFactory([0, 1, 2, 4], "in"),
                    MovingAvgEndpointFactory("in", "out", 2),
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )
        self.assertEqual(node.get_data("out"), 3.0)


class TestTempFile(SNRTestCase):
    def test_temp_file_as_context_manager(self) -> None:
        with self.temp_file() as temp:
            with temp.open() as f:
                f.write("hello")
            temp.assertExists()
            with open(temp.path) as f:
                self.assertEqual(f.read(), "hello")

    @pytest.mark.timeout(0.2)
    def test_recorder_writes_a_named_temp_file(self) -> None:
        with self.temp_file("recording.jsonl", overwrite=True) as temp:
            self.run_test_node(
                [
                    RecorderEndpointFactory(temp.path, ["in"]),
                    ListReplayerFactory([1, 2], "in"),
                    TimeoutLoopFactory(ms=20),
                ]
            )
            temp.assertExists()


if __name__ == "__main__":
    unittest.main()


class TestPipeLoop(SNRTestCase):
    @pytest.mark.timeout(5)
    def test_a_page_serialized_into_the_pipe_is_stored_and_the_end_closes(self) -> None:
        parent_conn, child_conn = mp.Pipe()
        page = Page("pipe_data", {"depth": 2.5}, "old_code", 1234.5)
        parent_conn.send_bytes(page.serialize().encode())
        expector = self.expector({(TaskType.store_page, "pipe_data"): 1})
        with expector:
            node = self.run_test_node(
                [
                    PipeLoopFactory(child_conn),  # no keys: forwards nothing, stores what comes
                    ExpectorEndpointFactory(expector, exit_when_satisfied=True),
                ]
            )
        stored = node.get_page("pipe_data")
        self.assertPage(stored, "pipe_data", {"depth": 2.5}, origin="old_code")
        assert stored is not None
        self.assertEqual(stored.created_at_s, 1234.5)
        # The node has stopped: its end of the pipe is closed (after its hello).
        received = []
        with self.assertRaises(EOFError):
            for _ in range(10):
                if not parent_conn.poll(2.0):
                    break
                received.append(parent_conn.recv_bytes())
        self.assertLessEqual(len(received), 1)  # at most SNR's hello frame
