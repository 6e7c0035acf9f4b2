"""The UROV system of thesis listing 5.1: two nodes, topside and urov.

Run each role in its own terminal (the order does not matter)::

    python examples/urov/main.py urov
    python examples/urov/main.py topside

or both at once (each in its own process)::

    python examples/urov/main.py topside urov --seconds 15

``--real-controller`` reads a real game pad instead of the scripted pilot;
``--host``/``--port`` choose where the two links listen (ports P and P+1).

The system and its components live in the ``snr.extras.demo`` package
(``snr/extras/demo/system.py`` is listing 5.1, ``snr/extras/demo/urov.py`` the components
and the simulated hardware), so ``python -m snr demo`` runs them from an
installed SNR too. This file is the command line around them.
"""

import argparse
import sys
from typing import List

import snr
from snr.extras.demo import make_components


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
