"""Layer 2 of SNR: ready-made components (thesis 6.4).

Sub-packages: ``comms`` (talk between nodes), ``filters``, ``io`` (console,
recorder, replayer, serial, controller, live view), ``sim`` (a simulated
robot) and ``utils`` (timeout, stopwatch, printer). Each sub-package gives
its components; the common ones are also in ``snr`` (``from snr import *``).
Importing this package imports none of them: a program pays only for the
components it uses.

Example::

    from snr.std_mods.comms import SocketsServerFactory
    from snr.std_mods.io import TextReplayerFactory
"""

__all__ = ["comms", "filters", "io", "sim", "utils"]
