"""GP core: exact posterior against scikit-learn, and the properties of Appendix A."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel

from mufusion.fusion import (
    NOISE_STD_FLOOR,
    PAPER_PRIOR,
    Z95,
    FusedEstimate,
    GPFusion,
    GPPrior,
    assemble_inputs,
    fuse,
)

GRID = np.arange(0.0, 51.0)


def _sklearn(s, mu, margin, prior, s_eval):
    kernel = ConstantKernel(prior.variance, "fixed") * RBF(prior.length_scale_m, "fixed")
    gpr = GaussianProcessRegressor(
        kernel=kernel, alpha=(np.asarray(margin) / 1.96) ** 2, optimizer=None, normalize_y=False
    )
    gpr.fit(np.asarray(s).reshape(-1, 1), np.asarray(mu) - prior.mean)
    mean, std = gpr.predict(np.asarray(s_eval).reshape(-1, 1), return_std=True)
    return mean + prior.mean, std


def _random_case(rng: np.random.Generator, n: int):
    s = rng.uniform(0.0, 60.0, n)
    mu = rng.uniform(0.1, 1.0, n)
    margin = rng.uniform(0.02, 0.3, n)
    return s, mu, margin


def test_prior_from_interval_is_95_band():
    assert PAPER_PRIOR.mean == pytest.approx(0.55)
    assert PAPER_PRIOR.std == pytest.approx(0.45 / 1.96)
    assert PAPER_PRIOR.length_scale_m == 15.0
    low = PAPER_PRIOR.mean - Z95 * PAPER_PRIOR.std
    assert low == pytest.approx(0.1)


def test_kernel_is_squared_exponential():
    prior = GPPrior(0.5, 0.2, 10.0)
    k = prior.kernel(np.array([0.0, 10.0]), np.array([0.0, 10.0]))
    assert k[0, 0] == pytest.approx(0.04)
    assert k[0, 1] == pytest.approx(0.04 * np.exp(-0.5))


@pytest.mark.parametrize("seed", range(12))
def test_matches_sklearn_on_random_heteroscedastic_cases(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    s, mu, margin = _random_case(rng, n)
    prior = GPPrior(rng.uniform(0.3, 0.7), rng.uniform(0.1, 0.4), rng.uniform(3.0, 30.0))
    s_eval = np.sort(rng.uniform(-10.0, 70.0, 37))
    est = fuse(s, mu, margin, prior, s_eval)
    ref_mean, ref_std = _sklearn(s, mu, margin, prior, s_eval)
    np.testing.assert_allclose(est.mean, ref_mean, rtol=0, atol=1e-8)
    np.testing.assert_allclose(est.std, ref_std, rtol=0, atol=1e-8)
    np.testing.assert_allclose(est.lower, est.mean - 1.96 * est.std, rtol=0, atol=1e-15)
    # μ̂ is the lower bound kept within the band [0, max(prior upper edge, max datum)].
    top = max(prior.mean + Z95 * prior.std, mu.max())
    np.testing.assert_array_equal(est.mu_hat, np.clip(est.lower, 0.0, top))


def test_matches_sklearn_on_paper_problem():
    mu = np.where(GRID < 5.0, 0.425, 0.5)
    margin = np.where(GRID < 5.0, 0.025, 0.1)
    est = fuse(GRID, mu, margin, PAPER_PRIOR, GRID)
    ref_mean, ref_std = _sklearn(GRID, mu, margin, PAPER_PRIOR, GRID)
    np.testing.assert_allclose(est.mean, ref_mean, rtol=0, atol=1e-8)
    np.testing.assert_allclose(est.std, ref_std, rtol=0, atol=1e-8)


def test_no_data_returns_prior():
    est = fuse([], [], [], PAPER_PRIOR, GRID)
    np.testing.assert_array_equal(est.mean, np.full(GRID.size, PAPER_PRIOR.mean))
    np.testing.assert_array_equal(est.std, np.full(GRID.size, PAPER_PRIOR.std))
    np.testing.assert_allclose(est.mu_hat, 0.1, atol=1e-12)
    assert isinstance(est, FusedEstimate)


def test_far_from_data_reverts_to_prior():
    est = fuse([0.0], [0.9], [0.02], PAPER_PRIOR, np.array([0.0, 500.0]))
    assert est.mean[1] == pytest.approx(PAPER_PRIOR.mean, abs=1e-9)
    assert est.std[1] == pytest.approx(PAPER_PRIOR.std, abs=1e-9)
    assert est.mean[0] == pytest.approx(0.9, abs=0.01)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 30))
def test_posterior_std_never_exceeds_prior(seed, n):
    rng = np.random.default_rng(seed)
    s, mu, margin = _random_case(rng, n)
    est = fuse(s, mu, margin, PAPER_PRIOR, GRID)
    assert (est.std <= PAPER_PRIOR.std + 1e-12).all()
    assert (est.std >= 0.0).all()


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 30))
def test_permutation_invariance(seed, n):
    rng = np.random.default_rng(seed)
    s, mu, margin = _random_case(rng, n)
    perm = rng.permutation(n)
    a = fuse(s, mu, margin, PAPER_PRIOR, GRID)
    b = fuse(s[perm], mu[perm], margin[perm], PAPER_PRIOR, GRID)
    np.testing.assert_allclose(a.mean, b.mean, atol=1e-10)
    np.testing.assert_allclose(a.std, b.std, atol=1e-10)


def test_duplicated_point_equals_one_point_with_half_variance():
    # Two independent copies of y with noise σ² carry the information of one with σ²/2.
    twice = fuse([10.0, 10.0], [0.7, 0.7], [0.1, 0.1], PAPER_PRIOR, GRID)
    once = fuse([10.0], [0.7], [0.1 / np.sqrt(2.0)], PAPER_PRIOR, GRID)
    np.testing.assert_allclose(twice.mean, once.mean, atol=1e-12)
    np.testing.assert_allclose(twice.std, once.std, atol=1e-12)
    ref_mean, ref_std = _sklearn([10.0, 10.0], [0.7, 0.7], [0.1, 0.1], PAPER_PRIOR, GRID)
    np.testing.assert_allclose(twice.mean, ref_mean, atol=1e-8)
    np.testing.assert_allclose(twice.std, ref_std, atol=1e-8)


def test_zero_margin_interpolates_the_data_to_the_noise_floor():
    # A zero margin is fused with the noise floor's std: the posterior follows the data to a
    # fraction of it and its std stays below it; exactly as a margin of 1.96 · floor.
    s = np.array([0.0, 20.0, 40.0])
    mu = np.array([0.3, 0.9, 0.5])
    est = fuse(s, mu, [0.0, 0.0, 0.0], PAPER_PRIOR, s)
    np.testing.assert_allclose(est.mean, mu, atol=0.1 * NOISE_STD_FLOOR)
    assert (est.std <= NOISE_STD_FLOOR).all()
    floor = fuse(s, mu, np.full(3, Z95 * NOISE_STD_FLOOR), PAPER_PRIOR, s)
    np.testing.assert_allclose(est.mean, floor.mean, rtol=0, atol=1e-15)
    ref_mean, ref_std = _sklearn(s, mu, np.full(3, Z95 * NOISE_STD_FLOOR), PAPER_PRIOR, s)
    np.testing.assert_allclose(est.mean, ref_mean, atol=1e-8)
    np.testing.assert_allclose(est.std, ref_std, atol=1e-8)


def test_zero_margin_on_dense_grid_is_finite():
    # 51 noise-free points 1 m apart with ℓ = 15 m: K alone is numerically singular; the noise
    # floor keeps K + Σ well conditioned.
    mu = np.linspace(0.4, 0.8, GRID.size)
    est = fuse(GRID, mu, np.zeros(GRID.size), PAPER_PRIOR, GRID)
    assert np.isfinite(est.mean).all() and np.isfinite(est.std).all()
    np.testing.assert_allclose(est.mean, mu, atol=NOISE_STD_FLOOR)


def test_scalar_margin_broadcasts():
    a = fuse([0.0, 5.0], [0.4, 0.5], 0.1, PAPER_PRIOR, GRID)
    b = fuse([0.0, 5.0], [0.4, 0.5], [0.1, 0.1], PAPER_PRIOR, GRID)
    np.testing.assert_array_equal(a.mean, b.mean)


def test_gpfusion_object_equals_function():
    f = GPFusion(PAPER_PRIOR, GRID, mode="paper")
    s, mu, margin = _random_case(np.random.default_rng(3), 20)
    a = f.fuse(s, mu, margin)
    b = fuse(s, mu, margin, PAPER_PRIOR, GRID)
    np.testing.assert_array_equal(a.mu_hat, b.mu_hat)


def test_paper_popup_estimate_near_vehicle():
    # Popup at μ = 0.89, local 0.865 ± 0.025 for s < 5 m, dry class 0.8 ± 0.2 ahead: the paper's
    # F gave 0.84 near the vehicle; μ̂(0) must stay within 10 % of 0.89.
    mu = np.where(GRID < 5.0, 0.865, 0.8)
    margin = np.where(GRID < 5.0, 0.025, 0.2)
    est = fuse(GRID, mu, margin, PAPER_PRIOR, GRID)
    assert 0.80 <= est.mu_hat[0] < 0.865


def test_gpfusion_step_on_assembled_data_in_safe_mode():
    data = assemble_inputs(GRID, np.full(51, 0.5), np.full(51, 0.1), local_mu=0.425, mode="safe")
    f = GPFusion(PAPER_PRIOR, GRID, mode="safe")
    a = f.step(data)
    b = fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, GRID, groups=data.groups, mode="safe")
    np.testing.assert_array_equal(a.mu_hat, b.mu_hat)
    np.testing.assert_allclose(a.mu_hat, 0.4, atol=1e-12)
