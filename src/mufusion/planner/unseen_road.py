"""The road beyond the friction estimate: where the estimate ends and what its source declares
possible there, for the planner's speed reference (docs/decisions/0084)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

MuOfS = Callable[[np.ndarray], np.ndarray]
"""A friction profile over absolute progress [m] → [-]."""


@dataclass(frozen=True)
class UnseenRoad:
    """Where the friction estimate ends and the friction the speed reference assumes beyond it.

    Holding the estimate's last value there (the authors' TAMP framework) lets a vehicle arrive
    at a curve it cannot see yet at the pace of the friction it sees: when the camera reveals
    ice on the curve, the braking distance is gone. With the lowest friction possible beyond
    ``from_s_m``, the reference keeps such a curve reachable from the edge of what is known, the
    principle of driving within sight; the OCP's friction rows keep the estimate (docs/decisions/
    0084).

    Attributes
    ----------
    from_s_m
        Absolute progress of the estimate's last grid point [m].
    mu
        Friction assumed beyond it [-] (the estimate's ``unseen_mu``).
    """

    from_s_m: float
    mu: float

    def __post_init__(self) -> None:
        if not math.isfinite(self.from_s_m):
            raise ValueError(f"UnseenRoad.from_s_m must be finite, got {self.from_s_m!r}")
        if not 0.0 < self.mu <= 2.0:
            raise ValueError(f"UnseenRoad.mu must be in (0, 2], got {self.mu!r}")

    def cap(self, mu_of_s: MuOfS) -> MuOfS:
        """``mu_of_s`` capped by :attr:`mu` beyond :attr:`from_s_m`.

        Examples
        --------
        >>> mu = UnseenRoad(50.0, 0.1).cap(lambda s: np.full(np.shape(s), 0.8))
        >>> mu(np.array([0.0, 50.0, 51.0])).tolist()
        [0.8, 0.8, 0.1]
        """

        def capped(s_m: np.ndarray) -> np.ndarray:
            s = np.asarray(s_m, dtype=float)
            mu = np.asarray(mu_of_s(s), dtype=float)
            return np.where(s > self.from_s_m, np.minimum(mu, self.mu), mu)

        return capped
