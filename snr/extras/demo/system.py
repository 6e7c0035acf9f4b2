"""The UROV system of thesis listing 5.1: which components each node runs.

``python -m snr demo`` runs it with both roles on this machine;
``examples/urov/main.py`` runs it from the command line, one role or both.
"""

from __future__ import annotations

from typing import Optional

import snr
from snr.extras.demo.urov import (
    ControlsProcessorFactory,
    InputProcessorFactory,
    SensorDisplayEndpointFactory,
    SensorReaderFactory,
    SerialConnectionFactory,
    TelemetryFactory,
    XboxControllerFactory,
)

__all__ = ["make_components"]


def make_components(
    host: str = "127.0.0.1",
    port: int = 9000,
    seconds: Optional[float] = None,
    simulated: bool = True,
) -> snr.ComponentsByRole:
    """The whole system: the links listen on ``port`` and ``port + 1`` of ``host``.

    ``seconds`` stops every node after that long; ``simulated=False`` reads a
    real game pad instead of the scripted pilot.

    Example::

        components = make_components("127.0.0.1", 9000, seconds=15)
        snr.CliRunner(components, ["main.py", "topside", "urov"]).run()
    """
    controller_input_sockets = snr.SocketsPair(server_tuple=(host, port))
    telemetry_sockets = snr.SocketsPair(server_tuple=(host, port + 1))
    components: snr.ComponentsByRole = {
        "topside": [
            # Topside control pipeline
            XboxControllerFactory("raw_controller_input", simulated),
            InputProcessorFactory("raw_controller_input", "controller_input"),
            controller_input_sockets.client("controller_input"),
            # Topside sensor pipeline
            telemetry_sockets.server(),
            SensorDisplayEndpointFactory("sensor_data"),
        ],
        "urov": [
            # Robot control pipeline
            controller_input_sockets.server(),
            ControlsProcessorFactory("controller_input", "motor_speed"),
            SerialConnectionFactory("motor_speed"),
            # On robot sensor pipeline
            SensorReaderFactory(),
            snr.MovingAvgFilterFactory("depth_raw", "depth", length=5),
            TelemetryFactory("sensor_data"),
            telemetry_sockets.client("sensor_data"),
        ],
    }
    if seconds is not None:
        for factories in components.values():
            assert isinstance(factories, list)
            factories.append(snr.TimeoutLoopFactory(seconds=seconds))
    return components
