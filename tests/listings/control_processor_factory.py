"""Thesis listing A.6: Example implementation of a factory for a control input processor endpoint.

Printed in Appendix A (line 1248 of the thesis text). Listing 5.3 imports this
module as ``control_processor_factory``; it imports listing A.7 as
``control_processor_endpoint``. SNR's own version is
``snr.ControlProcessorFactory`` (``snr/extras/controller/control_processor.py``).

Repaired PDF artefacts: indentation.
Deviations: none.
"""
from snr import *

import control_processor_endpoint


class ControlProcessorFactory(EndpointFactory):

    input_data: DataKey

    def __init__(self,
                 input_data: DataKey = "controller_input",
                 ) -> None:
        super().__init__(control_processor_endpoint)
        self.input_data = input_data

    def get(self, parent: AbstractNode) -> Endpoint:
        return control_processor_endpoint.ControlProcessorEndpoint(
            self,
            parent,
            self.input_data)
