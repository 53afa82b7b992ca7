"""Fusion cannot return nonsense: for any finite input it raises ValueError (exactly when an input
is outside its declared range) or returns finite μ̂ within the band [0, max(prior upper edge,
largest datum)]."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from mufusion.fusion import (
    LENGTH_SCALE_RANGE_M,
    MARGIN_RANGE,
    MU_RANGE,
    NOISE_STD_FLOOR,
    PAPER_PRIOR,
    POSITION_RANGE_M,
    PRIOR_MEAN_RANGE,
    PRIOR_STD_RANGE,
    Z95,
    GPPrior,
    fuse,
    fuse_batch,
)

GRID = np.arange(0.0, 51.0)

FINITE = st.floats(allow_nan=False, allow_infinity=False)
# Near-duplicates of 10 m: 0, 1e-12, 1e-9, 1e-6, 1e-3 and 1e-2 m apart.
NEAR = st.sampled_from([10.0, 10.0 + 1e-12, 10.0 + 1e-9, 10.0 + 1e-6, 10.001, 10.01])
# Within the declared ranges, edges and tiny values included ...
IN_RANGE = {
    "s": st.one_of(st.floats(-100.0, 100.0), NEAR, st.sampled_from([-1e6, 0.0, 1e6])),
    "mu": st.one_of(st.floats(0.0, 2.0), st.sampled_from([0.0, 5e-324, 2.0])),
    "margin": st.one_of(st.floats(0.0, 1.0), st.sampled_from([0.0, 5e-324, 1e-300, 1e-12, 1.0])),
    "mean": st.one_of(st.floats(0.0, 2.0), st.sampled_from([0.0, 2.0])),
    "std": st.one_of(st.floats(1e-3, 1.0), st.sampled_from([1e-3, 1.0])),
    "length": st.one_of(st.floats(0.1, 1e4), st.sampled_from([0.1, 1e4])),
}
# ... or any finite value (hostile examples).
ANY = {
    "s": st.one_of(IN_RANGE["s"], FINITE, st.sampled_from([2e6, -1e300])),
    "mu": st.one_of(IN_RANGE["mu"], FINITE, st.sampled_from([5.0, -1.0, 1e308])),
    "margin": st.one_of(IN_RANGE["margin"], FINITE, st.sampled_from([-1e-12, 1.5])),
    "mean": st.one_of(IN_RANGE["mean"], FINITE),
    "std": st.one_of(IN_RANGE["std"], FINITE, st.sampled_from([1e200, 1e-300])),
    "length": st.one_of(IN_RANGE["length"], FINITE, st.sampled_from([1e200, 1e-300])),
}


def _inside(values, bounds) -> bool:
    return all(bounds[0] <= v <= bounds[1] for v in values)


def _valid_prior(mean, std, length) -> bool:
    return (
        _inside([mean], PRIOR_MEAN_RANGE)
        and _inside([std], PRIOR_STD_RANGE)
        and _inside([length], LENGTH_SCALE_RANGE_M)
    )


def _assert_sane(est, prior, mu_max):
    top = max(prior.mean + Z95 * prior.std, mu_max)
    for field in ("mean", "std", "lower", "mu_hat"):
        assert np.isfinite(getattr(est, field)).all(), field
    assert (est.mu_hat >= 0.0).all()
    assert (est.mu_hat <= top).all()


@settings(
    max_examples=400, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    data=st.data(),
    hostile=st.booleans(),
    n=st.integers(0, 7),
    n_eval=st.integers(0, 6),
    grouped=st.booleans(),
    mode=st.sampled_from(["paper", "safe"]),
)
def test_fuse_raises_or_returns_finite_mu_hat_in_the_band(
    data, hostile, n, n_eval, grouped, mode
):
    pick = ANY if hostile else IN_RANGE

    def draw(key, size):
        return data.draw(st.lists(pick[key], min_size=size, max_size=size), label=key)

    s, mu, margin = draw("s", n), draw("mu", n), draw("margin", n)
    s_eval = draw("s", n_eval if hostile else max(n_eval, 1))
    prior = (draw("mean", 1)[0], draw("std", 1)[0], draw("length", 1)[0])
    groups = data.draw(st.lists(st.integers(-2, 2), min_size=n, max_size=n)) if grouped else None
    valid = (
        _valid_prior(*prior)
        and _inside(s + s_eval, POSITION_RANGE_M)
        and len(s_eval) > 0
        and _inside(mu, MU_RANGE)
        and _inside(margin, MARGIN_RANGE)
    )
    try:
        gp = GPPrior(*prior)
        est = fuse(s, mu, margin, gp, s_eval, groups=groups, mode=mode)
    except ValueError:
        event("rejected")
        assert not valid, "raised on input within every declared range"
        return
    event("fused")
    assert valid, "accepted input outside a declared range"
    _assert_sane(est, gp, max(mu, default=0.0))


@settings(
    max_examples=150, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    n=st.integers(1, 5),
    b=st.integers(1, 4),
    data=st.data(),
    hostile=st.booleans(),
    mode=st.sampled_from(["paper", "safe"]),
    shared_positions=st.booleans(),
)
def test_fuse_batch_raises_or_returns_finite_mu_hat_in_the_band(
    n, b, data, hostile, mode, shared_positions
):
    pick = ANY if hostile else IN_RANGE

    def draw(strategy, size):
        return np.array(data.draw(st.lists(strategy, min_size=size, max_size=size)))

    shape = (n,) if shared_positions else (b, n)
    s = draw(pick["s"], math.prod(shape)).reshape(shape)
    mu = draw(st.one_of(pick["mu"], st.just(math.nan)), b * n).reshape(b, n)
    margin = draw(pick["margin"], n)
    prior = (draw(pick["mean"], 1)[0], draw(pick["std"], 1)[0], draw(pick["length"], 1)[0])
    present = ~np.isnan(mu)
    valid = (
        _valid_prior(*prior)
        and _inside(s.ravel(), POSITION_RANGE_M)
        and _inside(mu[present], MU_RANGE)
        and _inside(margin[present.any(axis=0)], MARGIN_RANGE)
    )
    try:
        gp = GPPrior(*prior)
        est = fuse_batch(s, mu, margin, gp, GRID, mode=mode)
    except ValueError:
        event("rejected")
        assert not valid, "raised on input within every declared range"
        return
    event("fused")
    assert valid, "accepted input outside a declared range"
    for i in range(b):
        row = type(est)(est.s_m, est.mean[i], est.std[i], est.lower[i], est.mu_hat[i])
        _assert_sane(row, gp, max(mu[i][present[i]], default=0.0))


# --- the cases reported in the issue ---------------------------------------------------------


@pytest.mark.parametrize("gap_m", [1e-6, 1e-4, 1e-2])
@pytest.mark.parametrize("margin", [0.0, 1e-12])
@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_near_duplicates_with_tiny_margins_stay_in_the_band(gap_m, margin, mode):
    # Before: μ̂ from −3.2e6 to +6.1e6.
    est = fuse([10.0, 10.0 + gap_m], [0.3, 0.9], [margin, margin], PAPER_PRIOR, GRID, mode=mode)
    assert np.isfinite(est.mean).all() and np.isfinite(est.std).all()
    assert (est.mu_hat >= 0.0).all() and (est.mu_hat <= 1.0).all()


def test_near_duplicates_far_below_the_length_scale_average():
    # 1e-6 m apart, margins 0: one position seen twice; the posterior sits between the two values.
    est = fuse([10.0, 10.0 + 1e-6], [0.3, 0.9], [0.0, 0.0], PAPER_PRIOR, np.array([10.0]))
    assert est.mean[0] == pytest.approx(0.6, abs=1e-3)


def test_capping_at_the_band_top_is_logged(caplog):
    # Contradicting data 1 cm apart with zero margins: the squared-exponential GP rings.
    with caplog.at_level(logging.WARNING, logger="mufusion.fusion"):
        est = fuse([10.0, 10.01], [0.3, 0.9], [0.0, 0.0], PAPER_PRIOR, GRID)
    assert (est.lower > 1.0).any()  # the raw lower bound overshoots ...
    assert est.mu_hat.max() == pytest.approx(1.0)  # ... μ̂ is capped at the band top
    assert "band top" in caplog.text


@pytest.mark.parametrize("value", [5.0, -1.0, 1e308, 2.0000001])
def test_mu_outside_the_physical_range_is_rejected(value):
    with pytest.raises(ValueError, match=r"mu must lie in \[0, 2\]"):
        fuse([0.0, 5.0], [0.5, value], [0.1, 0.1], PAPER_PRIOR, GRID)


@pytest.mark.parametrize("value", [-1e-12, 1.5, 1e300])
def test_margin_outside_its_range_is_rejected(value):
    with pytest.raises(ValueError, match=r"margin must lie in \[0, 1\]"):
        fuse([0.0, 5.0], [0.5, 0.5], [0.1, value], PAPER_PRIOR, GRID)


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [
        ("std", {"mean": 0.5, "std": 1e200, "length_scale_m": 15.0}),
        ("std", {"mean": 0.5, "std": 1e-300, "length_scale_m": 15.0}),
        ("mean", {"mean": 1e308, "std": 0.2, "length_scale_m": 15.0}),
        ("mean", {"mean": -0.1, "std": 0.2, "length_scale_m": 15.0}),
        ("length_scale_m", {"mean": 0.5, "std": 0.2, "length_scale_m": 1e-300}),
        ("length_scale_m", {"mean": 0.5, "std": 0.2, "length_scale_m": 1e200}),
    ],
)
def test_prior_outside_its_ranges_is_rejected(field, kwargs):
    with pytest.raises(ValueError, match=rf"GPPrior\.{field} must lie in"):
        GPPrior(**kwargs)


def test_positions_outside_their_range_are_rejected():
    with pytest.raises(ValueError, match="s_m must lie in"):
        fuse([0.0, 2e6], [0.5, 0.5], 0.1, PAPER_PRIOR, GRID)
    with pytest.raises(ValueError, match="s_eval_m must lie in"):
        fuse([0.0], [0.5], 0.1, PAPER_PRIOR, [1e300])


def test_margin_below_the_floor_is_fused_at_the_floor():
    s, mu = [0.0, 3.0, 20.0], [0.4, 0.5, 0.8]
    tiny = fuse(s, mu, [1e-9, 0.0, 0.1], PAPER_PRIOR, GRID)
    floor = fuse(s, mu, [Z95 * NOISE_STD_FLOOR, Z95 * NOISE_STD_FLOOR, 0.1], PAPER_PRIOR, GRID)
    np.testing.assert_allclose(tiny.mean, floor.mean, rtol=0, atol=1e-15)
    np.testing.assert_allclose(tiny.std, floor.std, rtol=0, atol=1e-15)


def test_safe_hard_bounds_keep_the_declared_margin():
    # The floor only conditions the GP; the guaranteed bound y − margin uses the margin itself.
    est = fuse([0.0, 10.0], [0.5, 0.6], [0.0, 0.0], PAPER_PRIOR, [0.0, 10.0], mode="safe")
    paper = fuse([0.0, 10.0], [0.5, 0.6], [0.0, 0.0], PAPER_PRIOR, [0.0, 10.0])
    np.testing.assert_allclose(est.mu_hat, np.minimum(paper.mu_hat, [0.5, 0.6]), atol=0)


def test_combined_range_check_matches_the_declared_ranges():
    # data.validate_data checks μ and margin in two reductions, which relies on this relation.
    assert MU_RANGE[0] == MARGIN_RANGE[0] == 0.0
    assert MU_RANGE[1] == 2.0 * MARGIN_RANGE[1]
