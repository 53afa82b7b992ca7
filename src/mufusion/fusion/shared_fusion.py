"""Fusion with shared reports as a third source, in both modes (decision 0060).

Given the vehicle's own data (camera classes, local estimate: a :class:`FusionData`) and the
received reports (:class:`~mufusion.fusion.reports.ReportData`):

1. **Trust test** (:func:`screen_reports`). The vehicle's own prediction at a report is its
   nearest own datum (y_o ± m_o). A report is *optimistic beyond the combined bounds* when its
   aged lower bound, moved to that datum, exceeds the own upper bound:
   ``lower_r − G·(δ_r + |s_r − s_o|) > y_o + m_o``; it is rejected. A report *below* the own
   estimate is kept whatever its size: it can only lower μ̂ (black ice the camera cannot see).
2. **Confirmation.** A kept report *confirms at* an evaluation point s when an own datum lies
   within ``reach_m + δ_r`` of the report, ``|s − s_r| ≤ reach_m + δ_r``, and the own data from
   the last one at or before ``min(s, s_r − δ_r)`` to the first one at or after ``max(s, s_r +
   δ_r)`` all carry one segment label (the camera saw no change of class over the stretch; the
   local estimate counts with the class segment it stands on).
3. **One-sided rule.** Let L⁺ be the lower bound of the GP with own data and kept reports, L⁻ the
   one with own data only, and L⁺_c the one with own data and the kept reports an own datum lies
   near (the confirmers). μ̂ uses ``min(L⁺, L⁺_c)`` where some report confirms, and
   ``min(L⁺, L⁻)`` elsewhere: a report that no own estimate confirms (none near it, or on the
   other side of a class change) never raises μ̂, neither where it lies nor through the
   posterior it shares with the points others confirm (decision 0076: reports behind the
   vehicle, where it has no datum, lifted the band ahead), and an old high-μ report, whose aged
   lower bound drops towards the prior's, raises it only as far as its own aged bound allows
   (step 4) in safe mode.
4. **Safe mode's hard bound with reports.** ``H(s) = max(H_own(s), H_rep(s))``. With
   ``report_bound = "consistent"`` (decision 0063, the default), ``H_rep(s)`` is the k-th
   highest (``corroboration``, default 1) over senders of each sender's best
   ``lower_c(Δt) − G·(|s − s_c| + δ_c)``, c over the reports an own datum confirms in s's class
   segment (at any distance: the position term prices it) that conflict with no report of that
   segment or of the road the own data do not cover (behind the vehicle, beyond the camera; no
   class change is known there, decision 0078) (:func:`conflicts`: c's lower bound, moved to the
   other report's place and creation time, above its upper bound). Under the premise each term
   is ≤ μ(s); a wrong report that survives lifts H by at most the interval of the honest
   report nearest s, ``2 m_h + 2 G·(|s − s_h| + δ_h)``, however many identities send it. With
   ``"lowest"`` (decision 0060), where a report confirms at s, ``H_rep(s) = min_r lower_r(Δt) −
   min_c G·(|s − s_c| + δ_c)``, r over the kept reports near s or in its segment: no optimistic
   report lifts it while one honest report is near, but every honest report counts at its
   worst. μ̂ = min(one-sided paper lower bound, H) on the data, and also at most the one-sided
   grouped lower bound beyond them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.fusion.assembly import LOCAL_GROUP
from mufusion.fusion.data import FusedEstimate, FusionData, clip_to_band
from mufusion.fusion.engine import PosteriorEngine, noise_sd_of
from mufusion.fusion.prior import Z95, GPPrior
from mufusion.fusion.reports import ReportData, age_variance
from mufusion.fusion.safe import SHARED_ERROR_FRACTION, grouped_noise, hard_bound_envelope


@dataclass(frozen=True)
class ReportScreen:
    """The outcome of the trust test for each report.

    Attributes
    ----------
    kept
        Passed the trust test (or it is off), shape ``(n,)``.
    rejected
        Optimistic beyond the combined bounds of the own estimate (``~kept`` when the test is on).
    near_own
        An own datum lies within ``reach_m + δ_r`` of the report.
    """

    kept: np.ndarray
    rejected: np.ndarray
    near_own: np.ndarray


def _nearest(sorted_s: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Index into ``sorted_s`` of the nearest element to each ``x``."""
    idx = np.clip(np.searchsorted(sorted_s, x), 1, max(sorted_s.size - 1, 1))
    left = np.maximum(idx - 1, 0)
    right = np.minimum(idx, sorted_s.size - 1)
    return np.where(np.abs(x - sorted_s[left]) <= np.abs(sorted_s[right] - x), left, right)


def _own_sorted(own: FusionData) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Own data sorted by s: positions, μ, margin and segment labels (the local estimate counted
    with the class segment it stands on; every datum its own segment without labels)."""
    order = np.argsort(own.s_m, kind="stable")
    if own.groups is None:
        seg = np.arange(own.s_m.size, dtype=np.int64)
    else:
        seg = np.where(own.groups == LOCAL_GROUP, LOCAL_GROUP + 1, own.groups)[order]
    return own.s_m[order], own.mu[order], own.margin[order], seg


def screen_reports(own: FusionData, reports: ReportData) -> ReportScreen:
    """The trust test against the vehicle's own estimate (module docstring, step 1).

    Examples
    --------
    >>> from mufusion.fusion import PAPER_PRIOR
    >>> from mufusion.estimators.shared import FrictionReport
    >>> from mufusion.fusion.reports import report_data
    >>> own = FusionData([0.0, 10.0], [0.5, 0.5], [0.1, 0.1])
    >>> rs = [FrictionReport.numeric(10.0, 0.55, 0.025), FrictionReport.numeric(10.0, 0.9, 0.025)]
    >>> d = report_data(rs, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    >>> screen_reports(own, d).kept.tolist()
    [True, False]
    """
    n = reports.size
    if own.s_m.size == 0 or n == 0:
        none = np.zeros(n, dtype=bool)
        return ReportScreen(~none, none, none)
    s_o, mu_o, m_o, _ = _own_sorted(own)
    near_i = _nearest(s_o, reports.s_m)
    dist = np.abs(reports.s_m - s_o[near_i])
    g = reports.settings.gradient_bound_per_m
    near = dist <= reports.settings.reach_m + reports.position_bound_m
    at_own = reports.lower - g * (reports.position_bound_m + dist)
    rejected = near & (at_own > mu_o[near_i] + m_o[near_i])
    if not reports.settings.trust_test:
        rejected = np.zeros(n, dtype=bool)
    return ReportScreen(~rejected, rejected, near)


def _report_bound(
    own: FusionData, r: ReportData, confirmers: np.ndarray, e: np.ndarray, prior_std: float
) -> tuple[np.ndarray, np.ndarray]:
    """``H_rep`` at ``e`` and where some report confirms (module docstring, steps 2 and 4;
    ``prior_std`` ages the reports towards each other's creation time)."""
    g = r.settings.gradient_bound_per_m
    dist = np.abs(e[:, None] - r.s_m[None, :])  # (m, n)
    within = dist <= r.settings.reach_m + r.position_bound_m[None, :]
    s_o, _, _, seg = _own_sorted(own)
    # One class segment from the last own datum at or before min(s, s_r − δ_r) to the first at or
    # after max(s, s_r + δ_r): the camera saw no change of class in between (a change may lie
    # anywhere between two data, so the bracketing data must agree, not the nearest ones).
    changes = np.concatenate([[0], np.cumsum(seg[1:] != seg[:-1])])
    lo = np.minimum(e[:, None], (r.s_m - r.position_bound_m)[None, :])
    hi = np.maximum(e[:, None], (r.s_m + r.position_bound_m)[None, :])
    inside = (lo >= s_o[0] - 1e-9) & (hi <= s_o[-1] + 1e-9)
    i0 = np.clip(np.searchsorted(s_o, lo + 1e-9, side="right") - 1, 0, s_o.size - 1)
    i1 = np.clip(np.searchsorted(s_o, hi - 1e-9, side="left"), 0, s_o.size - 1)
    no_change_seen = changes[i1] == changes[i0]  # also where the stretch leaves the own data
    one_segment = inside & no_change_seen
    confirms = within & confirmers[None, :] & one_segment
    confirmed = confirms.any(axis=1)
    term = g * (dist + r.position_bound_m[None, :])  # position term of each report at each s
    if r.settings.report_bound == "lowest":
        # The lowest bound of every kept report near s or in its class segment, less the
        # smallest position term of a *confirming* report c: ≤ lower_c − G·(|s − s_c| + δ_c) ≤
        # μ(s) under the premise (decision 0060); no report, nor any number of identities,
        # lifts it above the lowest report of the segment.
        lowest = np.where(within | one_segment, r.lower[None, :], np.inf).min(axis=1)
        shift = np.where(confirms, term, np.inf).min(axis=1)
        return np.where(confirmed, lowest - np.where(confirmed, shift, 0.0), -np.inf), confirmed
    # "consistent" (decision 0063): a report in conflict with another one of s's segment (its
    # lower bound, moved to the other's place and time, above the other's upper bound) is left
    # out — the two cannot both be right, and the higher one is the harmful one if wrong. Of the
    # rest, the highest lower bound aged to now and moved to s: ≤ μ(s) for an honest report; a
    # wrong one that survives is within one honest report's own interval of it.
    # Every report an own datum confirms in s's segment counts, however far: its position term
    # prices the distance, and a cut-off at the reach would leave a hole at the class bound
    # wherever one packet is lost or one report is left out.
    w, h = conflict_pairs(r, prior_std)
    # The report that conflicts may lie where the own data do not reach (behind the vehicle,
    # beyond the camera): no class change is known there, and leaving a report out only lowers
    # H, so it counts unless the camera saw a change between it and s (decision 0078).
    excluded = np.zeros_like(one_segment)
    if w.size:
        # excluded[s, w] = any over the pairs (w, h) of no_change_seen[s, h]: grouped by w.
        order = np.argsort(w, kind="stable")
        w, h = w[order], h[order]
        starts = np.flatnonzero(np.concatenate([[True], w[1:] != w[:-1]]))
        excluded[:, w[starts]] = np.logical_or.reduceat(no_change_seen[:, h], starts, axis=1)
    agree = confirmers[None, :] & one_segment & ~excluded
    return corroborated(np.where(agree, r.lower[None, :] - term, -np.inf), r.sender,
                        r.settings.corroboration), confirmed


def corroborated(bounds: np.ndarray, sender: np.ndarray, k: int) -> np.ndarray:
    """Per row, the k-th highest of the senders' best bounds (−inf with fewer than k senders):
    a bound counts once k senders vouch for at least as much, so one miscalibrated sender alone
    cannot lift H (decision 0063). ``bounds`` (m, n) with −inf where a report does not count.

    Examples
    --------
    >>> b = np.array([[0.40, 0.45, 0.50, -np.inf]])
    >>> corroborated(b, np.array([0, 0, 1, 2]), 2).tolist()
    [0.45]
    """
    order = np.argsort(sender, kind="stable")
    s = sender[order]
    starts = np.flatnonzero(np.concatenate([[True], s[1:] != s[:-1]]))
    if starts.size < k:
        return np.full(bounds.shape[0], -np.inf)
    best = np.maximum.reduceat(bounds[:, order], starts, axis=1)
    return np.sort(best, axis=1)[:, -k]


def conflicts(r: ReportData, prior_std: float) -> np.ndarray:
    """``C[w, h]``: report w's lower bound, moved to h's position and creation time, lies above
    h's own upper bound (decision 0063), shape ``(n, n)``.

    Moved: the sender's lower half-width aged by the time between the two reports
    (:func:`~mufusion.fusion.reports.age_variance`) and less ``G·(|s_w − s_h| + δ_w + δ_h)``.
    """
    w, h = conflict_pairs(r, prior_std)
    out = np.zeros((r.size, r.size), dtype=bool)
    out[w, h] = True
    return out


def conflict_pairs(r: ReportData, prior_std: float) -> tuple[np.ndarray, np.ndarray]:
    """The index pairs (w, h) of :func:`conflicts` (few: only wrong reports conflict)."""
    settings = r.settings
    moved = settings.gradient_bound_per_m * (
        np.abs(r.s_m[:, None] - r.s_m[None, :])
        + r.position_bound_m[:, None] + r.position_bound_m[None, :]
    )
    room = (r.mu + Z95 * r.upper_sd)[None, :] + moved + 1e-12  # h's upper bound, moved to w
    # Ageing only widens w's interval: pairs that do not conflict unaged never do, so the
    # ageing (the costly part) is evaluated on the few candidate pairs only.
    w, h = np.nonzero((r.mu - Z95 * r.lower_sd)[:, None] > room)
    aged = age_variance(np.abs(r.age_s[w] - r.age_s[h]), prior_std, settings.tau_s,
                        settings.age_kernel)
    keep = r.mu[w] - Z95 * np.sqrt(r.lower_sd[w] ** 2 + aged) > room[w, h]
    return w[keep], h[keep]


def sender_noise(own_sd: np.ndarray, r: ReportData) -> tuple[np.ndarray, np.ndarray]:
    """The paper posterior's noise with reports (paper mode, and safe mode's paper part): the own
    data independent, each sender's reports sharing one error (the sender cap, decisions 0075
    and 0077).

    A report's variance σ_r² splits into ``ρ σ_r²`` common to its sender and ``(1 − ρ) σ_r²``
    of its own, ``ρ = 1 / sender_cap`` (at most ``SHARED_ERROR_FRACTION``): ``Σ_ij = ρ σ_i σ_j``
    for two reports of one sender. However many reports a sender sends, and wherever, their
    mean keeps the variance ``ρ σ²``: the sender counts at most as ``sender_cap`` independent
    reports. Returns the independent std per point (own data first) and one shared column per
    sender (:meth:`~mufusion.fusion.engine.PosteriorEngine.latent`).

    Examples
    --------
    >>> from mufusion.fusion import PAPER_PRIOR
    >>> from mufusion.estimators.shared import FrictionReport
    >>> from mufusion.fusion.reports import report_data
    >>> rs = [FrictionReport.numeric(x, 0.5, 0.025, sender="a") for x in (5.0, 6.0)]
    >>> d = report_data(rs, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    >>> indep, shared = sender_noise(np.array([0.05]), d)
    >>> bool(indep[0] == 0.05), bool(np.allclose(3 * shared[1:, 0] ** 2, d.noise_sd ** 2))
    (True, True)
    """
    rho = min(1.0 / r.settings.sender_cap, SHARED_ERROR_FRACTION)
    _, column = np.unique(r.sender, return_inverse=True)
    shared = np.zeros((own_sd.size + r.size, int(column.max()) + 1 if r.size else 0))
    shared[own_sd.size + np.arange(r.size), column] = math.sqrt(rho) * r.noise_sd
    return np.concatenate([own_sd, math.sqrt(1.0 - rho) * r.noise_sd]), shared


def _latent_lower(
    engine: PosteriorEngine,
    prior: GPPrior,
    s: np.ndarray,
    e: np.ndarray,
    resid: np.ndarray,
    noise_sd: np.ndarray,
    groups: np.ndarray | None = None,
    split: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Posterior mean, std and lower bound (grouped noise if ``groups`` is given, or the
    independent std and shared columns ``split``)."""
    if split is None and groups is not None:
        split = grouped_noise(noise_sd, groups)
    if split is None:
        offset, std = engine.latent(prior, s, e, resid, noise_sd)
    else:
        offset, std = engine.latent(prior, s, e, resid, split[0], split[1])
    mean = offset + prior.mean
    return mean, std, mean - Z95 * std


def fuse_shared(
    engine: PosteriorEngine,
    prior: GPPrior,
    own: FusionData,
    e: np.ndarray,
    mode: str,
    reports: ReportData,
    without: FusedEstimate,
) -> FusedEstimate:
    """The fused estimate with reports, from validated inputs (module docstring).

    ``without`` is the estimate on the own data alone (same mode); it is returned unchanged when
    the trust test keeps no report. ``mean``/``std``/``lower`` of the result are the posterior
    with own data and kept reports (grouped noise in safe mode, one group per sender).
    """
    screen = screen_reports(own, reports)
    r = reports.subset(screen.kept)
    if r.size == 0:
        return without
    confirmers = screen.near_own[screen.kept]
    s_all = np.concatenate([own.s_m, r.s_m])
    resid = np.concatenate([own.mu, r.mu]) - prior.mean
    own_sd = noise_sd_of(own.margin)
    sd_all = np.concatenate([own_sd, r.noise_sd])
    mean, std, lower = _latent_lower(engine, prior, s_all, e, resid, sd_all,
                                     split=sender_noise(own_sd, r))
    top = max(prior.upper, own.mu_max, float(r.mu.max()))
    if own.s_m.size == 0:
        # Nothing of the vehicle's own can confirm a report: they may only lower μ̂.
        mu_hat = np.minimum(lower, without.mu_hat)
        if mode == "paper":
            return FusedEstimate(e, mean, std, lower, clip_to_band(mu_hat, top))
        _, g_std, g_lower = _latent_lower(
            engine, prior, s_all, e, resid, sd_all, r.sender)
        return FusedEstimate(e, mean, g_std, g_lower, clip_to_band(mu_hat, top))
    h_rep, confirmed = _report_bound(own, r, confirmers, e, prior.std)
    # Reports no own datum lies near may lower μ̂ but never raise it, also not through the
    # posterior at the points other reports confirm: there μ̂ is at most L⁺_c (step 3).
    near = np.concatenate([np.ones(own.s_m.size, dtype=bool), confirmers])
    lower_c = lower if near.all() else _latent_lower(
        engine, prior, s_all[near], e, resid[near], sd_all[near],
        split=sender_noise(own_sd, r.subset(confirmers)))[2]
    if mode == "paper":
        one_sided = np.where(confirmed, np.minimum(lower, lower_c),
                             np.minimum(lower, without.lower))
        return FusedEstimate(e, mean, std, lower, clip_to_band(one_sided, top))
    # Safe mode: the own-data pieces without reports, then the one-sided rule and the bound H.
    own_resid = own.mu - prior.mean
    _, _, paper_without = _latent_lower(engine, prior, own.s_m, e, own_resid, own_sd)
    own_groups = (
        np.arange(own.s_m.size, dtype=np.int64) if own.groups is None else own.groups
    )
    groups = np.concatenate([own_groups, int(own_groups.max()) + 1 + r.sender])
    g_mean, g_std, g_lower = _latent_lower(engine, prior, s_all, e, resid, sd_all, groups)
    g_lower_c = g_lower if near.all() else _latent_lower(
        engine, prior, s_all[near], e, resid[near], sd_all[near], groups[near])[2]
    paper_used = np.where(confirmed, np.minimum(lower, lower_c), np.minimum(lower, paper_without))
    grouped_used = np.where(confirmed, np.minimum(g_lower, g_lower_c),
                            np.minimum(g_lower, without.lower))
    h_own, outside = hard_bound_envelope(own.s_m, own.mu, own.margin, e)
    bound = np.maximum(h_own, h_rep)  # h_rep is −inf where no report counts
    mu_hat = np.minimum(paper_used, bound)
    mu_hat = np.where(outside, np.minimum(mu_hat, grouped_used), mu_hat)
    return FusedEstimate(e, g_mean, g_std, g_lower, clip_to_band(mu_hat, top))

