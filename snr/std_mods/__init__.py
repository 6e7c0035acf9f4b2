"""Layer 2 of SNR: ready-made components (thesis 6.4).

Sub-packages: ``comms`` (talk between nodes: pipes, TCP), ``filters``, ``io``
(console, recorder, replayer) and ``utils`` (timeout, stopwatch, printer).
Serial links, Zenoh, the controller, the live view, MCAP and the simulator
are extras (``snr.extras``). Each sub-package gives
its components; the common ones are also in ``snr`` (``from snr import *``).
Importing this package imports none of them: a program pays only for the
components it uses.

Example::

    from snr.std_mods.comms import SocketsServerFactory
    from snr.std_mods.io import TextReplayerFactory
"""

__all__ = ["comms", "filters", "io", "utils"]
