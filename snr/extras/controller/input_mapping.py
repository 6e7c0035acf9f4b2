"""`InputMappingFactory`: give a controller's numbered controls names (A.10, A.11).

`ControllerLoop` stores ``{"button_2": 1, "axis_0": 0.5, ...}``; this
endpoint stores ``{"A": 1, "left_stick_X": 0.5, ...}`` under another key.
Which number is which button depends on the controller model, so the table
is yours to pass; the default is the thesis's Steam controller.

Example::

    InputMappingFactory("raw_controller_input", "controller_input")
    InputMappingFactory("raw_controller_input", "controller_input",
                        mapping={"button_0": "A", "button_1": "B", "axis_0": "steer"})
"""

from __future__ import annotations

import sys
from typing import Any, Dict, Mapping, Optional

from snr.core import Endpoint, EndpointFactory
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
    "STEAM_CONTROLLER_MAPPING",
    "InputMappingEndpoint",
    "InputMappingFactory",
    "stored_dict",
]

STEAM_CONTROLLER_MAPPING: Dict[str, str] = {
    "button_0": "d_pad_tap",
    "button_1": "right_stick_press",
    "button_2": "A",
    "button_3": "B",
    "button_4": "X",
    "button_5": "Y",
    "button_6": "left_shoulder",
    "button_7": "right_shoulder",
    "button_8": "left_trigger",
    "button_9": "right_trigger",
    "button_13": "left_stick_press",
    "button_15": "left_paddle",
    "button_16": "right_paddle",
    "axis_0": "left_stick_X",
    "axis_1": "left_stick_Y",
    "axis_2": "right_stick_X",
    "axis_3": "right_stick_Y",
}
"""Raw control → name for a Steam controller under pygame (thesis listing A.11).

Copy and extend it for your pad, e.g.
``{**STEAM_CONTROLLER_MAPPING, "dhat_0": "d_pad"}``.
"""


def stored_dict(task: Task) -> Optional[Dict[str, Any]]:
    """The dict a store_page task carries, or None if it carries anything else.

    Example::

        stored_dict(tasks.store_data("controller_input", {"A": 1}))   # {'A': 1}
    """
    page = task.page()
    if page is not None and isinstance(page.data, dict):
        return page.data
    return None


class InputMappingEndpoint(Endpoint):
    """Renames the controls of each raw controller page; drops unmapped ones.

    Example: with the default table, a page ``{"button_2": 1, "button_10": 0}``
    under ``raw_controller_input`` becomes ``{"A": 1}`` under
    ``controller_input``.
    """

    def __init__(
        self,
        factory: InputMappingFactory,
        parent: AbstractNode,
        input_data: DataKey,
        output_data: DataKey,
        mapping: Mapping[str, str],
    ) -> None:
        super().__init__(factory, parent, factory.name)
        self.input_data = input_data
        self.output_data = output_data
        self.mapping = dict(mapping)
        self.task_handlers = {(TaskType.store_page, input_data): self.map_raw_input}

    def map_raw_input(self, task: Task, key: TaskId) -> SomeTasks:
        """Store the named version of the raw controller dict."""
        raw = stored_dict(task)
        if raw is None:
            self.warn(
                "Ignoring %s: expected a page whose data is a dict of controls such as "
                "{'button_2': 1}, as ControllerLoop stores.",
                task,
            )
            return None
        data: Dict[str, Any] = {
            self.mapping[control]: value
            for control, value in raw.items()
            if control in self.mapping
        }
        return self.store_data_task(self.output_data, data)


class InputMappingFactory(EndpointFactory):
    """Builds an `InputMappingEndpoint` (thesis listing A.10).

    Args:
        input_data: the key the raw controller state is stored under.
        output_data: the key to store the named state under.
        mapping: raw control (``"button_2"``) → name (``"A"``); default
            `STEAM_CONTROLLER_MAPPING`.
        name: the endpoint's name (default ``"controller_input_map_endpoint"``).

    Example::

        InputMappingFactory("raw_controller_data", "controller_data")
    """

    def __init__(
        self,
        input_data: DataKey = "raw_controller_input",
        output_data: DataKey = "controller_input",
        mapping: Optional[Mapping[str, str]] = None,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        self.input_data = input_data
        self.output_data = output_data
        self.mapping = _checked_mapping(STEAM_CONTROLLER_MAPPING if mapping is None else mapping)
        self.name = name or "controller_input_map_endpoint"

    def get(self, parent: AbstractNode) -> InputMappingEndpoint:
        return InputMappingEndpoint(self, parent, self.input_data, self.output_data, self.mapping)


def _checked_mapping(mapping: Mapping[str, str]) -> Dict[str, str]:
    if not isinstance(mapping, Mapping):
        raise ComponentError(
            f"InputMappingFactory(mapping={mapping!r}): the mapping must be a dict from "
            'raw control to name, e.g. {"button_2": "A", "axis_0": "left_stick_X"}.'
        )
    named_by: Dict[str, str] = {}
    for control, name in mapping.items():
        if not isinstance(control, str) or not isinstance(name, str):
            raise ComponentError(
                f"InputMappingFactory mapping entry {control!r}: {name!r} must map a "
                'control name to a button name, both strings, e.g. "button_2": "A".'
            )
        if name in named_by:
            raise ComponentError(
                f"InputMappingFactory mapping gives the name {name!r} to both "
                f"{named_by[name]!r} and {control!r}; one would hide the other. "
                "Give each control its own name."
            )
        named_by[name] = control
    return dict(mapping)
