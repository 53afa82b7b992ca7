"""The sampling roll-outs equal, bit for bit, the straightforward loop over the model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.ocp import longitudinal_force_bounds_n
from mufusion.planner.sampling import (
    SamplingConfig,
    candidate_rollouts,
    rk4_step,
    steering_force_n,
)
from mufusion.vehicle.params import TRUCK, VehicleParams
from mufusion.vehicle.planner_model import (
    Input,
    State,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
)
from mufusion.vehicle.surface_tires import AUTHORS_TIRES, SurfaceTireTable


def _reference_rollouts(
    x0, lateral, speeds, curvature_of_s, mu_hat_of_s, params: VehicleParams,
    utilization: float, horizon_steps: int, dt_s: float, config: SamplingConfig,
    stiffness_table: SurfaceTireTable | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The roll-outs as first written: whole-array expressions, ``rk4_step``, ``np.stack``."""
    d_t, v_t = (a.ravel() for a in np.meshgrid(lateral, speeds))
    m_count = d_t.size
    x = np.repeat(np.asarray(x0, dtype=float)[:, None], m_count, axis=1)
    lower, upper = longitudinal_force_bounds_n(params)
    m = params.mass_kg
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    xs, us = [x], []
    ax = np.zeros(m_count)
    for _ in range(horizon_steps):
        v = np.maximum(x[State.vx], 1.0)
        kappa = np.asarray(curvature_of_s(x[State.s]), dtype=float) * np.ones(m_count)
        mu = np.asarray(mu_hat_of_s(x[State.s]), dtype=float) * np.ones(m_count)
        fzf, fzr = normal_loads_n(ax, params)
        mu_stiffness = np.where(np.isfinite(mu) & (mu > 0.0), mu, 1.0)
        c_r = rear_cornering_stiffness_n_per_rad(
            params, fzr, utilization, mu_hat=mu_stiffness, table=stiffness_table
        )
        fyf = steering_force_n(x, d_t, kappa, v, params, config)
        f_long = m * config.speed_gain_1_per_s * (v_t - x[State.vx])
        fxf = np.where(f_long < 0.0, share_front * f_long, 0.0)
        fxr = np.where(f_long < 0.0, (1.0 - share_front) * f_long, f_long)
        limit_f = utilization * mu * fzf
        limit_r = utilization * mu * fzr
        fxf = np.clip(fxf, np.maximum(lower[0], -0.8 * limit_f), upper[0])
        fxr = np.clip(fxr, np.maximum(lower[1], -0.8 * limit_r),
                      np.minimum(upper[1], 0.8 * limit_r))
        lat_room = np.sqrt(np.maximum(limit_f**2 - fxf**2, 0.0)) * 0.95
        fyf = np.clip(fyf, -lat_room, lat_room)
        u = np.zeros((3, m_count))
        u[Input.fyf], u[Input.fxf], u[Input.fxr] = fyf, fxf, fxr
        x = rk4_step(x, u, kappa, c_r, params, dt_s)
        x[State.vx] = np.maximum(x[State.vx], 0.0)
        ax = (fxf + fxr) / m
        xs.append(x)
        us.append(u)
    return np.stack(xs), np.stack(us)


def _curved(s: np.ndarray) -> np.ndarray:
    return np.where(np.asarray(s) < 40.0, 0.0, 0.02)


def _straight(s: np.ndarray) -> float:
    return 0.0  # a scalar: the roll-outs broadcast it


def _mu_patchy(s: np.ndarray) -> np.ndarray:
    return np.where(np.asarray(s) < 35.0, 0.9, 0.3)


@settings(max_examples=25, deadline=None)
@given(
    speed_mps=st.floats(0.0, 30.0), d0_m=st.floats(-3.0, 3.0), dpsi0=st.floats(-0.3, 0.3),
    vy0=st.floats(-1.0, 1.0), curved=st.booleans(), table=st.booleans(),
    n_lateral=st.integers(1, 9), horizon=st.integers(1, 40),
)
def test_rollouts_are_bitwise_the_straightforward_loop(
    speed_mps, d0_m, dpsi0, vy0, curved, table, n_lateral, horizon
) -> None:
    x0 = np.array([10.0, d0_m, dpsi0, 0.1 * dpsi0, speed_mps, vy0])
    lateral = np.append(np.linspace(-1.5, 5.0, n_lateral), 0.0)
    speeds = np.array([0.0, 0.5 * speed_mps, speed_mps, 20.0])
    args = (x0, lateral, speeds, _curved if curved else _straight, _mu_patchy, TRUCK, 0.9,
            horizon, 0.1, SamplingConfig())
    tire = AUTHORS_TIRES if table else None
    with np.errstate(all="ignore"):
        xs, us = candidate_rollouts(*args, stiffness_table=tire)
        ref_x, ref_u = _reference_rollouts(*args, stiffness_table=tire)
    assert xs.shape == ref_x.shape and us.shape == ref_u.shape
    np.testing.assert_array_equal(xs, ref_x)
    np.testing.assert_array_equal(us, ref_u)


@pytest.mark.parametrize("table", [None, AUTHORS_TIRES])
def test_diverging_candidates_match_the_reference(table) -> None:
    # Over-speed on low friction with a sharp curve: some candidates leave the finite range.
    x0 = np.array([0.0, 4.0, 1.2, 0.8, 35.0, 3.0])
    args = (x0, np.linspace(-8.0, 8.0, 9), np.array([0.0, 35.0]), lambda s: 0.3 + 0.0 * s,
            lambda s: np.where(np.asarray(s) < 20.0, 0.1, np.nan), TRUCK, 0.9, 40, 0.2,
            SamplingConfig())
    with np.errstate(all="ignore"):
        xs, us = candidate_rollouts(*args, stiffness_table=table)
        ref_x, ref_u = _reference_rollouts(*args, stiffness_table=table)
    np.testing.assert_array_equal(xs, ref_x)
    np.testing.assert_array_equal(us, ref_u)
