"""`ControlProcessorFactory`: turn button changes into events (listings A.6, A.7).

Each time named controller data is stored (by `InputMappingFactory`, or
received from another node), the endpoint compares every watched button
with its previous value and schedules
``tasks.event("button_pressed", ["A"])`` or ``tasks.event("button_released", ["A"])``.
Other components handle those events, e.g. `PrinterEndpointFactory` prints
``(event, 'button_pressed'): ['A']`` (thesis figure 5.4).

Example::

    ControlProcessorFactory("controller_data")
    ControlProcessorFactory("controller_data", watch_buttons=["A", "B"])
"""

from __future__ import annotations

import sys
from typing import Any, Dict, List, Optional, Sequence

from snr.core import Endpoint, EndpointFactory, tasks
from snr.extras.controller.input_mapping import stored_dict
from snr.prelude import (
    AbstractNode,
    ComponentError,
    DataKey,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)

__all__ = [
    "BUTTON_PRESSED",
    "BUTTON_RELEASED",
    "STEAM_CONTROLLER_BUTTONS",
    "ControlProcessorEndpoint",
    "ControlProcessorFactory",
]

BUTTON_PRESSED = "button_pressed"
"""Name of the event scheduled when a watched button goes down."""

BUTTON_RELEASED = "button_released"
"""Name of the event scheduled when a watched button comes up."""

STEAM_CONTROLLER_BUTTONS: List[str] = [
    "d_pad_tap",
    "right_stick_press",
    "A",
    "B",
    "X",
    "Y",
    "left_shoulder",
    "right_shoulder",
    "left_trigger",
    "right_trigger",
    "left_stick_press",
    "left_paddle",
    "right_paddle",
]
"""The buttons watched by default: every button of `STEAM_CONTROLLER_MAPPING`."""


def _button_state(value: Any) -> Optional[bool]:
    """True for 1 (pressed), False for 0 (released), None for anything else."""
    if not isinstance(value, (bool, int, float)):
        return None
    if value == 1:
        return True
    if value == 0:
        return False
    return None


class ControlProcessorEndpoint(Endpoint):
    """Schedules ``button_pressed`` / ``button_released`` events for watched buttons.

    The previous input is kept on the factory, so a hot reload of this
    module does not forget which buttons are held. The first input only sets
    that baseline: a button already held when the program starts gives no
    event.

    Example::

        # {"A": 0, "B": 1} then {"A": 1, "B": 0} gives, in watch order:
        # tasks.event("button_pressed", ["A"]), tasks.event("button_released", ["B"])
    """

    def __init__(
        self,
        factory: ControlProcessorFactory,
        parent: AbstractNode,
        input_data: DataKey,
        watch_buttons: Sequence[str],
        previous_input: Dict[str, Any],
    ) -> None:
        super().__init__(factory, parent, factory.name)
        self.input_data = input_data
        self.watch_buttons = list(watch_buttons)
        self.previous_input = previous_input
        self.warned_no_buttons = False
        self.task_handlers = {(TaskType.store_page, input_data): self.process_input}

    def process_input(self, task: Task, key: TaskId) -> SomeTasks:
        """Compare the new input with the previous one; one event per change."""
        data = stored_dict(task)
        if data is None:
            self.warn(
                "Ignoring %s: expected a page whose data is a dict of buttons such as "
                "{'A': 1, 'B': 0}, as InputMappingFactory stores.",
                task,
            )
            return None
        self.check_watched_buttons_present(data)
        previous = dict(self.previous_input)
        # Update in place: the dict is shared with the factory (kept over reloads).
        self.previous_input.clear()
        self.previous_input.update(data)
        if not previous:
            self.dbg("No previous input data; this input is the baseline")
            return None
        return self.button_events(previous, data)

    def button_events(self, previous: Dict[str, Any], data: Dict[str, Any]) -> List[Task]:
        """The events for every watched button that changed, in watch order."""
        events: List[Task] = []
        for button in self.watch_buttons:
            before = _button_state(previous.get(button))
            now = _button_state(data.get(button))
            if before is None or now is None or before == now:
                continue
            events.append(tasks.event(BUTTON_PRESSED if now else BUTTON_RELEASED, [button]))
        return events

    def check_watched_buttons_present(self, data: Dict[str, Any]) -> None:
        """Warn once if the input has none of the watched buttons (names differ)."""
        if self.warned_no_buttons or any(b in data for b in self.watch_buttons):
            return
        self.warned_no_buttons = True
        self.warn(
            "Endpoint %r watches %s, but the data under %r has none of them (it has: %s). "
            "Pass ControlProcessorFactory(watch_buttons=[...]) with the names your "
            "input mapping gives.",
            self.name,
            ", ".join(self.watch_buttons),
            self.input_data,
            ", ".join(sorted(map(str, data))) or "nothing",
        )


class ControlProcessorFactory(EndpointFactory):
    """Builds a `ControlProcessorEndpoint` (thesis listing A.6).

    Args:
        input_data: the key the named controller data is stored under.
        watch_buttons: the buttons to report; default `STEAM_CONTROLLER_BUTTONS`.
        name: the endpoint's name (default ``"input_processor_endpoint"``).

    Attributes:
        previous_input: the last input seen; kept here so it survives a reload.

    Example::

        ControlProcessorFactory("controller_data")
    """

    def __init__(
        self,
        input_data: DataKey = "controller_input",
        watch_buttons: Optional[Sequence[str]] = None,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        buttons = STEAM_CONTROLLER_BUTTONS if watch_buttons is None else watch_buttons
        if isinstance(buttons, str) or not all(isinstance(b, str) for b in buttons):
            raise ComponentError(
                f"ControlProcessorFactory(watch_buttons={watch_buttons!r}): give a list "
                'of button names, e.g. watch_buttons=["A", "B"].'
            )
        self.input_data = input_data
        self.watch_buttons = list(buttons)
        self.name = name or "input_processor_endpoint"
        self.previous_input: Dict[str, Any] = {}

    def get(self, parent: AbstractNode) -> ControlProcessorEndpoint:
        return ControlProcessorEndpoint(
            self, parent, self.input_data, self.watch_buttons, self.previous_input
        )
