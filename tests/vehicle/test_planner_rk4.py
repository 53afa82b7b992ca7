"""BatchRK4 computes bit for bit what classical RK4 over frenet_bicycle_dynamics computes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import frenet_bicycle_dynamics
from mufusion.vehicle.planner_rk4 import BatchRK4


def _reference_rk4(x, u, kappa, c_r, params, dt_s):
    """The straightforward formulation: four evaluations of the model, summed as written."""
    k1 = frenet_bicycle_dynamics(x, u, kappa, c_r, params)
    k2 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k1, u, kappa, c_r, params)
    k3 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k2, u, kappa, c_r, params)
    k4 = frenet_bicycle_dynamics(x + dt_s * k3, u, kappa, c_r, params)
    return x + dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def _batch(rng: np.random.Generator, m: int) -> tuple[np.ndarray, ...]:
    x = np.stack([
        rng.uniform(0.0, 200.0, m),         # s
        rng.uniform(-6.0, 6.0, m),          # d
        rng.uniform(-1.5, 1.5, m),          # Δψ
        rng.uniform(-1.0, 1.0, m),          # ψ̇
        rng.uniform(-2.0, 35.0, m),         # v_x, below the slip floor too
        rng.uniform(-3.0, 3.0, m),          # v_y
    ])
    u = rng.uniform(-4e4, 4e4, (3, m))
    kappa = rng.uniform(-0.1, 0.1, m)
    c_r = rng.uniform(1e4, 4e5, m)
    return x, u, kappa, c_r


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 50),
       dt_s=st.sampled_from([0.05, 0.1, 0.2]), truck=st.booleans())
def test_batch_rk4_is_bitwise_the_reference(seed: int, m: int, dt_s: float, truck: bool) -> None:
    params = TRUCK if truck else CAR
    rng = np.random.default_rng(seed)
    rk4 = BatchRK4(params, m)
    for _ in range(3):  # buffers reused across steps and step sizes
        x, u, kappa, c_r = _batch(rng, m)
        out = np.empty_like(x)
        got = rk4.step(x, u, kappa, c_r, dt_s, out)
        assert got is out
        np.testing.assert_array_equal(got, _reference_rk4(x, u, kappa, c_r, params, dt_s))
        dt_s = dt_s * 0.5


def test_batch_rk4_propagates_non_finite_values_as_the_reference() -> None:
    rng = np.random.default_rng(3)
    x, u, kappa, c_r = _batch(rng, 8)
    x[1, 0], x[4, 1], u[0, 2], kappa[3], x[1, 4] = np.nan, np.inf, -np.inf, 1e300, 1e300
    out = np.empty_like(x)
    with np.errstate(all="ignore"):
        expected = _reference_rk4(x, u, kappa, c_r, TRUCK, 0.1)
        got = BatchRK4(TRUCK, 8).step(x, u, kappa, c_r, 0.1, out)
    np.testing.assert_array_equal(got, expected)
    assert not np.isfinite(got).all()


def test_batch_size_is_checked() -> None:
    with pytest.raises(ValueError, match="n_batch must be >= 1"):
        BatchRK4(TRUCK, 0)
