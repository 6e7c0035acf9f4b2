"""Game controller over sockets (thesis section 5.4.1, listing 5.3).

One node reads a game controller and sends its named buttons and sticks to
another node over TCP; the other prints each button press and release.
Run the two nodes in two terminals:

    python main.py receiver
    python main.py input_device              # with a controller plugged in
    python main.py input_device --simulated  # without one

``--port`` picks another TCP port (default 9000) and ``--seconds`` stops both
nodes after that many seconds (by default the input device stops after 20 s
and the receiver runs until Ctrl-C, as in the thesis).
"""

import argparse
import sys
from typing import List, Optional, Sequence, Tuple

import snr

RAW_KEY = "raw_controller_data"
NAMED_KEY = "controller_data"
DEFAULT_PORT = 9000
INPUT_DEVICE_SECONDS = 20.0


def input_device_parts(joystick: Optional[snr.Joystick] = None) -> List[snr.AbstractFactory]:
    """Read the controller and give its controls names (no networking)."""
    return [
        snr.ControllerLoopFactory(RAW_KEY, joystick=joystick),
        snr.InputMappingFactory(RAW_KEY, NAMED_KEY),
    ]


def receiver_parts() -> List[snr.AbstractFactory]:
    """Turn button changes into events and print them (no networking)."""
    return [
        snr.ControlProcessorFactory(NAMED_KEY),
        snr.PrinterEndpointFactory([
            (snr.TaskType.event, "button_pressed"),
            (snr.TaskType.event, "button_released"),
        ]),
    ]  # fmt: skip


def make_components(
    port: int = DEFAULT_PORT,
    simulated: bool = False,
    seconds: Optional[float] = None,
) -> snr.ComponentsByRole:
    """The two roles of listing 5.3, joined by a sockets connection."""
    # Replays its ~4 s script of presses and stick moves again and again.
    joystick = snr.SimulatedJoystick(repeat_after_s=4.5) if simulated else None
    sockets = snr.SocketsPair(server_tuple=("localhost", port))
    input_device: List[snr.AbstractFactory] = [
        *input_device_parts(joystick),
        sockets.client([NAMED_KEY]),
        snr.TimeoutLoopFactory(seconds=seconds or INPUT_DEVICE_SECONDS),
    ]
    receiver: List[snr.AbstractFactory] = [sockets.server(), *receiver_parts()]
    if seconds is not None:
        receiver.append(snr.TimeoutLoopFactory(seconds=seconds))
    return {"input_device": input_device, "receiver": receiver}


def parse_options(argv: Sequence[str]) -> Tuple[argparse.Namespace, List[str]]:
    """This example's own options; the rest (the role) goes to snr.CliRunner."""
    parser = argparse.ArgumentParser(
        prog=argv[0] if argv else "main.py",
        description="Game controller over sockets: run 'receiver' in one terminal "
        "and 'input_device' in another.",
    )
    parser.add_argument("roles", nargs="*", metavar="ROLE", help="input_device or receiver")
    parser.add_argument(
        "--simulated", action="store_true", help="use a pretend controller (no pad needed)"
    )
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="TCP port (9000)")
    parser.add_argument("--seconds", type=float, default=None, help="stop after this long")
    options, rest = parser.parse_known_args(argv[1:])
    return options, [*options.roles, *rest]


def main(argv: Sequence[str]) -> None:
    options, cli_args = parse_options(argv)
    components = make_components(options.port, options.simulated, options.seconds)
    snr.CliRunner(components, [argv[0], *cli_args]).run()


if __name__ == "__main__":
    main(sys.argv)
