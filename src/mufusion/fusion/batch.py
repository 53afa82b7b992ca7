"""The batch API: :func:`fuse_batch` fuses ``B`` horizons at once (fleet, campaign, calibration).

Validation happens once here for the whole batch; each horizon then goes through the same
validated core as :func:`~mufusion.fusion.fuse` (or, in paper mode on shared positions, through
one vectorized pass of the posterior engine).
"""

from __future__ import annotations

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
from mufusion.fusion.engine import noise_sd_of
from mufusion.fusion.prior import Z95, GPPrior, check_prior


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
        Row ``b`` equals ``fuse`` on row ``b``'s present points: bit for bit in safe mode or with
        per-horizon positions (these run horizon by horizon); to rounding (≈ 1e-13 with the
        estimators' margins) in paper mode on shared positions, which runs all horizons in one
        vectorized pass.

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

    if mode == "paper" and np.ndim(s_m) == 1 and n > 0:
        sd = noise_sd_of(np.where(present, m, 1.0))
        precision = np.where(present, 1.0 / (sd * sd), 0.0)
        resid = np.where(present, y - prior.mean, 0.0)
        out = DEFAULT_ENGINE.latent_batch(prior, s[0], e, resid, precision)
        if out is not None:
            mean = prior.mean + out[0]
            lower = mean - Z95 * out[1]
            return FusedEstimate(e, mean, out[1], lower, clip_to_band(lower, top[:, None]))
    # Safe mode or per-horizon positions: horizon by horizon through the validated core.
    rows = []
    for i in range(b):
        p = present[i]
        data = FusionData._trusted(
            s[i][p], y[i][p], m[i][p], None if grp is None else grp[i][p], read_only=False
        )
        rows.append(fuse_validated(DEFAULT_ENGINE, prior, data, e, mode))
    return FusedEstimate(
        e,
        np.stack([r.mean for r in rows]),
        np.stack([r.std for r in rows]),
        np.stack([r.lower for r in rows]),
        np.stack([r.mu_hat for r in rows]),
    )
