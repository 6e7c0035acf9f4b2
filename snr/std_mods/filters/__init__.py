"""Filters for noisy sensor data.

Example::

    from snr.std_mods.filters import KalmanFilterFactory, MovingAvgFilterFactory
"""

from snr.std_mods.filters.kalman import KalmanFilter, KalmanFilterEndpoint, KalmanFilterFactory
from snr.std_mods.filters.moving_average import (
    DEFAULT_FILTER_LENGTH,
    MovingAvgEndpoint,
    MovingAvgFilter,
    MovingAvgFilterFactory,
)

__all__ = [
    "DEFAULT_FILTER_LENGTH",
    "KalmanFilter",
    "KalmanFilterEndpoint",
    "KalmanFilterFactory",
    "MovingAvgEndpoint",
    "MovingAvgFilter",
    "MovingAvgFilterFactory",
]
