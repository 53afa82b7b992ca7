"""A friction estimator of your own: the slip estimator's reports, smoothed, floored by the IMU.

Run it in closed loop from the repository root (the CLI imports from the current directory):

    mufusion run popup --config examples.plugins.recursive_slip:RecursiveSlip
    mufusion campaign examples/plugins/compare.toml --out results/plugins
"""

from __future__ import annotations

import math

import numpy as np

from mufusion.configurations import FrictionEstimator
from mufusion.estimators import SensorFrame, VehicleSignals

G_MPS2 = 9.81


class RecursiveSlip(FrictionEstimator):
    """μ̂ = a recursive mean of the slip reports minus their margin, never below the friction the
    tires demonstrably transmit (|a| / g); one value over the whole horizon. No camera."""

    channels = frozenset()  # the slip report and the vehicle signals reach every source

    def __init__(self, forgetting: float = 0.7) -> None:
        self.forgetting = forgetting  # weight of the past in the recursive mean [-]
        self.mu: float | None = None
        self.demonstrated = 0.0

    def observe(self, signals: VehicleSignals) -> None:  # after every plant step
        self.demonstrated = max(self.demonstrated,
                                math.hypot(signals.accel_x_mps2, signals.accel_y_mps2) / G_MPS2)

    def step(self, frame: SensorFrame) -> np.ndarray:  # once per planning step
        if self.mu is None:
            self.mu = frame.slip.mu
        elif frame.slip.available:  # the slip estimator measured: update the recursive mean
            self.mu = self.forgetting * self.mu + (1.0 - self.forgetting) * frame.slip.mu
        mu_hat = max(self.mu - frame.slip.margin, self.demonstrated)
        self.demonstrated = 0.0  # the next interval's floor is measured afresh
        return np.full(frame.s_ahead_m.shape, mu_hat)
