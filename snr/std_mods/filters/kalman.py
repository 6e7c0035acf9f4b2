"""A one-dimensional Kalman filter endpoint and factory.

The filter estimates a value that changes slowly (a depth, a temperature)
from noisy measurements: each one moves the estimate towards itself by the
*Kalman gain*, a lot when the estimate is uncertain, a little when the sensor
is noisy. Its state is kept on the factory, so it survives a hot reload.
"""

from __future__ import annotations

import math
import sys
from typing import Optional

from snr.core import Endpoint, EndpointFactory, tasks
from snr.prelude import (
    AbstractNode,
    ConfigError,
    DataKey,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)

__all__ = ["KalmanFilter", "KalmanFilterEndpoint", "KalmanFilterFactory"]


class KalmanFilter:
    """A 1-D Kalman filter for a value that drifts slowly (a random walk).

    Args:
        process_variance: how much the true value may change between two
            measurements (variance, in units²). Larger: follows changes
            faster, smooths less.
        measurement_variance: how noisy the sensor is (variance of its error,
            units²; the square of the noise's standard deviation).
        estimate: the starting estimate; None starts at the first measurement.
        variance: how uncertain the starting estimate is (units²); None uses
            ``measurement_variance``.

    Example::

        kf = KalmanFilter(process_variance=0.001, measurement_variance=0.25)
        for z in [1.2, 0.8, 1.1, 0.9]:
            kf.update(z)
        kf.estimate   # close to 1.0
    """

    def __init__(
        self,
        process_variance: float,
        measurement_variance: float,
        estimate: Optional[float] = None,
        variance: Optional[float] = None,
    ) -> None:
        if not process_variance >= 0:  # also rejects NaN
            raise ConfigError(
                f"KalmanFilter(process_variance={process_variance}): it must be 0 or more "
                "(0 means the true value never changes)."
            )
        if not measurement_variance > 0:
            raise ConfigError(
                f"KalmanFilter(measurement_variance={measurement_variance}): it must be more "
                "than 0: the square of your sensor's noise, e.g. 0.05**2 for ±5 cm."
            )
        self.process_variance = float(process_variance)
        self.measurement_variance = float(measurement_variance)
        self.estimate = estimate
        self.variance = measurement_variance if variance is None else float(variance)
        self.gain = 0.0

    def update(self, measurement: float) -> float:
        """Take one measurement; return the new estimate.

        Example::

            kf.update(3.1)   # e.g. 3.04
        """
        if self.estimate is None:  # first measurement: nothing better to go on
            self.estimate = float(measurement)
            return self.estimate
        # Predict: the value may have drifted, so we are less sure of it.
        predicted_variance = self.variance + self.process_variance
        # Correct: trust the measurement in proportion to our uncertainty.
        self.gain = predicted_variance / (predicted_variance + self.measurement_variance)
        self.estimate += self.gain * (measurement - self.estimate)
        self.variance = (1.0 - self.gain) * predicted_variance
        return self.estimate


class KalmanFilterEndpoint(Endpoint):
    """Filters numbers stored under ``input``; stores estimates under ``output``.

    Values that are not finite numbers are logged and skipped, so one bad
    reading cannot spoil every later estimate.

    Example::

        KalmanFilterFactory("depth_raw", "depth", 1e-4, 0.05**2)
    """

    def __init__(self, factory: KalmanFilterFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.input = factory.input
        self.output = factory.output
        self.filter = factory.filter
        self.task_handlers = {(TaskType.store_page, self.input): self.update_filter}

    def update_filter(self, task: Task, key: TaskId) -> SomeTasks:
        """Feed the stored number to the filter and store the new estimate."""
        page = task.page()
        data = page.data if page is not None else None
        if isinstance(data, bool) or not isinstance(data, (int, float)) or not math.isfinite(data):
            self.warn("Skipped %r under %r: expected a finite number", data, self.input)
            return None
        return tasks.store_page(self.page(self.output, self.filter.update(data)))


class KalmanFilterFactory(EndpointFactory):
    """Builds a `KalmanFilterEndpoint`; the filter's state survives reloads.

    Args:
        input: the data key of the raw measurements.
        output: the data key to store the estimates under.
        process_variance: how much the true value may change between
            measurements (units²). Try ``measurement_variance / 100`` first.
        measurement_variance: the sensor's noise variance (units²).
        name: the endpoint's name (default ``"kalman_filter"``).

    Example::

        # a depth sensor with ±5 cm noise on a slowly moving robot
        KalmanFilterFactory("depth_raw", "depth", process_variance=1e-4,
                            measurement_variance=0.05**2)
    """

    def __init__(
        self,
        input: DataKey,
        output: DataKey,
        process_variance: float,
        measurement_variance: float,
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        self.input = input
        self.output = output
        self.name = name or "kalman_filter"
        self.filter = KalmanFilter(process_variance, measurement_variance)

    def get(self, parent: AbstractNode) -> KalmanFilterEndpoint:
        # Rebuild the filter from the old one's numbers, so a reload keeps
        # the state *and* runs the newly loaded KalmanFilter code.
        old = self.filter
        self.filter = KalmanFilter(
            old.process_variance, old.measurement_variance, old.estimate, old.variance
        )
        return KalmanFilterEndpoint(self, parent)
