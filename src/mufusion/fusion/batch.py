"""The batch API: :func:`fuse_batch` fuses ``B`` horizons at once (fleet, campaign, calibration).

Validation happens once here for the whole batch; each horizon then goes through the same
validated core as :func:`~mufusion.fusion.fuse` (or, in paper mode on shared positions, through
one vectorized pass of the posterior engine).
"""

from __future__ import annotations

import math

import numpy as np

from mufusion.fusion.core import DEFAULT_ENGINE, fuse_validated
from mufusion.fusion.data import (
    MARGIN_RANGE,
    MU_RANGE,
    POSITION_RANGE_M,
    FusedEstimate,
    FusionData,
    FusionMode,
    check_groups,
    check_mode,
    check_positions,
    check_range,
    clip_to_band,
)
from mufusion.fusion.engine import feature_noise_floor, noise_sd_of
from mufusion.fusion.prior import Z95, GPPrior, check_prior
from mufusion.fusion.safe import (
    SAME_S_TOL_M,
    SHARED_ERROR_FRACTION,
    envelope_bound,
    envelope_index,
)


def fuse_batch(
    s_m: np.ndarray,
    mu: np.ndarray,
    margin: np.ndarray,
    prior: GPPrior,
    s_eval_m: np.ndarray,
    *,
    groups: np.ndarray | None = None,
    mode: FusionMode = "paper",
) -> FusedEstimate:
    """:func:`~mufusion.fusion.fuse` for ``B`` horizons at once.

    Parameters
    ----------
    s_m
        Data positions [m], shape ``(n,)`` shared by all horizons or ``(B, n)``.
    mu
        Friction values [-], shape ``(B, n)``, within ``MU_RANGE`` = [0, 2]. NaN marks an absent
        point, so horizons with different numbers of data points share one array (the point is
        decoupled exactly: its precision is 0).
    margin
        95 % half-widths [-], within ``MARGIN_RANGE`` = [0, 1], shape ``(n,)`` or ``(B, n)``;
        ignored where ``mu`` is NaN.
    prior, s_eval_m, mode
        As in :func:`~mufusion.fusion.fuse`; ``s_eval_m`` is shared, shape ``(m,)``.
    groups
        Optional integer labels, shape ``(n,)`` or ``(B, n)``.

    Returns
    -------
    FusedEstimate
        ``s_m`` of shape ``(m,)``; ``mean``, ``std``, ``lower``, ``mu_hat`` of shape ``(B, m)``.
        Row ``b`` equals ``fuse`` on row ``b``'s present points: to rounding (≈ 1e-13 with the
        estimators' margins) on shared positions, where paper mode runs all horizons in one
        vectorized pass and safe mode the horizons with every point present (strictly
        increasing positions, groups few enough for the feature path); bit for bit for the
        other horizons, which run one by one.

    Raises
    ------
    ValueError
        As :func:`~mufusion.fusion.fuse`, plus shapes that do not broadcast to ``(B, n)``.

    Examples
    --------
    >>> from mufusion.fusion import PAPER_PRIOR
    >>> est = fuse_batch([0.0, 10.0], [[0.4, 0.5], [0.8, np.nan]], [0.025, 0.1],
    ...                  PAPER_PRIOR, [0.0, 10.0])
    >>> est.mu_hat.shape
    (2, 2)
    """
    prior = check_prior(prior)
    mode = check_mode(mode)
    y = np.asarray(mu, dtype=float)
    if y.ndim != 2:
        raise ValueError(f"mu must have shape (B, n), got {y.shape}")
    b, n = y.shape
    if b == 0:
        raise ValueError("mu must hold at least one horizon (B >= 1)")
    if np.isinf(y).any():
        raise ValueError("mu must be finite or NaN (absent point), got inf")
    present = ~np.isnan(y)

    def _broadcast(name: str, value: object) -> np.ndarray:
        arr = np.asarray(value, dtype=float)
        if arr.shape not in ((n,), (b, n)):
            raise ValueError(f"{name} must have shape ({n},) or ({b}, {n}), got {arr.shape}")
        return np.broadcast_to(arr, (b, n))

    s = _broadcast("s_m", s_m)
    m = _broadcast("margin", margin)
    if n:
        check_range("s_m", s, POSITION_RANGE_M, " m")
    if present.any():
        check_range("mu", y[present], MU_RANGE)
        check_range("margin where mu is given", m[present], MARGIN_RANGE)
    e = check_positions("s_eval_m", s_eval_m)
    grp = None
    if groups is not None:
        graw = np.asarray(groups)
        if graw.shape not in ((n,), (b, n)):
            raise ValueError(f"groups must have shape ({n},) or ({b}, {n}), got {graw.shape}")
        grp = np.broadcast_to(check_groups(graw, graw.shape), (b, n))
    mu_max = np.where(present, y, 0.0).max(axis=1) if n else np.zeros(b)
    top = np.maximum(prior.upper, mu_max)

    out = [np.empty((b, e.size)) for _ in range(4)]  # mean, std, lower, mu_hat
    todo = np.ones(b, dtype=bool)
    if np.ndim(s_m) == 1 and n > 0:
        vectorized = _paper_rows if mode == "paper" else _safe_rows
        todo = vectorized(prior, s[0], e, y, m, grp, present, top, out)
    # The rest (per-horizon positions, safe rows with absent points, many groups or tiny
    # margins): horizon by horizon through the validated core, exactly as fuse.
    for i in np.flatnonzero(todo):
        p = present[i]
        data = FusionData._trusted(
            s[i][p], y[i][p], m[i][p], None if grp is None else grp[i][p], read_only=False
        )
        row = fuse_validated(DEFAULT_ENGINE, prior, data, e, mode)
        for arr, value in zip(out, (row.mean, row.std, row.lower, row.mu_hat), strict=True):
            arr[i] = value
    return FusedEstimate(e, *out)


def _paper_rows(prior, s, e, y, m, grp, present, top, out) -> np.ndarray:
    """Paper mode on shared positions, every horizon in one pass; returns the rows left to do."""
    sd = noise_sd_of(np.where(present, m, 1.0))
    resid = np.where(present, y - prior.mean, 0.0)
    post = DEFAULT_ENGINE.latent_batch(prior, s, e, resid, np.where(present, 1.0 / (sd * sd), 0.0))
    if post is None:
        return np.ones(y.shape[0], dtype=bool)
    mean, std, lower, mu_hat = out
    mean[:] = prior.mean + post[0]
    std[:] = post[1]
    lower[:] = mean - Z95 * std
    mu_hat[:] = clip_to_band(lower, top[:, None])
    return np.zeros(y.shape[0], dtype=bool)


def _safe_rows(prior, s, e, y, m, grp, present, top, out) -> np.ndarray:
    """Safe mode on shared, strictly increasing positions for the horizons with every point
    present and few enough groups for the feature path (see safe.safe_estimate, which this
    vectorizes); returns the rows left to do."""
    b, n = y.shape
    todo = ~present.all(axis=1)
    if todo.all() or not (np.diff(s) > SAME_S_TOL_M).all():
        return np.ones(b, dtype=bool)
    rows = np.flatnonzero(~todo)
    yb, mb = y[rows], m[rows]
    sd = noise_sd_of(mb)
    resid = yb - prior.mean
    paper = DEFAULT_ENGINE.latent_batch(prior, s, e, resid, 1.0 / (sd * sd))
    if paper is None:
        return np.ones(b, dtype=bool)
    p_mean = prior.mean + paper[0]
    p_lower = p_mean - Z95 * paper[1]
    g_mean, g_std, g_lower = p_mean.copy(), paper[1].copy(), p_lower.copy()
    if grp is not None:
        # Dense labels 0, 1, … per row (np.unique row by row, vectorized).
        order = np.argsort(grp[rows], axis=1, kind="stable")
        ranked = np.take_along_axis(grp[rows], order, axis=1)
        dense = np.zeros(ranked.shape, dtype=np.int64)
        np.cumsum(ranked[:, 1:] != ranked[:, :-1], axis=1, out=dense[:, 1:])
        label = np.empty_like(dense)
        np.put_along_axis(label, order, dense, axis=1)
        n_groups = dense[:, -1] + 1
        indep = math.sqrt(1.0 - SHARED_ERROR_FRACTION) * sd
        shared_rows = n_groups < n  # all groups of one point: the paper posterior (as fuse)
        fast = (2 * n_groups <= n) & (indep.min(axis=1) >= feature_noise_floor(prior))
        todo[rows[shared_rows & ~fast]] = True
        sel = np.flatnonzero(shared_rows & fast)
        if sel.size:
            loadings = np.zeros((sel.size, n, int(n_groups[sel].max())))
            rr, ii = np.meshgrid(np.arange(sel.size), np.arange(n), indexing="ij")
            loadings[rr, ii, label[sel]] = math.sqrt(SHARED_ERROR_FRACTION) * sd[sel]
            post = DEFAULT_ENGINE.latent_batch(
                prior, s, e, resid[sel], 1.0 / (indep[sel] ** 2), loadings
            )
            if post is None:
                todo[rows[sel]] = True
            else:
                g_mean[sel] = prior.mean + post[0]
                g_std[sel] = post[1]
                g_lower[sel] = g_mean[sel] - Z95 * post[1]
    where = envelope_index(s, e)
    mu_hat = np.minimum(p_lower, envelope_bound(yb - mb, where))
    mu_hat = np.where(where[4], np.minimum(mu_hat, g_lower), mu_hat)
    done = ~todo[rows]
    for arr, value in zip(
        out, (g_mean, g_std, g_lower, clip_to_band(mu_hat, top[rows, None])), strict=True
    ):
        arr[rows[done]] = value[done]
    return todo
