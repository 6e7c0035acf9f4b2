"""Thesis listing A.10: Example implementation of a factory for the input mapping endpoint.

Printed in Appendix A (line 1499 of the thesis text). Listing 5.3 imports this
module as ``input_mapping_factory``; it imports listing A.11 as
``input_mapping_endpoint``. SNR's own version is ``snr.InputMappingFactory``.

Repaired PDF artefacts: indentation, and lines 20-28, where the PDF split
``self.input_data`` and ``self.output_data`` over lines of their own.
Deviations: none.
"""
from snr import *

import input_mapping_endpoint


class InputMappingFactory(EndpointFactory):

    input_data: DataKey
    output_data: DataKey

    def __init__(self,
                 input_data: DataKey = "raw_controller_input",
                 output_data: DataKey = "controller_input",
                 ) -> None:
        super().__init__(input_mapping_endpoint)
        self.input_data = input_data
        self.output_data = output_data

    def get(self, parent: AbstractNode) -> Endpoint:
        return input_mapping_endpoint.InputMappingEndpoint(self,
                                                           parent,
                                                           self.input_data,
                                                           self.output_data)
