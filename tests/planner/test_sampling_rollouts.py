"""The sampling roll-outs on buffers give, bit for bit, the straightforward evaluation of the model.

The reference below is the obvious loop: the public model functions called on fresh arrays, the
RK4 written as the formula, the trajectories stacked at the end. Compared through the bit patterns
(``-0.0`` ≠ ``0.0``, NaN payloads count), on random states, targets, curvature and μ̂ profiles, with
the fixed rear tire and with the stiffness table. The compiled loop is held to the same bits
except a NaN's sign and payload (a C compiler may rewrite ``-0.8 * x`` as ``-(0.8 * x)`` or
return either NaN of two operands): NaN appears exactly where the reference has one; those
candidates diverged and the planner discards them.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from mufusion.planner.ocp import longitudinal_force_bounds_n
from mufusion.planner.sampling import (
    RK4Workspace,
    SamplingConfig,
    candidate_rollouts,
    compiled_rollouts_available,
    rk4_step,
    steering_force_n,
)
from mufusion.vehicle.params import CAR, TRUCK, VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    State,
    frenet_bicycle_dynamics,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
)
from mufusion.vehicle.surface_tires import (
    AUTHORS_TIRES,
    AUTHORS_TIRES_INTERPOLATED,
    SurfaceTireTable,
)

N, DT_S = 40, 0.1


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _same(got: np.ndarray, want: np.ndarray, kind: str) -> bool:
    """Bitwise equal; for the compiled loop, every NaN counted as one NaN."""
    if kind == "numpy":
        return np.array_equal(_bits(got), _bits(want))
    canonical = [np.where(np.isnan(a), np.nan, a) for a in (got, want)]
    return np.array_equal(_bits(canonical[0]), _bits(canonical[1]))


KINDS = ["numpy", "compiled"]


def _reference_rk4(x, u, kappa, c_r, params, dt_s):
    k1 = frenet_bicycle_dynamics(x, u, kappa, c_r, params)
    k2 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k1, u, kappa, c_r, params)
    k3 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k2, u, kappa, c_r, params)
    k4 = frenet_bicycle_dynamics(x + dt_s * k3, u, kappa, c_r, params)
    return x + dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def _reference_rollouts(
    x0: np.ndarray, lateral: np.ndarray, speeds: np.ndarray, curvature_of_s: Callable,
    mu_hat_of_s: Callable, params: VehicleParams, lam: float, config: SamplingConfig,
    table: SurfaceTireTable | None,
) -> tuple[np.ndarray, np.ndarray]:
    d_t, v_t = (a.ravel() for a in np.meshgrid(lateral, speeds))
    count = d_t.size
    x = np.repeat(np.asarray(x0, dtype=float)[:, None], count, axis=1)
    lower, upper = longitudinal_force_bounds_n(params)
    m = params.mass_kg
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    xs, us, ax = [x], [], np.zeros(count)
    for _ in range(N):
        v = np.maximum(x[State.vx], 1.0)
        kappa = np.asarray(curvature_of_s(x[State.s]), dtype=float) * np.ones(count)
        mu = np.asarray(mu_hat_of_s(x[State.s]), dtype=float) * np.ones(count)
        fzf, fzr = normal_loads_n(ax, params)
        mu_stiffness = np.where(np.isfinite(mu) & (mu > 0.0), mu, 1.0)
        c_r = rear_cornering_stiffness_n_per_rad(params, fzr, lam, mu_hat=mu_stiffness,
                                                 table=table)
        fyf = steering_force_n(x, d_t, kappa, v, params, config)
        f_long = m * config.speed_gain_1_per_s * (v_t - x[State.vx])
        fxf = np.where(f_long < 0.0, share_front * f_long, 0.0)
        fxr = np.where(f_long < 0.0, (1.0 - share_front) * f_long, f_long)
        limit_f, limit_r = lam * mu * fzf, lam * mu * fzr
        fxf = np.minimum(np.maximum(fxf, np.maximum(lower[0], -0.8 * limit_f)), upper[0])
        fxr = np.minimum(np.maximum(fxr, np.maximum(lower[1], -0.8 * limit_r)),
                         np.minimum(upper[1], 0.8 * limit_r))
        lat_room = np.sqrt(np.maximum(limit_f**2 - fxf**2, 0.0)) * 0.95
        fyf = np.minimum(np.maximum(fyf, -lat_room), lat_room)
        u = np.stack([fyf, fxf, fxr])
        x = _reference_rk4(x, u, kappa, c_r, params, DT_S)
        x[State.vx] = np.maximum(x[State.vx], 0.0)
        ax = (fxf + fxr) / m
        xs.append(x)
        us.append(u)
    return np.stack(xs), np.stack(us)


def _random_case(seed: int):
    """A state, targets, a curvature profile and a μ̂ profile drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    x0 = np.array([
        rng.uniform(0.0, 100.0), rng.uniform(-2.0, 2.0), rng.uniform(-0.3, 0.3),
        rng.uniform(-0.3, 0.3), rng.uniform(8.0, 25.0), rng.uniform(-0.5, 0.5),
    ])
    lateral = np.append(np.linspace(-1.5, 3.5, 9), rng.uniform(-1.0, 1.0))
    speeds = np.append(np.array([0.0, 0.5, 1.0]) * rng.uniform(5.0, 25.0), x0[State.vx])
    knots_s = np.sort(rng.uniform(0.0, 300.0, 6))
    kappa_knots = rng.uniform(-1 / 30.0, 1 / 30.0, 6)
    mu_knots = rng.uniform(0.1, 1.1, 6)

    def curvature_of_s(s: np.ndarray) -> np.ndarray:
        return np.interp(s, knots_s, kappa_knots)

    def mu_hat_of_s(s: np.ndarray) -> np.ndarray:
        return np.interp(s, knots_s, mu_knots)

    return x0, lateral, speeds, curvature_of_s, mu_hat_of_s


TABLES = [None, AUTHORS_TIRES, AUTHORS_TIRES_INTERPOLATED]


@pytest.mark.filterwarnings("error")  # not even an ignored warning in the hot loop
@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("table", TABLES, ids=["fixed-tire", "table-step", "table-linear"])
@pytest.mark.parametrize("kind", KINDS)
def test_rollouts_are_bitwise_the_straightforward_evaluation(seed: int, table, kind: str) -> None:
    x0, lateral, speeds, curvature_of_s, mu_hat_of_s = _random_case(seed)
    params = TRUCK if seed % 2 == 0 else CAR
    lam = (0.9, 0.8, 0.75)[seed % 3]
    config = SamplingConfig()
    with np.errstate(all="ignore"):
        xs, us = candidate_rollouts(x0, lateral, speeds, curvature_of_s, mu_hat_of_s, params,
                                    lam, N, DT_S, config, stiffness_table=table, kind=kind)
        ref_x, ref_u = _reference_rollouts(x0, lateral, speeds, curvature_of_s, mu_hat_of_s,
                                           params, lam, config, table)
    m_count = lateral.size * speeds.size
    assert xs.shape == (N + 1, N_STATES, m_count) and us.shape == (N, N_INPUTS, m_count)
    assert _same(xs, ref_x, kind) and _same(us, ref_u, kind)
    # The candidates do move apart (the comparison is not of constants).
    final_d = xs[-1, State.d][np.isfinite(xs[-1, State.d])]
    assert final_d.size >= m_count // 2 and np.ptp(final_d) > 0.1


@pytest.mark.parametrize("kind", KINDS)
def test_scalar_profiles_and_non_finite_mu_are_bitwise_too(kind: str) -> None:
    """A path answering one curvature for all candidates; μ̂ NaN beyond a point (a diverged or
    far candidate: the stiffness falls back, the limits go NaN)."""
    x0, lateral, speeds, _, _ = _random_case(11)
    x0[State.vx] = 20.0

    def mu_hat_of_s(s: np.ndarray) -> np.ndarray:
        return np.where(s < x0[State.s] + 30.0, 0.6, np.nan)

    with np.errstate(all="ignore"):
        for table in (None, AUTHORS_TIRES):
            args = (x0, lateral, speeds, lambda s: 0.01, mu_hat_of_s, TRUCK, 0.9)
            xs, us = candidate_rollouts(*args, N, DT_S, SamplingConfig(), stiffness_table=table,
                                        kind=kind)
            ref_x, ref_u = _reference_rollouts(*args, SamplingConfig(), table)
            assert np.isnan(xs).any()
            assert _same(xs, ref_x, kind) and _same(us, ref_u, kind)


@pytest.mark.parametrize("batch", [(), (7,), (3, 5)])
def test_rk4_step_with_workspace_is_bitwise_the_formula(batch: tuple[int, ...]) -> None:
    rng = np.random.default_rng(5)
    x = rng.normal(size=(N_STATES, *batch))
    x[State.vx] = np.abs(x[State.vx]) * 10.0
    u = rng.normal(size=(N_INPUTS, *batch)) * 5_000.0
    kappa = rng.uniform(-0.03, 0.03, size=batch)
    c_r = rng.uniform(1e5, 2e5, size=batch)
    expected = _reference_rk4(x, u, kappa, c_r, TRUCK, DT_S)
    plain = rk4_step(x, u, kappa, c_r, TRUCK, DT_S)
    out = np.full_like(x, np.nan)
    buffered = rk4_step(x, u, kappa, c_r, TRUCK, DT_S, out=out,
                        workspace=RK4Workspace.for_states(x.shape))
    assert buffered is out
    assert np.array_equal(_bits(plain), _bits(expected))
    assert np.array_equal(_bits(buffered), _bits(expected))
    # The inputs are left as they were.
    assert np.array_equal(_bits(rk4_step(x, u, kappa, c_r, TRUCK, DT_S)), _bits(expected))


def test_dynamics_into_a_buffer_is_bitwise_the_allocating_call() -> None:
    rng = np.random.default_rng(9)
    x = rng.normal(size=(N_STATES, 12))
    u = rng.normal(size=(N_INPUTS, 12)) * 5_000.0
    kappa, c_r = rng.uniform(-0.03, 0.03, 12), rng.uniform(1e5, 2e5, 12)
    out = np.empty_like(x)
    got = frenet_bicycle_dynamics(x, u, kappa, c_r, TRUCK, out=out)
    assert got is out
    assert np.array_equal(_bits(out), _bits(frenet_bicycle_dynamics(x, u, kappa, c_r, TRUCK)))


def test_the_install_built_the_compiled_rollouts() -> None:
    # `pip install -e .` compiles the loop; without it sampling silently takes the slower path.
    assert compiled_rollouts_available()


def test_an_unknown_rollout_kind_is_refused_by_name() -> None:
    x0, lateral, speeds, curvature_of_s, mu_hat_of_s = _random_case(0)
    with pytest.raises(ValueError, match="kind must be one of auto, compiled, numpy"):
        candidate_rollouts(x0, lateral, speeds, curvature_of_s, mu_hat_of_s, CAR, 0.9, N, DT_S,
                           SamplingConfig(), kind="fast")
