"""The thread-safe task queue: FIFO, urgent lane, waking a sleeping node."""

import threading
import unittest
from typing import List, Optional

from snr import Task, tasks
from snr.core import TaskQueue
from snr.prelude import HandlerError


class TestTaskQueue(unittest.TestCase):
    def test_fifo(self) -> None:
        queue = TaskQueue()
        queue.schedule([tasks.event(str(i)) for i in range(5)])
        queue.schedule(tasks.event("5"))
        names = [task.name if task else None for task in [queue.get(0) for _ in range(6)]]
        self.assertEqual(names, ["0", "1", "2", "3", "4", "5"])
        self.assertIsNone(queue.get(0))

    def test_terminate_jumps_ahead_and_urgent_stays_fifo(self) -> None:
        queue = TaskQueue()
        queue.schedule([tasks.event("a"), tasks.terminate("first"), tasks.terminate("second")])
        order = [queue.pop() for _ in range(3)]
        self.assertEqual([t.name for t in order if t], ["first", "second", "a"])

    def test_put_queues_one_task_and_wakes_a_sleeping_consumer(self) -> None:
        queue = TaskQueue()
        got: List[Optional[Task]] = []
        consumer = threading.Thread(target=lambda: got.append(queue.get(5.0)))
        consumer.start()
        queue.put(tasks.event("hello"))  # what a loop's store_data uses
        consumer.join(5.0)
        self.assertFalse(consumer.is_alive())
        self.assertEqual([task.name if task else None for task in got], ["hello"])
        queue.put(tasks.event("a"))
        queue.put(tasks.terminate("urgent"))
        self.assertEqual([t.name for t in (queue.pop(), queue.pop()) if t], ["urgent", "a"])

    def test_none_is_nothing(self) -> None:
        queue = TaskQueue()
        queue.schedule(None)
        self.assertEqual(len(queue), 0)

    def test_rejects_non_tasks_with_advice(self) -> None:
        queue = TaskQueue()
        with self.assertRaises(HandlerError) as ctx:
            queue.schedule([tasks.event("ok"), "oops"])  # type: ignore[list-item]
        self.assertIn("'oops'", str(ctx.exception))
        self.assertIn("tasks.event", str(ctx.exception))
        with self.assertRaises(HandlerError):
            queue.schedule(42)  # type: ignore[arg-type]

    def test_wait_wakes_when_another_thread_schedules(self) -> None:
        queue = TaskQueue()
        got: List[Optional[Task]] = []
        consumer = threading.Thread(target=lambda: got.append(queue.get(5.0)))
        consumer.start()
        queue.schedule(tasks.event("hello"))
        consumer.join(5.0)
        self.assertFalse(consumer.is_alive())
        self.assertEqual([task.name if task else None for task in got], ["hello"])

    def test_many_producers_lose_nothing(self) -> None:
        queue = TaskQueue()

        def produce(prefix: str) -> None:
            for i in range(2000):
                queue.schedule(tasks.event(f"{prefix}{i}"))

        threads = [threading.Thread(target=produce, args=(p,)) for p in "abcd"]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
        names = []
        while (task := queue.pop()) is not None:
            names.append(task.name)
        self.assertEqual(len(names), 8000)
        for p in "abcd":
            mine = [int(n[1:]) for n in names if n[0] == p]
            self.assertEqual(mine, list(range(2000)))  # each producer's order kept


if __name__ == "__main__":
    unittest.main()
