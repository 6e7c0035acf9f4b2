"""The UROV system of thesis listing 5.1: two nodes, topside and urov.

Run each role in its own terminal (the order does not matter)::

    python examples/urov/main.py urov
    python examples/urov/main.py topside

or both at once (each in its own process)::

    python examples/urov/main.py topside urov --seconds 15

``--real-controller`` reads a real game pad instead of the scripted pilot;
``--host``/``--port`` choose where the two links listen (ports P and P+1).
"""

import argparse
import sys
from typing import List, Optional

from urov import (
    ControlsProcessorFactory,
    InputProcessorFactory,
    SensorDisplayEndpointFactory,
    SensorReaderFactory,
    SerialConnectionFactory,
    TelemetryFactory,
    XboxControllerFactory,
)

import snr


def make_components(
    host: str = "127.0.0.1",
    port: int = 9000,
    seconds: Optional[float] = None,
    simulated: bool = True,
) -> snr.ComponentsByRole:
    """The whole system; ``seconds`` stops every node after that long."""
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


def main(argv: List[str]) -> None:
    """Parse this example's options; the roles go to ``snr.CliRunner``."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=9000)
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--real-controller", action="store_true")
    options, rest = parser.parse_known_args(argv[1:])
    components = make_components(
        options.host, options.port, options.seconds, simulated=not options.real_controller
    )
    snr.CliRunner(components, [argv[0], *rest]).run()


if __name__ == "__main__":
    main(sys.argv)
