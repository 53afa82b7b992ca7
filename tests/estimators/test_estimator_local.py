"""Emulated slip-based local estimator with hold (paper Sec. IV-A/B, Table I, configuration L)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators import LocalEstimator


@pytest.mark.parametrize(
    ("error", "expected"), [("none", 0.6), ("worst_over", 0.625), ("worst_under", 0.575)]
)
def test_available_measures_truth_plus_error(error, expected):
    est = LocalEstimator(error=error, initial_mu=0.8)
    out = est.update(0.6, utilization=0.7)
    assert out.available
    assert out.mu == pytest.approx(expected)
    assert out.margin == 0.025


def test_threshold_is_strict_and_value_is_held():
    est = LocalEstimator(initial_mu=0.8)
    at_threshold = est.update(0.4, utilization=0.5)
    assert not at_threshold.available and at_threshold.mu == 0.8
    assert est.update(0.4, utilization=0.51).mu == pytest.approx(0.4)
    held = est.update(0.9, utilization=0.1)
    assert not held.available and held.mu == pytest.approx(0.4)


def test_first_update_without_initial_value_measures_but_is_not_available():
    # Turn scenario: μ = 0.8 under the vehicle, worst over-estimation, not excited.
    est = LocalEstimator(error="worst_over")
    assert est.estimate is None
    first = est.update(0.8, utilization=0.2)
    assert not first.available and first.mu == pytest.approx(0.825)
    # Only the very first update measures: the next one holds even on a different surface.
    assert est.update(0.4, utilization=0.2).mu == pytest.approx(0.825)
    assert est.estimate.mu == pytest.approx(0.825)


def test_reset_returns_to_initial_value():
    est = LocalEstimator(initial_mu=0.7)
    est.update(0.3, utilization=0.9)
    est.reset()
    assert est.estimate is None
    assert est.update(0.3, utilization=0.0).mu == 0.7
    unset = LocalEstimator()
    unset.update(0.3, utilization=0.9)
    unset.reset()
    assert unset.update(0.9, utilization=0.0).mu == pytest.approx(0.9)


def test_random_error_is_seeded_per_update_and_needs_rng():
    def run(seed):
        est = LocalEstimator(error="random", rng=np.random.default_rng(seed), initial_mu=0.5)
        return [est.update(0.6, utilization=0.8).mu for _ in range(20)]

    a, b = run(11), run(11)
    assert a == b
    assert len(set(a)) == 20  # a fresh draw each measurement
    assert all(abs(v - 0.6) <= 0.025 for v in a)
    with pytest.raises(ValueError, match=r"random.*Generator"):
        LocalEstimator(error="random")


@settings(max_examples=150, deadline=None)
@given(
    mus=st.lists(st.floats(0.05, 1.5), min_size=1, max_size=15),
    utils=st.lists(st.floats(0.0, 1.2), min_size=15, max_size=15),
    error=st.sampled_from(["none", "worst_over", "worst_under", "random"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_held_value_is_last_measurement_within_max_error(mus, utils, error, seed):
    est = LocalEstimator(error=error, rng=np.random.default_rng(seed), initial_mu=0.77)
    last_measured_truth = None
    for mu, util in zip(mus, utils[: len(mus)], strict=True):
        out = est.update(mu, util)
        assert out.available == (util > 0.5)
        if out.available:
            last_measured_truth = mu
        if last_measured_truth is None:
            assert out.mu == 0.77
        else:
            assert abs(out.mu - last_measured_truth) <= 0.025 + 1e-12


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"max_error": 0.0}, "max_error must be in"),
        ({"max_error": float("nan")}, "max_error must be in"),
        ({"utilization_threshold": -0.1}, "utilization_threshold must be"),
        ({"error": "huge"}, "error must be one of"),
        ({"initial_mu": 0.0}, r"initial_mu must be a friction coefficient in \(0, 2"),
        ({"initial_mu": 2.5}, "initial_mu must be"),
        ({"rng": 42}, "rng must be a numpy.random.Generator"),
    ],
)
def test_constructor_rejects_bad_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        LocalEstimator(**kwargs)


@pytest.mark.parametrize(
    ("mu", "util", "match"),
    [
        (0.0, 0.3, "mu_true_here must be"),
        (float("nan"), 0.3, "mu_true_here must be"),
        (0.5, -0.1, "utilization must be finite and ≥ 0"),
        (0.5, float("inf"), "utilization must be finite"),
    ],
)
def test_update_rejects_bad_input(mu, util, match):
    with pytest.raises(ValueError, match=match):
        LocalEstimator().update(mu, util)
