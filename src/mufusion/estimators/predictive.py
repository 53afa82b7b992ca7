"""Emulated camera-based (predictive) friction estimator (paper Sec. IV-A, Table I).

The camera classifies the road surface ahead into the classes of
:mod:`mufusion.estimators.classes` up to its range ``s_f = 50 m``; the class is always the true
one (the paper emulates a correct classifier), and the error model decides the value reported
for it (see :mod:`mufusion.estimators.errors`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.estimators.classes import PAPER_CLASSES, SurfaceClass, classify, validate_classes
from mufusion.estimators.errors import check_error_model, signed_error

# Camera range s_f [m] (paper Table I).
CAMERA_RANGE_M = 50.0


@dataclass(frozen=True)
class PredictiveEstimate:
    """The camera's output over a grid of distances ahead; arrays are read-only, shape (n,).

    Attributes
    ----------
    s_m : numpy.ndarray
        Distances ahead of the vehicle [m].
    mu : numpy.ndarray
        Reported friction coefficient [-]; NaN beyond the camera range (no data).
    margin : numpy.ndarray
        95 % half-width of the report [-] (the class margin); NaN beyond the range.
    class_index : numpy.ndarray of int
        Index of the (true) class in the class table; −1 beyond the range.
    mu_low : numpy.ndarray
        Lowest μ of the class [-] (configuration P's conservative value); NaN beyond the range.
    """

    s_m: np.ndarray
    mu: np.ndarray
    margin: np.ndarray
    class_index: np.ndarray
    mu_low: np.ndarray

    @property
    def in_range(self) -> np.ndarray:
        """Boolean mask of the grid points the camera covers."""
        return self.class_index >= 0


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def check_grid(
    s_ahead_m: np.ndarray, mu_true: np.ndarray, mu_name: str = "mu_true"
) -> tuple[np.ndarray, np.ndarray]:
    """Validate a distance-ahead grid and the true μ on it; returns float copies.

    ``mu_name`` is the name of the μ argument in messages.

    Raises
    ------
    ValueError
        If ``s_ahead_m`` is not 1-D, empty, non-finite, negative or not strictly increasing, or
        ``mu_true`` differs in shape or holds values that are not finite and > 0.
    """
    s = np.array(s_ahead_m, dtype=float)
    mu = np.array(mu_true, dtype=float)
    if s.ndim != 1 or s.size == 0:
        raise ValueError(f"s_ahead_m must be a non-empty 1-D array, got shape {s.shape}")
    if not np.all(np.isfinite(s)) or s[0] < 0.0 or np.any(np.diff(s) <= 0.0):
        raise ValueError("s_ahead_m must be finite, ≥ 0 m and strictly increasing")
    if mu.shape != s.shape:
        raise ValueError(
            f"{mu_name} must have the shape of s_ahead_m {s.shape}, got {mu.shape}"
        )
    if not np.all(np.isfinite(mu)) or np.any(mu <= 0.0):
        raise ValueError(f"{mu_name} must be finite and > 0 everywhere")
    return s, mu


def _segment_ids(class_index: np.ndarray) -> np.ndarray:
    """Label of the contiguous run of equal classes each point belongs to (0, 1, 2, ...)."""
    change = np.concatenate(([False], class_index[1:] != class_index[:-1]))
    return np.cumsum(change)


def predictive_estimate(
    s_ahead_m: np.ndarray,
    mu_true: np.ndarray,
    *,
    classes: Sequence[SurfaceClass] = PAPER_CLASSES,
    error: str = "none",
    rng: np.random.Generator | None = None,
    range_m: float = CAMERA_RANGE_M,
) -> PredictiveEstimate:
    """Emulate one camera frame: class, reported μ and margin at each distance ahead.

    Parameters
    ----------
    s_ahead_m : array_like, shape (n,)
        Distances ahead of the vehicle [m], ≥ 0, strictly increasing.
    mu_true : array_like, shape (n,)
        True friction coefficient at those distances [-].
    classes : sequence of SurfaceClass
        Class table; default the paper's.
    error : {"none", "worst_over", "worst_under", "random"}
        Error model of the reported value (see :mod:`mufusion.estimators.errors`):
        ``"none"`` reports the class value (mean); ``"worst_over"`` / ``"worst_under"`` report
        ``μ_gt ± margin`` of the class; ``"random"`` reports ``μ_gt + e``, ``e ~ U(−margin,
        margin)`` drawn once per contiguous class segment of this frame (one camera estimate
        per segment) from ``rng``. A report below 0 is clipped to 0 (still within the margin
        of ``μ_gt``, which is > 0).
    rng : numpy.random.Generator, optional
        Required for ``error="random"``.
    range_m : float
        Camera range [m]; points with ``s > range_m`` get no data (NaN, class index −1).

    Returns
    -------
    PredictiveEstimate

    Raises
    ------
    ValueError
        On a bad grid or μ (see :func:`check_grid`), an unknown error model, ``"random"``
        without ``rng``, ``range_m`` not finite and > 0, or an in-range μ outside every class.

    Examples
    --------
    >>> est = predictive_estimate([0.0, 20.0, 60.0], [0.8, 0.4, 0.4], error="worst_over")
    >>> est.mu.round(3).tolist(), est.mu_low.tolist()
    ([1.0, 0.5, nan], [0.6, 0.4, nan])
    """
    s, mu = check_grid(s_ahead_m, mu_true)
    check_error_model("error", error, rng)
    table = validate_classes(classes)
    if not (math.isfinite(range_m) and range_m > 0.0):
        raise ValueError(f"range_m must be finite and > 0 m, got {range_m!r}")

    seen = s <= range_m
    class_index = np.full(s.shape, -1, dtype=int)
    class_index[seen] = classify(mu[seen], table)
    values = np.array([c.value for c in table])
    margins = np.array([c.margin for c in table])
    lows = np.array([c.mu_low for c in table])

    idx = class_index[seen]
    report = np.full(s.shape, np.nan)
    margin = np.full(s.shape, np.nan)
    mu_low = np.full(s.shape, np.nan)
    margin[seen] = margins[idx]
    mu_low[seen] = lows[idx]
    if error == "none":
        # The paper's emulation: the camera reports the mean of the (correct) class.
        report[seen] = values[idx]
    elif error == "random":
        # One camera estimate per contiguous class segment: a common error within a segment.
        segment = _segment_ids(idx)
        if rng is None:
            raise ValueError("rng: the 'random' error model needs a numpy.random.Generator")
        e_unit = rng.uniform(-1.0, 1.0, size=int(segment[-1]) + 1 if idx.size else 0)
        report[seen] = mu[seen] + e_unit[segment] * margins[idx]
    else:
        report[seen] = mu[seen] + signed_error(error, margins[idx], rng)
    report[seen] = np.maximum(report[seen], 0.0)
    return PredictiveEstimate(
        s_m=_read_only(s),
        mu=_read_only(report),
        margin=_read_only(margin),
        class_index=_read_only(class_index),
        mu_low=_read_only(mu_low),
    )
