"""Thesis listing A.9: Example implementation of a factory for the controller loop.

Printed in Appendix A (line 1472 of the thesis text). Listing 5.3 imports this
module as ``controller_loop_factory``; it imports listing A.8 as
``controller_loop``. SNR's own version is ``snr.ControllerLoopFactory``.

Repaired PDF artefacts: indentation, and line 10, broken before its ``)``.
Deviations: none.
"""
from snr import *

import controller_loop


class ControllerLoopFactory(LoopFactory):

    output_data: DataKey

    def __init__(self, output_data: DataKey = "raw_controller_input"
                 ) -> None:
        super().__init__([controller_loop])
        self.output_data = output_data

    def get(self,
            parent: AbstractNode,
            ) -> controller_loop.ControllerLoop:
        return controller_loop.ControllerLoop(self,
                                              parent,
                                              self.output_data)
