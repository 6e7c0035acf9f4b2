"""Thesis listing 5.1: Example configuration of a UROV system.

Printed in section 5.1 (line 308 of the thesis text). Its components are in
the ``urov`` module of ``examples/urov`` (``urov.py``), the thesis's
"exercise for the reader". With that folder on PYTHONPATH (or this file
copied into it), run ``python listing_5_1.py urov`` on the vehicle and
``python listing_5_1.py topside`` on the pilot's computer. On one computer,
change both addresses to ``127.0.0.1`` and run ``python listing_5_1.py urov
topside``: the topside node prints the telemetry. The maintained version is
``examples/urov/main.py``.

How the test suite runs it: both roles in one process, each link on 127.0.0.1
and a port free at run time instead of ``192.168.1.10:9000`` and
``192.168.1.11:9001``: it runs this file with ``snr.SocketsPair`` replaced by a
subclass that moves the address there (the text is unchanged).

Repaired PDF artefacts: indentation.
Deviations (each marked ``DEVIATION`` on its line):
- [5.1-bracket] line 22: ``ControlsProcessorFactory("controller_input"),``
  closed the call before its second argument, so line 23's ``)`` matched
  nothing (``SyntaxError: closing parenthesis ')' does not match opening
  parenthesis '['``). The ``)`` on line 22 goes.
"""
import sys
import snr
from urov import *

controller_input_sockets = snr.SocketsPair(
    server_tuple=("192.168.1.10", 9000))
telemetry_sockets = snr.SocketsPair(
    server_tuple=("192.168.1.11", 9001))
components: snr.ComponentsByRole = {
    "topside": [
        # Topside control pipeline
        XboxControllerFactory("raw_controller_input"),
        InputProcessorFactory("raw_controller_input",
                              "controller_input"),
        controller_input_sockets.client("controller_input"),
        # Topside sensor pipeline
        telemetry_sockets.server(),
        SensorDisplayEndpointFactory("sensor_data")],
    "urov": [
        # Robot control pipeline
        controller_input_sockets.server(),
        ControlsProcessorFactory("controller_input",  # DEVIATION [5.1-bracket]
                                 "motor_speed"),
        SerialConnectionFactory("motor_speed"),
        # On robot sensor pipeline
        SensorReaderFactory("sensor_data"),
        telemetry_sockets.client("sensor_data")],
    }

if __name__ == "__main__":
    snr.CliRunner(components, sys.argv).run()
