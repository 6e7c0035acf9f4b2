"""Thesis listing A.7: Example implementation of a control input processor endpoint.

Printed in Appendix A (line 1280 of the thesis text). Listing A.6 imports this
module as ``control_processor_endpoint``. SNR's own version is
``snr.ControlProcessorEndpoint`` (``snr/extras/controller/control_processor.py``).

Repaired PDF artefacts: indentation; line 30, broken before its ``)``; the
page break after line 44, where lines 44-45 were numbered twice.
Deviations: none. As printed it compares each input with the data stored under
``input_data + "_prev"``, which nothing stores, so it logs "No previous input
data" and gives no button events (docs/deviations-controller.md): in listing
5.3 the receiver gets the controller's input but prints nothing.
"""
from typing import Any, List, Dict

from snr import *


class ControlProcessorEndpoint(Endpoint):

    input_data: DataKey
    watch_buttons: List[str] = [
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

    def __init__(self,
                 factory: EndpointFactory,
                 parent: AbstractNode,
                 input_data: DataKey,
                 ) -> None:
        super().__init__(factory, parent, "input_processor_endpoint"
                         )

        self.input_data = input_data
        self.task_handlers = {
            (TaskType.store_page, input_data): self.process_input
        }

    def process_input(self, task: Task, id: TaskId) -> SomeTasks:
        page = task.val_list[0]
        assert isinstance(page, Page)
        prev_data: Dict[str, Any] = self.get_data(  # type: ignore
            self.input_data+"_prev")
        if prev_data is None:
            self.info("No previous input data")
            return None
        data: Dict[str, Any] = page.data
        assert isinstance(prev_data, dict) and isinstance(data, dict)
        events: List[Task] = []
        for key, value in data.items():
            prev = prev_data[key]
            if value == 0 and prev == 1:
                events.append(tasks.event("button_released", [key]))
            if value == 1 and prev == 0:
                events.append(tasks.event("button_pressed", [key]))
        return events

    def begin(self) -> None:
        pass

    def halt(self) -> None:
        pass

    def terminate(self) -> None:
        pass
