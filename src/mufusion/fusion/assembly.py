"""Input assembly for the fusion: predictive classes ahead, the local estimate near the vehicle.

Paper Sec. III, "we combine friction estimates ... into two input data vectors":
``μ'(s), m'(s) = (μ_l, m_l)`` if the local estimate is available and ``s < s_l``, else
``(μ_p(s), m_p(s))``. Each point also gets a group label: points that are copies of one estimate
(the local estimate; one class segment seen by the camera) share one label, which safe mode uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.fusion.data import (
    MARGIN_RANGE,
    MU_RANGE,
    POSITION_RANGE_M,
    FusionData,
    FusionMode,
    check_mode,
    check_range,
)
from mufusion.fusion.safe import SAME_S_TOL_M, envelope_index

GRID_STEP_M = 1.0
"""Spacing ds of the fusion grid [m] (paper: s ∈ {0, ds, …, s_f}; the authors' code used ≈ 2 m)."""

HORIZON_M = 50.0
"""Grid end s_f [m]: the predictive estimate's foresight (Table I)."""

DEFAULT_GRID_M = np.arange(0.0, HORIZON_M + 0.5 * GRID_STEP_M, GRID_STEP_M)
"""Default fusion grid 0, 1, …, 50 m (51 points)."""
DEFAULT_GRID_M.setflags(write=False)

DEFAULT_S_LOCAL_M = 5.0
"""Reach s_l of the local estimate [m]: it replaces the predictive data at s < s_l.

The local estimate measures μ under the tires (s = 0); 5 m is about a quarter of a second at
20 m/s, short enough that the surface rarely changes within it, long enough that the fused μ̂ at
s ≈ 0 follows the accurate local value (docs/fusion.md)."""

LOCAL_MARGIN = 0.025
"""Worst-case local estimation error max|e_l| [-] (Table I)."""

LOCAL_GROUP = 0
"""Group label of the local estimate's points; class segments are labelled 1, 2, …"""


@dataclass(frozen=True)
class FusionDataBatch:
    """Fusion input data of ``B`` horizons on one grid, in the form :func:`fuse_batch` takes.

    Attributes
    ----------
    s_m
        Grid positions [m], shape ``(n,)``, shared by all horizons.
    mu
        Friction values [-], shape ``(B, n)``; NaN where a horizon has no datum at that point.
    margin
        95 % half-widths [-], shape ``(B, n)``; NaN where ``mu`` is NaN.
    groups
        Integer labels, shape ``(B, n)`` (as :class:`FusionData`; meaningless where ``mu`` is
        NaN).
    """

    s_m: np.ndarray
    mu: np.ndarray
    margin: np.ndarray
    groups: np.ndarray


def _runs(values: np.ndarray, margins: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Run index per grid point (last axis): a new run starts wherever (value, margin) changes or
    data stop."""
    start = np.ones(values.shape, dtype=bool)
    same = (
        valid[..., 1:]
        & valid[..., :-1]
        & (values[..., 1:] == values[..., :-1])
        & (margins[..., 1:] == margins[..., :-1])
    )
    start[..., 1:] = ~same
    return np.cumsum(start, axis=-1) - 1


def _check_inputs(
    s_grid_m: object,
    predictive_mu: object,
    predictive_margin: object,
    local_mu: np.ndarray,
    local_margin: float,
    s_local_m: float,
    mode: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The checks of :func:`assemble_inputs` (``predictive_*`` of shape ``(n,)`` or ``(B, n)``,
    ``local_mu`` with NaN where unavailable); returns the grid and the predictive arrays."""
    check_mode(mode)
    grid = np.asarray(s_grid_m, dtype=float)
    if grid.ndim != 1 or grid.size == 0:
        raise ValueError("s_grid_m must be a non-empty, one-dimensional array")
    check_range("s_grid_m", grid, POSITION_RANGE_M, " m")
    if (np.diff(grid) <= 0.0).any():
        raise ValueError("s_grid_m must be strictly increasing")
    pmu = np.asarray(predictive_mu, dtype=float)
    pmar = np.asarray(predictive_margin, dtype=float)
    shape = local_mu.shape + grid.shape
    if pmu.shape != shape:
        raise ValueError(f"predictive_mu must have shape {shape}, got {pmu.shape}")
    if pmar.shape != shape:
        raise ValueError(f"predictive_margin must have shape {shape}, got {pmar.shape}")
    if np.isinf(pmu).any():
        raise ValueError("predictive_mu must be finite or NaN (no data), got inf")
    valid = ~np.isnan(pmu)
    if valid.any():
        check_range("predictive_mu", pmu[valid], MU_RANGE)
        check_range("predictive_margin where predictive_mu is given", pmar[valid], MARGIN_RANGE)
    if not math.isfinite(float(s_local_m)):
        raise ValueError(f"s_local_m must be finite, got {s_local_m!r}")
    if np.isinf(local_mu).any():
        raise ValueError("local_mu must be finite (or absent), got inf")
    if not np.isnan(local_mu).all():
        check_range("local_mu", local_mu[~np.isnan(local_mu)], MU_RANGE)
    check_range("local_margin", np.array([float(local_margin)]), MARGIN_RANGE)
    return grid, pmu, pmar


def _assemble(
    grid: np.ndarray,
    pmu: np.ndarray,
    pmar: np.ndarray,
    local_mu: np.ndarray,
    local_margin: float,
    s_local_m: float,
    mode: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Paper Sec. III on validated ``(B, n)`` arrays: μ, margin, groups per grid point (NaN where
    there is no datum) and the mask of points with a datum."""
    valid = ~np.isnan(pmu)
    run = _runs(pmu, pmar, valid)
    use_local = ~np.isnan(local_mu)[:, None] & (grid < float(s_local_m))[None, :]
    if mode == "safe":
        # Stop at the first change of class (or of coverage) ahead of the vehicle.
        use_local &= run == run[:, :1]
    keep_pred = valid & ~use_local
    mu = np.where(use_local, local_mu[:, None], np.where(keep_pred, pmu, np.nan))
    margin = np.where(use_local, float(local_margin), np.where(keep_pred, pmar, np.nan))
    groups = np.where(use_local, LOCAL_GROUP, run + LOCAL_GROUP + 1).astype(np.int64)
    return mu, margin, groups, use_local | keep_pred


def assemble_inputs(
    s_grid_m: np.ndarray,
    predictive_mu: np.ndarray,
    predictive_margin: np.ndarray,
    *,
    local_mu: float | None = None,
    local_margin: float = LOCAL_MARGIN,
    s_local_m: float = DEFAULT_S_LOCAL_M,
    mode: FusionMode = "paper",
) -> FusionData:
    """Combine predictive class estimates and the local estimate into fusion data (Sec. III).

    Parameters
    ----------
    s_grid_m
        Increasing grid positions ahead of the vehicle [m], shape ``(n,)``; s = 0 is the vehicle.
    predictive_mu
        Class mean value per grid point [-], shape ``(n,)``; NaN where the camera has no data
        (e.g. beyond its 50 m foresight): such points are skipped.
    predictive_margin
        Class margin per grid point [-], ``>= 0`` where ``predictive_mu`` is finite.
    local_mu
        Local estimate [-], or None when it is unavailable (low tire utilization).
    local_margin
        Worst-case local error [-], ``>= 0`` (Table I: 0.025).
    s_local_m
        Reach s_l [m]: the local estimate replaces the predictive data at ``s < s_local_m``.
    mode
        ``"paper"``: as in the paper. ``"safe"``: the local estimate stops at the first change of
        predictive class (or of camera coverage) seen ahead, since it measures the surface under
        the tires; the points from that change on keep their predictive data.

    Returns
    -------
    FusionData
        Points sorted by s; ``LOCAL_GROUP`` for local points, one label per contiguous run of equal
        predictive (value, margin).

    Raises
    ------
    ValueError
        If the grid is not 1-D, within ``POSITION_RANGE_M`` and strictly increasing, lengths
        differ, a class value (where given) or ``local_mu`` is outside ``MU_RANGE`` = [0, 2], a
        margin (where the class value is given) or ``local_margin`` is outside ``MARGIN_RANGE``
        = [0, 1] or NaN, ``s_local_m`` is not finite, or ``mode`` is unknown.

    Examples
    --------
    >>> d = assemble_inputs([0.0, 1.0, 2.0], [0.5, 0.5, 0.8], [0.1, 0.1, 0.2],
    ...                     local_mu=0.42, s_local_m=1.5)
    >>> d.mu.tolist(), d.groups.tolist()
    ([0.42, 0.42, 0.8], [0, 0, 2])
    """
    if local_mu is not None and not math.isfinite(float(local_mu)):
        raise ValueError(f"local_mu must be finite or None, got {local_mu!r}")
    local = np.array(np.nan if local_mu is None else float(local_mu))
    grid, pmu, pmar = _check_inputs(
        s_grid_m, predictive_mu, predictive_margin, local, local_margin, s_local_m, mode
    )
    mu, margin, groups, present = _assemble(
        grid, pmu[None, :], pmar[None, :], local.reshape(1), local_margin, s_local_m, mode
    )
    p = present[0]
    # Every value was range-checked above: the data are built without a second check.
    return FusionData._trusted(grid[p], mu[0, p], margin[0, p], groups[0, p])


def assemble_inputs_batch(
    s_grid_m: np.ndarray,
    predictive_mu: np.ndarray,
    predictive_margin: np.ndarray,
    *,
    local_mu: np.ndarray,
    local_margin: float = LOCAL_MARGIN,
    s_local_m: float = DEFAULT_S_LOCAL_M,
    mode: FusionMode = "paper",
) -> FusionDataBatch:
    """:func:`assemble_inputs` for ``B`` horizons on one grid, vectorized.

    Parameters
    ----------
    s_grid_m
        As :func:`assemble_inputs`, shape ``(n,)``.
    predictive_mu, predictive_margin
        As :func:`assemble_inputs`, shape ``(B, n)``.
    local_mu
        Local estimate per horizon [-], shape ``(B,)``; NaN where it is unavailable.
    local_margin, s_local_m, mode
        As :func:`assemble_inputs`.

    Returns
    -------
    FusionDataBatch
        Row ``b``'s present points (``mu`` not NaN) are exactly ``assemble_inputs`` on row ``b``.

    Raises
    ------
    ValueError
        As :func:`assemble_inputs`, plus ``local_mu`` not of shape ``(B,)``.

    Examples
    --------
    >>> d = assemble_inputs_batch([0.0, 1.0], [[0.5, 0.8], [0.5, 0.8]], [[0.1, 0.2]] * 2,
    ...                           local_mu=[0.45, np.nan], s_local_m=0.5)
    >>> d.mu.tolist(), d.groups.tolist()
    ([[0.45, 0.8], [0.5, 0.8]], [[0, 2], [1, 2]])
    """
    local = np.asarray(local_mu, dtype=float)
    if local.ndim != 1:
        raise ValueError(f"local_mu must have shape (B,), got {local.shape}")
    grid, pmu, pmar = _check_inputs(
        s_grid_m, predictive_mu, predictive_margin, local, local_margin, s_local_m, mode
    )
    mu, margin, groups, _ = _assemble(grid, pmu, pmar, local, local_margin, s_local_m, mode)
    return FusionDataBatch(grid, mu, margin, groups)


def local_surface_bound(data: FusionData, s_eval_m: np.ndarray) -> np.ndarray:
    """What the local estimate guarantees of μ on the surface it measured, at ``s_eval_m`` [-].

    The local estimate measures μ under the tires; within its declared error ``m_l`` the surface
    there has ``μ ≥ μ_l − m_l`` (the largest such bound when it holds several points). The camera
    reports that surface's class up to its first change of class (or of coverage): the points
    labelled ``LOCAL_GROUP`` and the class segment labelled ``LOCAL_GROUP + 1`` (the segment the
    vehicle stands on, contiguous from s = 0 by construction). Over that stretch the bound is
    carried forward; beyond it, and everywhere when the data hold no local point or no group
    labels, the local estimate says nothing: ``+inf``.

    Not a bound the fusion guarantees ahead: the surface of one class can still change within it.
    It is the friction the measured surface supports within the local estimator's declared error,
    which is what a departure from the guaranteed μ̂ (lane recovery) may assume at most there.

    Examples
    --------
    >>> d = assemble_inputs([0.0, 1.0, 2.0, 3.0], [0.5, 0.5, 0.5, 0.8], [0.1, 0.1, 0.1, 0.2],
    ...                     local_mu=0.42, s_local_m=1.5, mode="safe")
    >>> local_surface_bound(d, np.array([0.0, 2.0, 2.5, 3.0])).round(3).tolist()
    [0.395, 0.395, inf, inf]
    """
    s_eval = np.asarray(s_eval_m, dtype=float)
    out = np.full(s_eval.shape, np.inf)
    if data.groups is None:
        return out
    local = data.groups == LOCAL_GROUP
    if not local.any():
        return out
    bound = float(np.max(data.mu[local] - data.margin[local]))
    surface = local | (data.groups == LOCAL_GROUP + 1)
    s_end = float(np.max(data.s_m[surface]))
    out[s_eval <= s_end + 1e-9] = bound
    return out


def declared_upper_bound(data: FusionData, s_eval_m: np.ndarray) -> np.ndarray:
    """The highest μ the estimates' declared errors allow, at ``s_eval_m`` [-].

    Each estimate ``(y, m)`` says ``μ ≤ y + m`` at its position when its error is within its
    declared margin (the other half of the hard bound ``μ ≥ y − m`` safe mode caps μ̂ with); at a
    position with several estimates the lowest such bound holds. Strictly between two data
    positions the larger of the two neighbours' bounds (the surface may change between them and
    neither estimate rules out the other's); outside the data nothing is declared: ``+inf``.

    What a departure from the guaranteed μ̂ (lane recovery) may assume at most: planning above it
    plans with a friction every estimate there declares impossible (docs/decisions/0061).

    Examples
    --------
    >>> d = FusionData([0.0, 1.0, 2.0], [0.9, 0.25, 0.25], [0.025, 0.15, 0.15])
    >>> declared_upper_bound(d, np.array([0.0, 0.5, 2.0, 3.0])).round(3).tolist()
    [0.925, 0.925, 0.4, inf]
    """
    return _lowest_declared(data.s_m, data.mu + data.margin, s_eval_m)


def declared_central_value(data: FusionData, s_eval_m: np.ndarray) -> np.ndarray:
    """The estimates' own values ``y`` (their most probable μ), at ``s_eval_m`` [-].

    :func:`declared_upper_bound` with ``y`` for ``y + m``: the lowest value at a position,
    the larger neighbour's strictly between two, ``+inf`` outside the data. What a departure from
    the guaranteed μ̂ may assume ahead of the surface the local estimate measured: every
    estimate there says the friction is most probably no higher (docs/decisions/0069).

    Examples
    --------
    >>> d = FusionData([0.0, 1.0, 2.0], [0.9, 0.25, 0.25], [0.025, 0.15, 0.15])
    >>> declared_central_value(d, np.array([0.0, 0.5, 2.0, 3.0])).round(3).tolist()
    [0.9, 0.9, 0.25, inf]
    """
    return _lowest_declared(data.s_m, data.mu, s_eval_m)


def _lowest_declared(s_m: np.ndarray, value: np.ndarray, s_eval_m: np.ndarray) -> np.ndarray:
    """Per position the lowest ``value``, between positions the larger neighbour's, outside
    ``+inf`` (the envelope of :func:`declared_upper_bound`)."""
    s_eval = np.asarray(s_eval_m, dtype=float)
    if s_m.size == 0:
        return np.full(s_eval.shape, np.inf)
    order = np.lexsort((value, s_m))  # by s, then the lowest value first
    s_sorted, v_sorted = s_m[order], value[order]
    first = np.ones(s_sorted.size, dtype=bool)
    first[1:] = np.diff(s_sorted) > SAME_S_TOL_M
    us, ub = s_sorted[first], v_sorted[first]
    left, right, at_left, at_right, outside = envelope_index(us, s_eval)
    bound = np.maximum(ub[left], ub[right])
    bound = np.where(at_right, ub[right], bound)
    bound = np.where(at_left, ub[left], bound)
    return np.where(outside, np.inf, bound)
