"""`ListReplayerFactory`: store the values of a list, one by one, under a key."""

from __future__ import annotations

from typing import Any, Optional, Sequence

from snr.core import LoopFactory, ThreadLoop
from snr.core.checks.call_checks import wrong_call
from snr.prelude import AbstractNode, ConfigError, DataKey, Task, TaskType

__all__ = ["ListReplayerFactory", "ListReplayerLoop"]


class ListReplayerLoop(ThreadLoop):
    """Stores each value under ``key`` in order, then stops.

    The node runs on, unless the factory was made with ``exit_when_done=True``:
    then the node stops once every value has been handled.

    Example::

        ListReplayerFactory([0, 1, 2, 4], "input_data")
    """

    def __init__(self, factory: ListReplayerFactory, parent: AbstractNode) -> None:
        period_s = factory.period_s
        rate = 1.0 / period_s if period_s > 0 else 0.0
        super().__init__(factory, parent, factory.name, max_tick_rate_hz=rate)
        self.values = factory.values
        self.key = factory.key
        self.index = 0
        self.exit_when_done = factory.exit_when_done

    def loop(self) -> None:
        if self.index < len(self.values):
            self.store_data(self.key, self.values[self.index])
            self.index += 1
            return
        self.set_terminate_flag("replayed every value")
        if self.exit_when_done:
            # A terminate task of normal priority waits its turn behind the
            # values just stored, so every handler sees every value first.
            self.schedule(Task(TaskType.terminate, f"{self.name} stored every value"))


class ListReplayerFactory(LoopFactory):
    """Builds a `ListReplayerLoop` (thesis listing A.3).

    Args:
        values: what to store, in order.
        key: the data key to store them under.
        period_s: seconds between values (0: as fast as possible).
        exit_when_done: stop the node once every value has been handled.

    Example::

        ListReplayerFactory([0.5, 0.7, 0.6], "depth_m", period_s=0.1)
        ListReplayerFactory(readings, "depth_m", exit_when_done=True)   # then stop
    """

    def __init__(
        self,
        values: Sequence[Any],
        key: DataKey,
        period_s: float = 0.0,
        name: Optional[str] = None,
        exit_when_done: bool = False,
    ) -> None:
        super().__init__()
        if not isinstance(key, str) or isinstance(values, str):
            why = (
                "the values and the key are swapped: the list of values comes first."
                if isinstance(values, str) and not isinstance(key, str)
                else f"the values must be a list and the key a str, not "
                f"{type(values).__name__} and {type(key).__name__}."
            )
            raise ConfigError(
                wrong_call("ListReplayerFactory", ListReplayerFactory, (values, key), why)
            )
        self.values = list(values)
        self.key = key
        self.period_s = period_s
        self.name = name or f"list_replayer_{key}"
        self.exit_when_done = exit_when_done

    def get(self, parent: AbstractNode) -> ListReplayerLoop:
        return ListReplayerLoop(self, parent)
