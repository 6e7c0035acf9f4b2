"""Small standard components: timeout, stopwatch, printer.

Example::

    from snr.std_mods.utils import TimeoutLoopFactory
"""

from snr.std_mods.utils.printer import PrinterEndpoint, PrinterEndpointFactory, format_task
from snr.std_mods.utils.stopwatch import StopwatchEndpoint, StopwatchEndpointFactory
from snr.std_mods.utils.timeout import TimeoutLoop, TimeoutLoopFactory

__all__ = [
    "PrinterEndpoint",
    "PrinterEndpointFactory",
    "StopwatchEndpoint",
    "StopwatchEndpointFactory",
    "TimeoutLoop",
    "TimeoutLoopFactory",
    "format_task",
]
