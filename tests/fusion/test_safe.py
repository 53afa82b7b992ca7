"""Safe mode: the paper's fused μ̂ over-estimates under worst-case errors; safe mode never does.

Camera classes (paper Sec. IV, configuration F): dry 0.8 ± 0.2, wet 0.5 ± 0.1, snow/ice 0.25 ±
0.15; local estimate μ_gt(0) + e_l with |e_l| ≤ 0.025 for s < s_l. A worst-case error is a true μ
at a class edge (class value − margin or + margin).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.fusion import (
    DEFAULT_GRID_M,
    DEFAULT_S_LOCAL_M,
    LOCAL_MARGIN,
    PAPER_PRIOR,
    assemble_inputs,
    fuse,
)

GRID = DEFAULT_GRID_M
DRY, WET, SNOW = (0.8, 0.2), (0.5, 0.1), (0.25, 0.15)


def _fused(mu_gt, classes, local_error, mode, s_eval=GRID):
    """Emulated estimators on a true profile, then assembly and fusion in one mode."""
    value = np.array([c[0] for c in classes])
    margin = np.array([c[1] for c in classes])
    local = None if local_error is None else mu_gt[0] + local_error
    data = assemble_inputs(GRID, value, margin, local_mu=local, mode=mode)
    est = fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, s_eval, groups=data.groups, mode=mode)
    return data, est


def _profile(change_m, first, second, err_first, err_second):
    """Class per grid point and the true μ: class value − error (error +margin = over-estimate)."""
    before = GRID < change_m
    classes = [first if b else second for b in before]
    mu_gt = np.where(before, first[0] - err_first, second[0] - err_second)
    return classes, mu_gt


def test_paper_mode_over_estimates_in_the_worst_case():
    # μ_gt = 0.4 on wet (class 0.5 ± 0.1: camera error +0.1) and local 0.4 + 0.025.
    classes, mu_gt = _profile(np.inf, WET, WET, 0.1, 0.1)
    _, est = _fused(mu_gt, classes, +LOCAL_MARGIN, "paper")
    excess = est.mu_hat - 0.4
    assert (excess > 0.0).all()
    assert excess.max() >= 0.05
    assert excess.max() < 0.1  # ≈ 0.08 with s_l = 5 m, ℓ = 15 m


def test_paper_mode_over_estimates_more_next_to_a_class_change():
    # Dry at its lower edge 0.6 then wet at 0.4, both over-estimated by the camera.
    classes, mu_gt = _profile(20.0, DRY, WET, 0.2, 0.1)
    _, est = _fused(mu_gt, classes, +LOCAL_MARGIN, "paper")
    wet = GRID >= 20.0
    uniform = _fused(np.full(51, 0.4), [WET] * 51, +LOCAL_MARGIN, "paper")[1]
    assert (est.mu_hat[wet] - 0.4).max() > (uniform.mu_hat - 0.4).max()
    assert (est.mu_hat[wet] - 0.4).max() >= 0.1


def _safe_never_over(mu_gt, classes, local_error):
    data, est = _fused(mu_gt, classes, local_error, "safe")
    at_data = np.isin(GRID, data.s_m)
    assert (est.mu_hat[at_data] <= mu_gt[at_data] + 1e-12).all()
    # On the same data, safe μ̂ never exceeds paper-mode μ̂ (the two assemblies differ when the
    # paper carries the local estimate past a class change).
    paper = fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, GRID, mode="paper")
    assert (est.mu_hat <= paper.mu_hat + 1e-12).all()
    return est


CHANGES = [(DRY, WET), (WET, SNOW), (DRY, SNOW), (SNOW, DRY)]
POSITIONS = [1.0, 3.0, 5.0, 12.0, 35.0, np.inf]


@pytest.mark.parametrize(("first", "second"), CHANGES)
@pytest.mark.parametrize("change_m", POSITIONS)
def test_safe_mode_never_over_estimates_at_worst_case_edges(first, second, change_m):
    edges = lambda c: (-c[1], 0.0, c[1])  # noqa: E731
    for err_first, err_second in itertools.product(edges(first), edges(second)):
        classes, mu_gt = _profile(change_m, first, second, err_first, err_second)
        for local_error in (None, -LOCAL_MARGIN, 0.0, LOCAL_MARGIN):
            _safe_never_over(mu_gt, classes, local_error)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_changes=st.integers(0, 3),
    with_local=st.booleans(),
)
def test_safe_mode_never_over_estimates_random_errors(seed, n_changes, with_local):
    rng = np.random.default_rng(seed)
    starts = np.sort(rng.uniform(0.0, 50.0, n_changes))
    seg = np.searchsorted(starts, GRID, side="right")
    # Consecutive segments differ in class: a change of μ within one class is invisible to the
    # camera, and the premise (one error per class segment and per local estimate) excludes it.
    kinds = [int(rng.integers(0, 3))]
    for _ in range(n_changes):
        kinds.append((kinds[-1] + int(rng.integers(1, 3))) % 3)
    seg_class = [(DRY, WET, SNOW)[i] for i in kinds]
    seg_error = [rng.uniform(-c[1], c[1]) for c in seg_class]
    classes = [seg_class[k] for k in seg]
    mu_gt = np.array([seg_class[k][0] - seg_error[k] for k in seg])
    local_error = rng.uniform(-LOCAL_MARGIN, LOCAL_MARGIN) if with_local else None
    _safe_never_over(mu_gt, classes, local_error)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1), n_groups=st.integers(1, 6))
def test_safe_fuse_guarantee_on_arbitrary_groups(seed, n_groups):
    # Any data: points of a group share one error within the group's margin; repeated and
    # unsorted positions; the true μ is arbitrary per point.
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 12, n_groups)
    groups = np.repeat(np.arange(n_groups), sizes)
    s = rng.choice(np.arange(0.0, 40.0, 0.5), groups.size)
    margin_g = rng.uniform(0.0, 0.3, n_groups)
    error_g = rng.uniform(-1.0, 1.0, n_groups) * margin_g
    mu_gt_at = dict(zip(np.unique(s), rng.uniform(0.1, 1.0, np.unique(s).size), strict=True))
    mu_gt = np.array([mu_gt_at[v] for v in s])
    # A report below 0 is clipped to 0, as the camera emulation does (still within its margin).
    mu = np.maximum(mu_gt + error_g[groups], 0.0)
    margin = margin_g[groups]
    s_eval = np.unique(np.concatenate([s, rng.uniform(-5.0, 50.0, 20)]))
    safe = fuse(s, mu, margin, PAPER_PRIOR, s_eval, groups=groups, mode="safe")
    paper = fuse(s, mu, margin, PAPER_PRIOR, s_eval, mode="paper")
    for i, v in enumerate(s_eval):
        if v in mu_gt_at:
            assert safe.mu_hat[i] <= mu_gt_at[v] + 1e-12
    assert (safe.mu_hat <= paper.mu_hat + 1e-12).all()


def test_safe_mode_is_tight_at_data_points():
    # μ̂ = max(y − margin) over the estimates at a point when that is below the paper's bound:
    # nothing higher is guaranteed by the estimates.
    s = np.array([0.0, 0.0, 10.0])
    mu = np.array([0.6, 0.5, 0.5])
    margin = np.array([0.2, 0.025, 0.1])
    safe = fuse(s, mu, margin, PAPER_PRIOR, np.array([0.0, 5.0, 10.0, 30.0]), mode="safe")
    paper = fuse(s, mu, margin, PAPER_PRIOR, np.array([0.0, 5.0, 10.0, 30.0]), mode="paper")
    assert safe.mu_hat[0] == pytest.approx(min(paper.mu_hat[0], 0.475))
    assert safe.mu_hat[2] == pytest.approx(min(paper.mu_hat[2], 0.4))
    # Between data points: the smaller neighbouring bound; beyond: no more than the last bound.
    assert safe.mu_hat[1] <= 0.4 + 1e-12
    assert safe.mu_hat[3] <= 0.4 + 1e-12


def test_safe_mode_without_groups_matches_paper_posterior():
    rng = np.random.default_rng(7)
    s = rng.uniform(0.0, 50.0, 15)
    mu = rng.uniform(0.2, 0.9, 15)
    margin = rng.uniform(0.02, 0.2, 15)
    safe = fuse(s, mu, margin, PAPER_PRIOR, GRID, mode="safe")
    paper = fuse(s, mu, margin, PAPER_PRIOR, GRID, mode="paper")
    np.testing.assert_allclose(safe.mean, paper.mean, atol=1e-12)
    np.testing.assert_allclose(safe.std, paper.std, atol=1e-12)


def test_grouped_noise_keeps_copies_from_shrinking_the_band():
    # 51 copies of one wet class estimate: independent noise shrinks the std far below the
    # class's own 0.1 / 1.96; one shared error keeps it near the single-estimate value.
    mu = np.full(51, 0.5)
    margin = np.full(51, 0.1)
    paper = fuse(GRID, mu, margin, PAPER_PRIOR, GRID, mode="paper")
    safe = fuse(GRID, mu, margin, PAPER_PRIOR, GRID, groups=np.zeros(51, int), mode="safe")
    sd = 0.1 / 1.96
    one_estimate = 1.0 / np.sqrt(1.0 / sd**2 + 1.0 / PAPER_PRIOR.variance)
    assert paper.std.min() < 0.5 * sd
    assert safe.std.min() > 0.9 * one_estimate


def test_safe_popup_keeps_local_accuracy_near_the_vehicle():
    # Popup at μ = 0.89: local 0.865 ± 0.025 → the guaranteed 0.84 at s < s_l, as the paper's F.
    classes, mu_gt = _profile(np.inf, DRY, DRY, -0.09, -0.09)
    _, est = _fused(mu_gt, classes, -LOCAL_MARGIN, "safe")
    near = GRID < DEFAULT_S_LOCAL_M
    np.testing.assert_allclose(est.mu_hat[near], 0.84, atol=1e-12)
    # Beyond the local reach only the class edge is guaranteed.
    assert (est.mu_hat[~near] <= 0.6 + 1e-12).all()


def test_safe_fuse_needs_the_safe_assembly():
    # The paper's assembly copies the local dry value past a dry→wet change at 2 m: the copies
    # violate their own margin there, so no fusion rule can guarantee μ̂ ≤ μ_gt on them.
    classes, mu_gt = _profile(2.0, DRY, WET, 0.0, 0.1)
    value = np.array([c[0] for c in classes])
    margin = np.array([c[1] for c in classes])
    data = assemble_inputs(GRID, value, margin, local_mu=mu_gt[0], mode="paper")
    est = fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, GRID, groups=data.groups, mode="safe")
    assert (est.mu_hat[2:5] > mu_gt[2:5]).all()
    _safe_never_over(mu_gt, classes, 0.0)
