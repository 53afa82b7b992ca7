"""Shared friction reports as fusion input: ageing, position error, trust test, sender cap.

Reports (:class:`~mufusion.estimators.shared.FrictionReport`) from earlier vehicles or roadside
units are a third source beside the camera's classes and the local estimate
(docs/decisions/0060-shared-friction.md, docs/shared-friction.md). This module turns the
received reports into a validated :class:`ReportData` in the receiver's frame; the fusion with
them is :mod:`mufusion.fusion.shared_fusion`.

**Age.** Following the spatio-temporal GP view (Särkkä, Solin & Hartikainen 2013: a Matérn
kernel in time is a linear state-space process whose variance relaxes to the prior's between
observations), a report's variance grows with its age Δt towards the prior's::

    σ²(Δt) = σ²_report + σ²_prior · (1 − k(Δt)),

k the time kernel's correlation with scale τ (:func:`age_variance`): Matérn-3/2 by default (μ
changes at a finite rate, decision 0063), the Ornstein–Uhlenbeck Matérn-1/2 of decision 0060 as
an option (``SharedSettings.age_kernel``).

**Position error.** A report stands for μ at a position known to ± σ_s (1.96 σ_s at 95 %). Within
one surface segment μ changes by at most a declared G per metre (``gradient_bound_per_m``), so a
position error δs moves the μ it stands for by at most G·|δs|: the GP gets it as input noise,
``(G σ_s)²`` added to the variance, and the hard bound of safe mode subtracts ``G·(|s − s_r| +
1.96 σ_s)`` at an evaluation point s.

**Sender cap.** One sender's reports share its bias (a miscalibrated estimator, a constant
offset): the fusion gives each sender's reports one common error of variance ``σ_r² /
sender_cap`` besides their own, so that a sender counts at most as ``sender_cap`` independent
reports however many it sends and wherever (the paper posterior of both modes,
:func:`~mufusion.fusion.shared_fusion.sender_noise`, decision 0077; safe mode's grouped
posterior counts each sender as one). Sybil identities (one sender, many pseudonyms) defeat any
per-sender cap; the one-sided rule and the minimum in safe mode's hard bound do not depend on
counts (decision 0060).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.estimators.shared import (
    DEFAULT_SHARED,
    AgeKernel,
    FrictionReport,
    SharedSettings,
    check_in,
)
from mufusion.fusion.data import MARGIN_RANGE, NOISE_STD_FLOOR, POSITION_RANGE_M
from mufusion.fusion.prior import Z95, GPPrior


def age_variance(
    age_s: np.ndarray, prior_std: float, tau_s: float, kernel: AgeKernel = "matern32"
) -> np.ndarray:
    """Variance a report gains by its age [-²]: ``σ²_prior · (1 − k(Δt))``, k the time kernel's
    correlation at lag Δt with scale τ (decision 0063):

    * ``"matern32"``: ``k = (1 + √3 Δt/τ) · exp(−√3 Δt/τ)``, a once mean-square differentiable
      process (μ changes at a finite rate): the gain grows as ``1.5 σ² (Δt/τ)²`` at short ages;
    * ``"matern12"``: ``k = exp(−Δt/τ)``, the Ornstein–Uhlenbeck process of decision 0060: the
      gain grows as ``σ² Δt/τ``, as if μ diffused from second to second.

    Negative ages (a report stamped in the receiver's future: clock skew) count as 0.

    Examples
    --------
    >>> round(float(age_variance(np.array([1e9]), 0.2, 600.0)[0]), 6)
    0.04
    >>> a = np.array([10.0])
    >>> bool(age_variance(a, 0.2, 1800.0) < age_variance(a, 0.2, 1800.0, "matern12"))
    True
    """
    age = np.maximum(np.asarray(age_s, dtype=float), 0.0)
    if kernel == "matern12":
        return prior_std * prior_std * -np.expm1(-age / tau_s)
    r = np.sqrt(3.0) * age / tau_s
    # 1 − (1 + r) e^(−r) = −expm1(−r) − r e^(−r), without cancellation at small r.
    return prior_std * prior_std * (-np.expm1(-r) - r * np.exp(-r))


@dataclass(frozen=True)
class ReportData:
    """Received reports in the receiver's frame, validated, aged and ready for the fusion.

    Attributes
    ----------
    s_m
        Report positions ahead of the vehicle [m], shape ``(n,)``.
    mu
        Most probable μ [-], shape ``(n,)``.
    noise_sd
        GP noise std [-]: own noise, age, position error (``G σ_s``) and the sender cap.
    lower, upper
        Aged lower and upper bounds on μ at the report's position [-] (no position term).
    lower_sd, upper_sd
        The sender's own 95 % half-widths below and above ``mu`` divided by 1.96 [-] (not aged).
    position_bound_m
        95 % position error 1.96 σ_s [m].
    sender
        Integer sender label per report (0, 1, … in order of first appearance).
    age_s
        Age at the receiver's time [s].
    settings
        The :class:`SharedSettings` they were prepared with.
    """

    s_m: np.ndarray
    mu: np.ndarray
    noise_sd: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    lower_sd: np.ndarray
    upper_sd: np.ndarray
    position_bound_m: np.ndarray
    sender: np.ndarray
    age_s: np.ndarray
    settings: SharedSettings

    @property
    def size(self) -> int:
        """Number of reports."""
        return int(self.s_m.size)

    @property
    def margin(self) -> np.ndarray:
        """The 95 % half-width the GP uses, ``1.96 · noise_sd`` [-]."""
        return Z95 * self.noise_sd

    def subset(self, keep: np.ndarray) -> ReportData:
        """The reports where ``keep`` is True (same settings)."""
        return ReportData(
            self.s_m[keep], self.mu[keep], self.noise_sd[keep], self.lower[keep],
            self.upper[keep], self.lower_sd[keep], self.upper_sd[keep],
            self.position_bound_m[keep], self.sender[keep], self.age_s[keep], self.settings,
        )


def report_data(
    reports: Sequence[FrictionReport],
    *,
    t_now_s: float,
    s_ego_m: float,
    prior: GPPrior,
    settings: SharedSettings = DEFAULT_SHARED,
    window_m: tuple[float, float] = (-10.0, 60.0),
) -> ReportData:
    """The reports that matter now, in the receiver's frame (positions relative to ``s_ego_m``).

    Dropped: reports older than ``settings.validity_s`` and those outside ``window_m`` (relative
    positions [m], e.g. the fusion grid with some slack). The GP std of each kept report is
    ``sqrt((margin/1.96)² + σ²_prior (1 − k(Δt)) + (G σ_s)²)`` (k the time kernel), floored at
    ``NOISE_STD_FLOOR`` and capped at ``MARGIN_RANGE[1] / 1.96``.

    Raises
    ------
    ValueError
        If ``t_now_s`` or ``s_ego_m`` is not finite, ``s_ego_m`` is outside ``POSITION_RANGE_M``,
        an element of ``reports`` is not a :class:`FrictionReport`, or ``window_m`` is not an
        increasing pair.

    Examples
    --------
    >>> from mufusion.fusion import PAPER_PRIOR
    >>> r = FrictionReport.numeric(112.0, 0.5, 0.025, t_created_s=0.0)
    >>> d = report_data([r], t_now_s=60.0, s_ego_m=100.0, prior=PAPER_PRIOR)
    >>> d.s_m.tolist(), bool(d.margin[0] > 0.025)
    ([12.0], True)
    """
    check_in("t_now_s", t_now_s, -1e12, 1e12, " s")
    check_in("s_ego_m", s_ego_m, *POSITION_RANGE_M, " m")
    lo_w, hi_w = (float(w) for w in window_m)
    if not lo_w < hi_w:
        raise ValueError(f"window_m must be an increasing pair, got {window_m!r}")
    for r in reports:
        if not isinstance(r, FrictionReport):
            raise ValueError(f"reports must hold FrictionReport records, got {type(r).__name__}")
    rel = np.array([r.s_m for r in reports], dtype=float) - float(s_ego_m)
    age = float(t_now_s) - np.array([r.t_created_s for r in reports], dtype=float)
    keep = (age <= settings.validity_s) & (rel >= lo_w) & (rel <= hi_w)
    kept = [r for r, k in zip(reports, keep, strict=True) if k]
    rel, age = rel[keep], age[keep]
    mu = np.array([r.mu for r in kept], dtype=float)
    own_lower = np.array([r.lower_mu for r in kept], dtype=float)
    own_upper = np.array([r.upper_mu for r in kept], dtype=float)
    margin = np.array([r.margin for r in kept], dtype=float)
    pos_sd = np.array([r.position_std_m for r in kept], dtype=float)
    ids: dict[str, int] = {}
    sender = np.array([ids.setdefault(r.sender, len(ids)) for r in kept], dtype=np.int64)
    aged = age_variance(age, prior.std, settings.tau_s, settings.age_kernel)
    own_sd = margin / Z95
    g_pos = settings.gradient_bound_per_m * pos_sd
    var = own_sd * own_sd + aged + g_pos * g_pos
    noise_sd = np.clip(np.sqrt(var), NOISE_STD_FLOOR, MARGIN_RANGE[1] / Z95)
    # Each side ages like the whole report: mu ∓ 1.96 sqrt(((mu − bound)/1.96)² + σ²_age).
    low_sd = (mu - own_lower) / Z95
    up_sd = (own_upper - mu) / Z95
    lower = mu - Z95 * np.sqrt(low_sd * low_sd + aged)
    upper = mu + Z95 * np.sqrt(up_sd * up_sd + aged)
    return ReportData(
        rel, mu, noise_sd, lower, upper, low_sd, up_sd, Z95 * pos_sd, sender, age, settings
    )
