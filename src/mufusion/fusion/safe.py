"""Safe mode (beyond the paper): grouped noise for the reported band, hard bounds for μ̂.

Points that are copies of one estimate share one error (a correlated noise block per group), and
μ̂ is capped by the hard bound ``y − margin`` each estimate implies, so that μ̂ never exceeds the
true μ at a data point when every error is within its declared margin. See ``docs/fusion.md``,
"Safe mode", for the proof sketch. Inputs are validated types; nothing is checked here.
"""

from __future__ import annotations

import math

import numpy as np

from mufusion.fusion.data import FusedEstimate, FusionData, clip_single
from mufusion.fusion.engine import PosteriorEngine
from mufusion.fusion.prior import Z95, GPPrior

SHARED_ERROR_FRACTION = 0.999
"""Safe mode: share of a point's noise variance that is common to its group [-].

The rest (0.1 %) is independent per point. It keeps ``K + Σ`` well conditioned when a group has
many close points (the squared-exponential ``K`` alone is numerically singular there), and it makes
a one-point group identical to the paper's independent noise.
"""

SAME_S_TOL_M = 1e-9
"""Two positions closer than this are the same point [m]."""


def grouped_noise(
    noise_sd: np.ndarray, groups: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """Independent std and shared-error columns for one shared error per group.

    Σ_ij = ρ σ_i σ_j for i ≠ j in a group, Σ_ii = σ_i² (ρ = ``SHARED_ERROR_FRACTION``), written as
    ``diag((1 − ρ) σ²) + G Gᵀ`` with one column of G per group holding ``sqrt(ρ) σ_i`` on its
    points. Returns None when every point is its own group: Σ is then the paper's diag(σ²).
    """
    n = groups.size
    if n > 1 and (groups[1:] >= groups[:-1]).all():
        # Sorted labels (assemble_inputs' output): the runs give the index without np.unique.
        index = np.zeros(n, dtype=np.int64)
        np.cumsum(groups[1:] != groups[:-1], out=index[1:])
        n_groups = int(index[-1]) + 1
    else:
        labels, index = np.unique(groups, return_inverse=True)
        n_groups = labels.size
    if n_groups == n:
        return None
    shared = np.zeros((n, n_groups))
    shared[np.arange(groups.size), index] = math.sqrt(SHARED_ERROR_FRACTION) * noise_sd
    return math.sqrt(1.0 - SHARED_ERROR_FRACTION) * noise_sd, shared


def hard_bound_envelope(
    s: np.ndarray, y: np.ndarray, margin: np.ndarray, s_eval: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Guaranteed lower bound on μ at the evaluation points, and a mask of points outside the data.

    At a data position the bound is ``max(y − margin)`` over all estimates there (each one alone
    is a valid bound when its error is within its margin). Strictly between two data positions
    it is the smaller of the two neighbours' bounds; outside the data it holds the nearest end's
    bound (the caller also caps it there by the GP).
    """
    lo = y - margin
    if (np.diff(s) > SAME_S_TOL_M).all():
        us, ub = s, lo  # already sorted, one estimate per position
        if us.size == s_eval.size and (us == s_eval).all():
            return ub, np.zeros(s_eval.size, dtype=bool)  # evaluated at the data positions
    else:
        order = np.lexsort((-lo, s))  # by s, then the largest bound first
        s_sorted = s[order]
        lo_sorted = lo[order]
        first = np.ones(s_sorted.size, dtype=bool)
        first[1:] = np.diff(s_sorted) > SAME_S_TOL_M
        us = s_sorted[first]
        ub = lo_sorted[first]
    where = envelope_index(us, s_eval)
    return envelope_bound(ub, where), where[4]


def envelope_index(
    us: np.ndarray, s_eval: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Neighbours of each evaluation point among the sorted, distinct data positions ``us``:
    left and right index, whether it sits on either, and whether it lies outside the data."""
    idx = np.searchsorted(us, s_eval)
    left = np.maximum(idx - 1, 0)
    right = np.minimum(idx, us.size - 1)
    at_left = np.abs(s_eval - us[left]) <= SAME_S_TOL_M
    at_right = np.abs(s_eval - us[right]) <= SAME_S_TOL_M
    outside = ((s_eval < us[0]) | (s_eval > us[-1])) & ~(at_left | at_right)
    return left, right, at_left, at_right, outside


def envelope_bound(
    ub: np.ndarray, where: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
) -> np.ndarray:
    """The hard bound at the evaluation points from the bounds ``ub`` at the data positions
    (last axis; any leading batch axes)."""
    left, right, at_left, at_right, _ = where
    bound = np.minimum(ub[..., left], ub[..., right])
    bound = np.where(at_right, ub[..., right], bound)
    return np.where(at_left, ub[..., left], bound)


def safe_estimate(
    engine: PosteriorEngine,
    prior: GPPrior,
    data: FusionData,
    e: np.ndarray,
    resid: np.ndarray,
    noise_sd: np.ndarray,
    paper: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> FusedEstimate:
    """Safe-mode estimate from the paper-mode posterior ``(mean, std, lower)`` on the same data.

    ``mean``/``std``/``lower`` of the result are the grouped-noise posterior; ``mu_hat`` is the
    paper-mode lower bound capped by the hard bounds (and, beyond the data, by the grouped lower
    bound), then kept within the band ``[0, max(prior.upper, max(mu))]``.
    """
    mean, std, lower = paper
    split = None if data.groups is None else grouped_noise(noise_sd, data.groups)
    if split is None:
        # Every point its own group: the grouped posterior is the paper's (Σ = diag(σ²)).
        g_mean, g_std, g_lower = mean, std, lower
    else:
        g_mean, g_std = engine.latent(prior, data.s_m, e, resid, split[0], split[1])
        g_mean += prior.mean  # in place: the engine returns fresh arrays
        g_lower = g_std * -Z95
        g_lower += g_mean
    # μ̂ = paper lower bound capped by what the estimates guarantee (docs/fusion.md).
    bound, outside = hard_bound_envelope(data.s_m, data.mu, data.margin, e)
    mu_hat = np.minimum(lower, bound)
    mu_hat = np.where(outside, np.minimum(mu_hat, g_lower), mu_hat)
    return FusedEstimate(e, g_mean, g_std, g_lower, clip_single(mu_hat, prior.upper, data))
