"""Emulated camera estimator: classes, error models, range (paper Sec. IV-A/B, Table I)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators import CAMERA_RANGE_M, PAPER_CLASSES, classify, predictive_estimate

GRID_M = np.arange(0.0, 61.0, 1.0)


def _step_mu(before: float, after: float, change_m: float) -> np.ndarray:
    return np.where(GRID_M < change_m, before, after)


def test_none_reports_class_mean_margin_and_low():
    est = predictive_estimate(GRID_M, _step_mu(0.8, 0.3, 20.0))
    near, far = GRID_M < 20.0, (GRID_M >= 20.0) & (GRID_M <= CAMERA_RANGE_M)
    assert np.all(est.mu[near] == 0.8) and np.all(est.margin[near] == 0.2)
    assert np.all(est.mu[far] == 0.25) and np.all(est.margin[far] == 0.15)
    assert np.all(est.mu_low[near] == 0.6) and np.all(est.mu_low[far] == 0.1)
    assert np.all(est.class_index[near] == 2) and np.all(est.class_index[far] == 0)


def test_beyond_range_is_no_data():
    est = predictive_estimate(GRID_M, np.full(GRID_M.size, 0.5), range_m=50.0)
    beyond = GRID_M > 50.0
    assert np.all(np.isnan(est.mu[beyond])) and np.all(np.isnan(est.margin[beyond]))
    assert np.all(np.isnan(est.mu_low[beyond])) and np.all(est.class_index[beyond] == -1)
    # s_f = 50 m itself is still seen (paper: s ∈ {0, ds, ..., s_f}).
    assert est.in_range.tolist() == (~beyond).tolist()
    assert est.mu[GRID_M == 50.0][0] == 0.5


def test_beyond_range_mu_need_not_be_classifiable():
    mu = np.where(GRID_M <= 50.0, 0.5, 0.05)  # 0.05 lies in no class, but the camera can't see it
    est = predictive_estimate(GRID_M, mu)
    assert np.all(est.class_index[GRID_M > 50.0] == -1)


def test_paper_worst_cases_coincide_with_class_values():
    # Turn (worst over-estimation at μ = 0.4): μ + m_wet = 0.5, the wet class mean.
    over = predictive_estimate([0.0], [0.4], error="worst_over")
    assert over.mu[0] == pytest.approx(0.5)
    # Pop-up (worst under-estimation at μ = 1.0): μ − m_dry = 0.8, the dry class mean.
    under = predictive_estimate([0.0], [1.0], error="worst_under")
    assert under.mu[0] == pytest.approx(0.8)
    # Authors' μ = 0.89: 0.69; P's value is 0.6 in either case.
    at_089 = predictive_estimate([0.0], [0.89], error="worst_under")
    assert at_089.mu[0] == pytest.approx(0.69) and at_089.mu_low[0] == 0.6


def test_worst_under_never_reports_negative_friction():
    est = predictive_estimate([0.0], [0.1], error="worst_under")
    assert est.mu[0] == 0.0


def test_random_draws_once_per_contiguous_class_segment():
    # Three segments: dry (0.7 and 0.9 inside it), snow/ice, dry again.
    mu = np.where(GRID_M < 10.0, 0.7, 0.9)
    mu = np.where((GRID_M >= 20.0) & (GRID_M < 30.0), 0.2, mu)
    est = predictive_estimate(GRID_M, mu, error="random", rng=np.random.default_rng(3))
    err = est.mu - mu
    seen = est.in_range
    seg1, seg2, seg3 = GRID_M < 20.0, (GRID_M >= 20) & (GRID_M < 30), (GRID_M >= 30) & seen
    for seg in (seg1, seg2, seg3):
        assert np.ptp(err[seg]) < 1e-12
    assert len({round(float(err[seg][0]), 12) for seg in (seg1, seg2, seg3)}) == 3


def test_random_is_deterministic_for_a_seed_and_needs_rng():
    mu = _step_mu(0.8, 0.45, 25.0)
    a = predictive_estimate(GRID_M, mu, error="random", rng=np.random.default_rng(7))
    b = predictive_estimate(GRID_M, mu, error="random", rng=np.random.default_rng(7))
    np.testing.assert_array_equal(a.mu, b.mu)
    with pytest.raises(ValueError, match=r"random.*Generator"):
        predictive_estimate(GRID_M, mu, error="random")


@settings(max_examples=150, deadline=None)
@given(
    mu=st.lists(st.floats(0.1, 1.0, allow_nan=False), min_size=1, max_size=30),
    error=st.sampled_from(["none", "worst_over", "worst_under", "random"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_report_within_margin_of_truth_for_every_error_model(mu, error, seed):
    mu = np.asarray(mu)
    s = np.arange(mu.size, dtype=float)
    est = predictive_estimate(s, mu, error=error, rng=np.random.default_rng(seed))
    assert np.all(np.abs(est.mu - mu) <= est.margin + 1e-12)
    # The class is always the true one and P's low value never over-estimates.
    np.testing.assert_array_equal(est.class_index, classify(mu))
    assert np.all(est.mu_low <= mu)


def test_arrays_are_read_only():
    est = predictive_estimate(GRID_M, np.full(GRID_M.size, 0.8))
    with pytest.raises(ValueError):
        est.mu[0] = 0.1


@pytest.mark.parametrize(
    ("s", "mu", "kwargs", "match"),
    [
        ([0.0, 1.0], [0.5], {}, "mu_true must have the shape"),
        ([1.0, 0.0], [0.5, 0.5], {}, "strictly increasing"),
        ([-1.0, 0.0], [0.5, 0.5], {}, "≥ 0 m"),
        ([[0.0, 1.0]], [[0.5, 0.5]], {}, "1-D"),
        ([0.0, 1.0], [0.5, 0.0], {}, "mu_true must be finite and > 0"),
        ([0.0, 1.0], [0.5, 0.5], {"error": "big"}, "error must be one of"),
        ([0.0, 1.0], [0.5, 0.5], {"range_m": 0.0}, "range_m must be finite and > 0"),
        ([0.0, 1.0], [0.5, 0.05], {}, "mu must lie in a surface class"),
    ],
)
def test_bad_input_is_a_value_error(s, mu, kwargs, match):
    with pytest.raises(ValueError, match=match):
        predictive_estimate(s, mu, **kwargs)


def test_custom_classes_are_used():
    table = (PAPER_CLASSES[0], PAPER_CLASSES[1])  # no dry class: 0.8 is unclassifiable
    with pytest.raises(ValueError, match=r"covered range \[0\.1, 0\.6\]"):
        predictive_estimate([0.0], [0.8], classes=table)
