"""The GP prior over friction along the road (paper Sec. III, eq. 5), with declared ranges.

f(s) ~ GP(mean, k), k(s, s') = std² exp(−(s − s')² / (2 ℓ²)). The ranges below are what the
fusion accepts; anything outside raises ``ValueError`` naming the field and the range, because
outside them the posterior stops meaning anything (a std of 1e200 overflows the variance, one of
1e-300 underflows it to 0) long before it stops being computable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.estimators.shared import check_in

Z95 = 1.96
"""Two-sided 95 % quantile of the standard normal: margin = Z95 · std (paper Sec. III)."""

PRIOR_MEAN_RANGE = (0.0, 2.0)
"""Allowed prior mean of μ [-], inclusive: the physical range of μ (``MU_RANGE``)."""

PRIOR_STD_RANGE = (1e-3, 1.0)
"""Allowed prior std of μ [-], inclusive. Above 1 the 95 % band (± 1.96) is wider than the whole
physical range [0, 2]; below 1e-3 the prior claims to know μ to ± 0.002, finer than any estimator
and than the fusion's noise floor (``NOISE_STD_FLOOR``), so no datum could move it."""

LENGTH_SCALE_RANGE_M = (0.1, 1e4)
"""Allowed kernel length scale ℓ [m], inclusive: from below a tyre's contact patch to 10 km, over
which μ is a constant for any planning horizon."""


def _check_in(name: str, value: object, bounds: tuple[float, float], unit: str = "") -> float:
    """``float(value)`` if it is a finite number within ``bounds`` (inclusive), else ValueError."""
    return check_in(name, value, bounds[0], bounds[1], unit)


@dataclass(frozen=True)
class GPPrior:
    """GP prior f(s) ~ GP(mean, k) with k(s, s') = std² exp(−(s − s')² / (2 ℓ²)) (eq. 5).

    Attributes
    ----------
    mean
        Constant prior mean η of μ [-], in ``PRIOR_MEAN_RANGE`` = [0, 2].
    std
        Prior standard deviation σ_f of μ [-], in ``PRIOR_STD_RANGE`` = [0.001, 1].
    length_scale_m
        Squared-exponential length scale ℓ [m], in ``LENGTH_SCALE_RANGE_M`` = [0.1, 10 000].

    Raises
    ------
    ValueError
        If a field is not a finite number within its declared range (the message names it).

    Examples
    --------
    >>> p = GPPrior.from_interval(0.1, 1.0, 15.0)
    >>> round(p.mean, 3), round(p.std, 4)
    (0.55, 0.2296)
    """

    mean: float
    std: float
    length_scale_m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", _check_in("GPPrior.mean", self.mean, PRIOR_MEAN_RANGE))
        object.__setattr__(self, "std", _check_in("GPPrior.std", self.std, PRIOR_STD_RANGE))
        object.__setattr__(
            self,
            "length_scale_m",
            _check_in("GPPrior.length_scale_m", self.length_scale_m, LENGTH_SCALE_RANGE_M, " m"),
        )

    @classmethod
    def from_interval(cls, low: float, high: float, length_scale_m: float) -> GPPrior:
        """Prior whose 95 % band is ``[low, high]`` (paper Sec. III: [0.1, 1.0]).

        Parameters
        ----------
        low, high
            Band edges of μ [-], ``low < high``.
        length_scale_m
            Kernel length scale ℓ [m].

        Returns
        -------
        GPPrior
            ``mean = (low + high) / 2``, ``std = (high − low) / (2 · 1.96)``.

        Raises
        ------
        ValueError
            If ``low`` or ``high`` is not finite or ``low >= high``, or the resulting mean, std or
            ``length_scale_m`` is outside its declared range.
        """
        low, high = float(low), float(high)
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(
                f"GPPrior.from_interval needs finite low < high, got low={low!r}, high={high!r}"
            )
        return cls(0.5 * (low + high), 0.5 * (high - low) / Z95, length_scale_m)

    @property
    def variance(self) -> float:
        """Prior variance σ_f² [-]."""
        return self.std * self.std

    @property
    def upper(self) -> float:
        """Upper edge of the prior's 95 % band, ``mean + 1.96 std`` [-]."""
        return self.mean + Z95 * self.std

    def kernel(self, a_m: np.ndarray, b_m: np.ndarray) -> np.ndarray:
        """Squared-exponential covariance matrix k(a_i, b_j) (eq. 5), shape ``(len(a), len(b))``."""
        a = np.asarray(a_m, dtype=float).reshape(-1, 1)
        b = np.asarray(b_m, dtype=float).reshape(1, -1)
        d = (a - b) / self.length_scale_m
        return self.variance * np.exp(-0.5 * d * d)


PAPER_LENGTH_SCALE_M = 15.0
"""Kernel length scale ℓ [m]: the authors' value in their code (the paper does not state it)."""

PAPER_PRIOR = GPPrior.from_interval(0.1, 1.0, PAPER_LENGTH_SCALE_M)
"""The paper's prior: [0.1, 1.0] is its 95 % band (Sec. III); ℓ = 15 m."""


def check_prior(prior: object) -> GPPrior:
    """``prior`` if it is a :class:`GPPrior` (validated when it was built), else ValueError."""
    if not isinstance(prior, GPPrior):
        raise ValueError(f"prior must be a GPPrior, got {type(prior).__name__}")
    return prior
