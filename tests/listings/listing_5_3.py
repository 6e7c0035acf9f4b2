"""Thesis listing 5.3: Example configuration using game controller and sockets.

Printed in section 5.4.1 (line 451 of the thesis text). Run from this folder,
where listings A.6-A.11 are the modules it imports, as two nodes in two
terminals: ``python listing_5_3.py receiver`` and
``python listing_5_3.py input_device`` (the thesis text says
``input.device``; the role is ``input_device``). The input device needs pygame
and a game controller (listing A.8). The maintained version is
``examples/controller/main.py``.

How the test suite runs it: both roles in one process, on 127.0.0.1 and a port
free at run time instead of ``("localhost", 9000)``: it runs this file with
``snr.SocketsPair`` replaced by a subclass that moves the address there (the
text is unchanged), and a virtual SDL pad as the controller.

Repaired PDF artefacts: indentation.
Deviations: none.
"""
import sys
import snr

from control_processor_factory import ControlProcessorFactory
from controller_loop_factory import ControllerLoopFactory
from input_mapping_factory import InputMappingFactory

sockets = snr.SocketsPair(server_tuple=("localhost", 9000))
components: snr.ComponentsByRole = {
    "input_device": [
        ControllerLoopFactory("raw_controller_data"),
        InputMappingFactory("raw_controller_data",
                            "controller_data"),
        sockets.client(["controller_data"]),
        snr.TimeoutLoopFactory(seconds=20),
    ],
    "receiver": [
        sockets.server(),
        ControlProcessorFactory("controller_data"),
        snr.PrinterEndpointFactory([
            (snr.TaskType.event, "button_pressed"),
            (snr.TaskType.event, "button_released"),
        ])
    ]
}

if __name__ == '__main__':
    snr.CliRunner(components, sys.argv).run()
