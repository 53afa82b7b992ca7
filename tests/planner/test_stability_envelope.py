"""The stability envelope (planner/stability.py): the state boxes both backends take per solve,
and a solver with them keeps its plan's yaw rate and body slip inside."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mufusion.planner.ocp import MAX_SPEED_MPS, Param, PlannerConfig
from mufusion.planner.stability import (
    MIN_ENVELOPE_SPEED_MPS,
    body_slip_speed_bound_mps,
    state_bounds,
    yaw_rate_bound_rps,
)
from mufusion.vehicle.params import GRAVITY_MPS2
from mufusion.vehicle.planner_model import N_STATES, State, normal_loads_n

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=3.95)


def _problem(cfg: PlannerConfig, mu_hat: np.ndarray, speed_mps: np.ndarray):
    n = cfg.horizon_steps
    guess_x = np.zeros((n + 1, N_STATES))
    guess_x[:, State.vx] = speed_mps
    p = np.zeros((n, len(Param)))
    p[:, Param.utilized_friction] = cfg.utilization_factor * mu_hat
    p[:, Param.utilized_friction_front] = p[:, Param.utilized_friction]
    return guess_x, p


def test_without_the_envelope_only_the_corridor_and_the_speed_are_bounded() -> None:
    n = CONFIG.horizon_steps
    guess_x, p = _problem(CONFIG, np.full(n, 0.9), np.full(n + 1, 15.0))
    d_lo, d_hi = np.linspace(-1.0, 0.0, n), np.linspace(1.0, 2.0, n)
    lower, upper = state_bounds(d_lo, d_hi, 2.0, guess_x, p, CONFIG)
    assert lower.shape == upper.shape == (n, 2)
    np.testing.assert_array_equal(lower, np.column_stack([d_lo, np.full(n, 2.0)]))
    np.testing.assert_array_equal(upper, np.column_stack([d_hi, np.full(n, MAX_SPEED_MPS)]))


def test_the_envelope_bounds_follow_each_stages_friction_and_the_guess_speed() -> None:
    cfg = dataclasses.replace(CONFIG, stability_envelope=True)
    n = cfg.horizon_steps
    mu = np.where(np.arange(n) < n // 2, 0.3, 0.9)
    speed = np.linspace(19.0, 0.2, n + 1)
    guess_x, p = _problem(cfg, mu, speed)
    lower, upper = state_bounds(np.zeros(n), np.ones(n), 0.0, guess_x, p, cfg)
    assert upper.shape == (n, 4)
    np.testing.assert_array_equal(lower[:, 2:], -upper[:, 2:])
    # Stage k (row k-1) takes stage k's μ̂ (the terminal the last stage's) and guess speed.
    mu_k = mu[np.minimum(np.arange(1, n + 1), n - 1)]
    v_k = np.maximum(speed[1:], MIN_ENVELOPE_SPEED_MPS)
    np.testing.assert_allclose(upper[:, 2] * v_k / (mu_k * GRAVITY_MPS2), 1.1)
    np.testing.assert_allclose(upper[:, 3] / (v_k * mu_k * GRAVITY_MPS2), 0.02)
    assert yaw_rate_bound_rps(np.array([0.3]), np.array([10.0]))[0] < yaw_rate_bound_rps(
        np.array([0.9]), np.array([10.0]))[0]
    assert body_slip_speed_bound_mps(np.array([0.9]), np.array([0.0]))[0] > 0.0


@pytest.mark.parametrize("backend_name", ["acados", "casadi"])
def test_a_solver_with_the_envelope_keeps_the_plans_yaw_rate_inside(backend_name) -> None:
    """A plan asked to track a yaw rate twice the bound's stays near the bound: the real-time
    iterations and the reference backend solved to convergence alike."""
    from mufusion.vehicle.params import TRUCK

    bounded = []
    for envelope in (False, True):
        cfg = dataclasses.replace(CONFIG, stability_envelope=envelope)
        if backend_name == "acados":
            from mufusion.planner.acados_backend import AcadosBackend

            backend, iterations = AcadosBackend(TRUCK, cfg, robust_retry=False), 15
        else:
            from mufusion.planner.casadi_backend import CasadiBackend

            backend, iterations = CasadiBackend(TRUCK, cfg), 1
        n = cfg.horizon_steps
        mu, speed = 0.3, 15.0
        guess_x, p = _problem(cfg, np.full(n, mu), np.full(n + 1, speed))
        guess_x[:, State.s] = speed * cfg.dt_s * np.arange(n + 1)
        p[:, Param.radius_front] = p[:, Param.radius_rear] = mu * TRUCK.mass_kg * GRAVITY_MPS2
        # The rear stiffness applies at the guess's rear load, the rear radius over λ μ̂, and
        # follows the plan's own (decision 0066): 3e5 N/rad at the static load.
        guess_load = p[:, Param.radius_rear] / p[:, Param.utilized_friction]
        p[:, Param.rear_stiffness] = 3e5 * guess_load / normal_loads_n(0.0, TRUCK)[1]
        guess_u = np.zeros((n, 3))
        bound = float(yaw_rate_bound_rps(np.array([mu]), np.array([speed]))[0])
        yref = np.zeros((n + 1, N_STATES + 3))
        yref[:, State.vx], yref[:, State.psidot] = speed, 2.0 * bound
        weights = np.ones(N_STATES + 3)
        weights[State.psidot] = 1e2
        weights[N_STATES:] = 1e-8
        for _ in range(iterations):
            status, xs, us = backend.solve(guess_x[0], guess_x, guess_u, p, yref, weights,
                                           np.full(n, -5.0), np.full(n, 5.0), 0.0)
            guess_x, guess_u = xs, us
        assert status in (0, 2), status
        # Stages 1 … N-1: the terminal stage bounds d only.
        bounded.append(float(np.max(np.abs(xs[1:n, State.psidot]))))
    free, enveloped = bounded
    assert free > 1.2 * bound  # the case needs the bound
    assert enveloped < 1.05 * bound


def test_a_curve_fraction_outside_0_1_is_refused_by_name() -> None:
    for bad in (0.0, 1.2):
        with pytest.raises(ValueError, match="reference_curve_fraction"):
            dataclasses.replace(CONFIG, reference_curve_fraction=bad)
