"""Emulated slip-based (local) friction estimator (paper Sec. IV-A, Table I, configuration L).

A slip-based estimator measures the friction under the tires only when the tires are excited
enough: available iff the tire-force utilization ``λ_t > 0.5``, then accurate to
``max{|e_l|} = 0.025``. When it is not available the latest value is held (the paper's
``μ̂_0``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.estimators.errors import check_error_model, signed_error

# Worst-case error of the local estimator max{|e_l|} [-] (paper Table I).
LOCAL_MAX_ERROR = 0.025
# Tire-force utilization above which the local estimate is available [-] (paper Table I).
UTILIZATION_THRESHOLD = 0.5
# Admissible true friction coefficients [-]: physically 0 < μ, and no tire exceeds 2.
MU_MAX = 2.0


@dataclass(frozen=True)
class LocalEstimate:
    """Output of one local-estimator update.

    Attributes
    ----------
    mu : float
        Held local estimate including its error [-] (``μ_gt(0) + e_l`` of the latest
        measurement, or the initial value).
    margin : float
        Its worst-case error ``max{|e_l|}`` [-].
    available : bool
        Whether this update measured (utilization above the threshold).
    """

    mu: float
    margin: float
    available: bool


def _check_mu(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and 0.0 < value <= MU_MAX):
        raise ValueError(f"{name} must be a friction coefficient in (0, {MU_MAX}], got {value!r}")
    return value


class LocalEstimator:
    """Slip-based local friction estimator with a hold (paper configuration L, without the
    conservative offset, which the configuration subtracts).

    Parameters
    ----------
    max_error : float
        Worst-case error ``max{|e_l|}`` [-], in (0, 1); also the reported margin.
    utilization_threshold : float
        Available iff utilization > this [-], ≥ 0.
    error : {"none", "worst_over", "worst_under", "random"}
        Error model ``e_l`` of a measurement: 0, ``+max_error``, ``−max_error`` or
        ``U(−max_error, max_error)`` drawn per measurement from ``rng``.
    rng : numpy.random.Generator, optional
        Required for ``error="random"``.
    initial_mu : float, optional
        Held value before the first measurement [-] (taken as an estimate, no error added). If
        None, the very first update measures the true μ with the error model as if the estimate
        had been available just before the run started (the vehicle drove on that surface);
        that update still reports ``available=False``.

    Raises
    ------
    ValueError
        On a parameter outside the ranges above, an unknown error model, or ``"random"``
        without ``rng``.

    Examples
    --------
    >>> est = LocalEstimator(error="worst_over")
    >>> first = est.update(0.8, utilization=0.2)  # measured as if available before the start
    >>> round(first.mu, 3), first.available
    (0.825, False)
    >>> round(est.update(0.4, utilization=0.2).mu, 3)  # not excited: the old value is held
    0.825
    >>> now = est.update(0.4, utilization=0.7)
    >>> round(now.mu, 3), now.available
    (0.425, True)
    """

    def __init__(
        self,
        *,
        max_error: float = LOCAL_MAX_ERROR,
        utilization_threshold: float = UTILIZATION_THRESHOLD,
        error: str = "none",
        rng: np.random.Generator | None = None,
        initial_mu: float | None = None,
    ) -> None:
        max_error = float(max_error)
        if not (math.isfinite(max_error) and 0.0 < max_error < 1.0):
            raise ValueError(f"max_error must be in (0, 1), got {max_error!r}")
        utilization_threshold = float(utilization_threshold)
        if not (math.isfinite(utilization_threshold) and utilization_threshold >= 0.0):
            raise ValueError(
                f"utilization_threshold must be finite and ≥ 0, got {utilization_threshold!r}"
            )
        self.max_error = max_error
        self.utilization_threshold = utilization_threshold
        self.error = error
        self.rng = check_error_model("error", error, rng)
        self.initial_mu = None if initial_mu is None else _check_mu("initial_mu", initial_mu)
        self._held: float | None = self.initial_mu
        self._last: LocalEstimate | None = None

    @property
    def estimate(self) -> LocalEstimate | None:
        """The output of the latest update (None before the first)."""
        return self._last

    def reset(self) -> None:
        """Forget all measurements: back to ``initial_mu`` (the rng is not rewound)."""
        self._held = self.initial_mu
        self._last = None

    def _measure(self, mu_true_here: float) -> float:
        # μ̂_l = μ_gt(0) + e_l (paper Sec. IV-B, configuration L); never a negative friction.
        return max(mu_true_here + float(signed_error(self.error, self.max_error, self.rng)), 0.0)

    def update(self, mu_true_here: float, utilization: float) -> LocalEstimate:
        """One estimator cycle.

        Parameters
        ----------
        mu_true_here : float
            True μ under the vehicle [-], in (0, 2].
        utilization : float
            Realised tire-force utilization ``λ_t`` over the last interval [-], finite, ≥ 0.

        Returns
        -------
        LocalEstimate

        Raises
        ------
        ValueError
            If an argument is outside its range.
        """
        mu_true_here = _check_mu("mu_true_here", mu_true_here)
        utilization = float(utilization)
        if not (math.isfinite(utilization) and utilization >= 0.0):
            raise ValueError(f"utilization must be finite and ≥ 0, got {utilization!r}")
        available = utilization > self.utilization_threshold
        if available or self._held is None:
            self._held = self._measure(mu_true_here)
        self._last = LocalEstimate(mu=self._held, margin=self.max_error, available=available)
        return self._last
