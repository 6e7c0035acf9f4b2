"""Thesis listing A.2: Standard implementation of a factory for MovingAverageFilterEndpoint.

Printed in Appendix A (line 886 of the thesis text). The module is
``moving_avg_endpoint_factory`` in the package ``moving_avg``, beside
listing A.1 (``moving_avg_endpoint``).

Repaired PDF artefacts: indentation, and lines 22 and 27, broken after
``maxlen=`` and ``self.``.
Deviations: none. ``snr.core.core_utils`` is the 2021 module path, kept in SNR
so line 5 works (it gives the ``moving_avg_filter`` module of ``snr.core``).
"""
import collections
from typing import Deque

from snr.core import *
from snr.core.core_utils import moving_avg_filter
from snr.prelude import *

from . import moving_avg_endpoint

DEFAULT_FILTER_LENGTH: int = 3


class MovingAvgFilterFactory(EndpointFactory):
    def __init__(self,
                 input: DataKey,
                 output: DataKey,
                 length: int,
                 ) -> None:
        super().__init__([moving_avg_endpoint, moving_avg_filter])
        self.input = input
        self.output = output
        self.backing_deque: Deque[float] = collections.deque(maxlen=length)

    def get(self,
            parent: AbstractNode,
            ) -> moving_avg_endpoint.MovingAvgEndpoint:
        filter = moving_avg_filter.MovingAvgFilter(self.backing_deque)
        return moving_avg_endpoint.MovingAvgEndpoint(
            self,
            parent,
            "moving_avg_filter",
            self.input,
            self.output,
            filter)
