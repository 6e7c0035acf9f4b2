"""The 2021 module path that thesis listing A.2 imports from.

Listing A.2 writes ``from snr.core.core_utils import moving_avg_filter`` and
then ``moving_avg_filter.MovingAvgFilter(...)``; this module makes that line
work. New code imports the class by name: ``from snr import MovingAvgFilter``.

Example::

    from snr.core.core_utils import moving_avg_filter
    f = moving_avg_filter.MovingAvgFilter(collections.deque(maxlen=3))
"""

from snr.core import moving_avg_filter
from snr.core.moving_avg_filter import MovingAvgFilter

__all__ = ["MovingAvgFilter", "moving_avg_filter"]
