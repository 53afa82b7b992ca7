"""Calibration with shared reports (issue 40): over-estimate rate and lower-bound coverage as
functions of the reports' age and of the share of wrong reports, both modes, no closed loop.

On the horizons of :func:`~mufusion.fusion.calibration.draw_horizons` (class layouts, camera and
local errors within their margins), each horizon also receives ``REPORTS_PER_HORIZON`` reports
from ``SENDERS`` earlier vehicles: true positions uniform over the grid's points, reported within
± 1.96 σ_s of them, μ within the slip estimator's ± 0.025 of the μ *at creation*. The surface
has since become slipperier, never grippier (the harmful direction): μ at creation = μ_gt now +
σ_age |z|, z standard normal, σ_age² = σ²_prior (1 − e^(−Δt/τ)), the ageing model's own scale,
one-sided. Then a share w of the reports is made wrong, w of each kind
(:class:`~mufusion.estimators.misbehaviour.WrongReports`: offset senders, restamped replays,
Sybil copies; +0.2 / +0.3 optimistic), and everything is fused with
:func:`~mufusion.fusion.fuse` in both modes.

Measured per (age, wrong share) and mode over all grid points: the rate of μ̂ > μ_gt, the
coverage of the posterior lower bound (μ_gt ≥ mean − 1.96 std), and the mean μ̂ (what the reports
buy), next to the same horizons without reports.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from mufusion.estimators import LOCAL_MAX_ERROR
from mufusion.estimators.misbehaviour import WrongReports, corrupt
from mufusion.estimators.shared import DEFAULT_SHARED, FrictionReport, SharedSettings
from mufusion.fusion.assembly import assemble_inputs
from mufusion.fusion.calibration import draw_horizons
from mufusion.fusion.core import fuse
from mufusion.fusion.data import FusionMode
from mufusion.fusion.prior import PAPER_PRIOR
from mufusion.fusion.reports import age_variance, report_data

REPORTS_PER_HORIZON = 25
"""Reports each horizon receives (one every 2 m on the 50 m grid, as a 5 Hz link at 10 m/s)."""
SENDERS = 5
"""Earlier vehicles the reports come from."""
POSITION_STD_M = 0.5
"""Position error of the reports along s [m] (the fleet's default)."""
DEFAULT_AGES_S = (0.0, 10.0, 60.0, 600.0, 1800.0, 7200.0)
"""Report ages calibrated on by default [s] (0 to 4 τ with the default τ = 1800 s)."""
DEFAULT_WRONG_SHARES = (0.0, 0.2)
"""Shares of wrong reports of each kind calibrated on by default [-]."""


@dataclass(frozen=True)
class SharedCell:
    """One (age, wrong share, mode) cell of the calibration."""

    age_s: float
    wrong_share: float
    mode: str
    over_estimate_rate: float
    """Share of grid points with μ̂ > μ_gt, with the reports."""
    lower_coverage: float
    """Share of grid points with μ_gt ≥ posterior lower bound, with the reports."""
    mean_mu_hat: float
    """Mean μ̂ with the reports [-]."""
    mean_mu_hat_without: float
    """Mean μ̂ on the same horizons without reports [-]."""
    over_estimate_rate_without: float
    points: int


def _reports(
    rng: np.random.Generator, s: np.ndarray, mu_gt: np.ndarray, age_s: float, sigma_age: float
) -> list[FrictionReport]:
    idx = rng.integers(0, s.size, REPORTS_PER_HORIZON)
    sender = rng.integers(0, SENDERS, REPORTS_PER_HORIZON)
    pos = s[idx] + rng.uniform(-1.0, 1.0, REPORTS_PER_HORIZON) * 1.96 * POSITION_STD_M
    then = mu_gt[idx] + sigma_age * np.abs(rng.standard_normal(REPORTS_PER_HORIZON))
    mu = np.clip(then + rng.uniform(-1.0, 1.0, REPORTS_PER_HORIZON) * LOCAL_MAX_ERROR, 0.0, 2.0)
    return [
        FrictionReport.numeric(float(p), float(m), LOCAL_MAX_ERROR, t_created_s=-age_s,
                               position_std_m=POSITION_STD_M, sender=f"v{k}")
        for p, m, k in zip(pos, mu, sender, strict=True)
    ]


def calibrate_shared(
    rng: np.random.Generator,
    n_horizons: int = 300,
    *,
    ages_s: Sequence[float] = DEFAULT_AGES_S,
    wrong_shares: Sequence[float] = DEFAULT_WRONG_SHARES,
    settings: SharedSettings = DEFAULT_SHARED,
    offset: float = WrongReports().offset,
) -> list[SharedCell]:
    """The calibration of the module docstring: one cell per (age, wrong share, mode);
    ``offset`` is how optimistic the offset senders and Sybil copies are.

    Raises
    ------
    ValueError
        If ``rng`` is not a Generator, ``n_horizons`` not an integer >= 1, an age is negative
        or a share is outside [0, 1] (the message names it).

    Examples
    --------
    >>> cells = calibrate_shared(np.random.default_rng(0), 3, ages_s=[0.0], wrong_shares=[0.0])
    >>> [c.mode for c in cells], cells[1].over_estimate_rate
    (['paper', 'safe'], 0.0)
    """
    horizons = draw_horizons(rng, n_horizons)
    for age in ages_s:
        if not float(age) >= 0.0:
            raise ValueError(f"ages_s must be >= 0 s, got {age!r}")
    s = horizons.s_ahead_m
    n = horizons.mu_gt.shape[0]
    modes: tuple[FusionMode, ...] = ("paper", "safe")
    own = {mode: [assemble_inputs(
        s, horizons.camera_mu[b], horizons.camera_margin[b],
        local_mu=None if np.isnan(horizons.local_mu[b]) else float(horizons.local_mu[b]),
        mode=mode) for b in range(n)] for mode in modes}
    base = {mode: np.array([
        fuse(d.s_m, d.mu, d.margin, PAPER_PRIOR, s, groups=d.groups, mode=mode).mu_hat
        for d in own[mode]]) for mode in own}
    cells = []
    for age in ages_s:
        sigma_age = float(np.sqrt(age_variance(np.array([age]), PAPER_PRIOR.std,
                                               settings.tau_s, settings.age_kernel)[0]))
        for share in wrong_shares:
            wrong = WrongReports(offset_share=share, replay_share=share, sybil_share=share,
                                 offset=offset)
            sent = [corrupt(_reports(rng, s, horizons.mu_gt[b], age, sigma_age), wrong, rng)
                    for b in range(n)]
            for mode in modes:
                hat = np.empty_like(horizons.mu_gt)
                lower = np.empty_like(horizons.mu_gt)
                for b, d in enumerate(own[mode]):
                    rd = report_data(sent[b], t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                                     settings=settings)
                    est = fuse(d.s_m, d.mu, d.margin, PAPER_PRIOR, s, groups=d.groups,
                               mode=mode, reports=rd)
                    hat[b], lower[b] = est.mu_hat, est.lower
                gt = horizons.mu_gt
                cells.append(SharedCell(
                    float(age), float(share), mode,
                    float(np.mean(hat > gt + 1e-12)), float(np.mean(gt >= lower)),
                    float(hat.mean()), float(base[mode].mean()),
                    float(np.mean(base[mode] > gt + 1e-12)), int(gt.size)))
    return cells


def cells_to_dicts(cells: Sequence[SharedCell]) -> list[dict]:
    """The cells as JSON-ready dicts."""
    return [asdict(c) for c in cells]
