"""The planner's Frenet bicycle model: numpy and CasADi agree, it vectorises, and it is sane."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.vehicle.params import CAR, GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    frenet_bicycle_dynamics,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
    rear_lateral_force_n,
)

finite = st.floats(-1.0, 1.0)


@settings(max_examples=40, deadline=None)
@given(
    s=st.floats(0.0, 200.0),
    d=st.floats(-3.0, 3.0),
    dpsi=st.floats(-0.5, 0.5),
    psidot=st.floats(-0.8, 0.8),
    vx=st.floats(0.0, 30.0),
    vy=st.floats(-2.0, 2.0),
    forces=st.tuples(finite, finite, finite),
    kappa=st.floats(-1 / 28.0, 1 / 28.0),
)
def test_numpy_and_casadi_agree(s, d, dpsi, psidot, vx, vy, forces, kappa) -> None:
    x = np.array([s, d, dpsi, psidot, vx, vy])
    u = 30_000.0 * np.asarray(forces)
    stiffness = rear_cornering_stiffness_n_per_rad(TRUCK, TRUCK.static_rear_load_n)
    xs, us, ks = ca.SX.sym("x", N_STATES), ca.SX.sym("u", N_INPUTS), ca.SX.sym("k")
    symbolic_rhs = frenet_bicycle_dynamics(xs, us, ks, stiffness, TRUCK)
    function = ca.Function("f", [xs, us, ks], [symbolic_rhs])
    symbolic = np.asarray(function(x, u, kappa)).reshape(-1)
    numeric = frenet_bicycle_dynamics(x, u, kappa, stiffness, TRUCK)
    np.testing.assert_allclose(numeric, symbolic, rtol=1e-12, atol=1e-9)


def test_an_output_buffer_is_refused_for_symbols() -> None:
    xs, us, ks = ca.SX.sym("x", N_STATES), ca.SX.sym("u", N_INPUTS), ca.SX.sym("k")
    with pytest.raises(ValueError, match="out"):
        frenet_bicycle_dynamics(xs, us, ks, 1e5, TRUCK, out=np.empty(N_STATES))


def test_vectorised_over_trailing_axes_equals_column_by_column() -> None:
    rng = np.random.default_rng(3)
    x = rng.normal(size=(N_STATES, 7, 5))
    x[State.vx] = np.abs(x[State.vx]) * 10.0
    u = rng.normal(size=(N_INPUTS, 7, 5)) * 5_000.0
    kappa = rng.uniform(-0.03, 0.03, size=(7, 5))
    stiffness = rng.uniform(1e5, 2e5, size=(7, 5))
    batch = frenet_bicycle_dynamics(x, u, kappa, stiffness, CAR)
    assert batch.shape == x.shape
    for i in range(7):
        for j in range(5):
            single = frenet_bicycle_dynamics(
                x[:, i, j], u[:, i, j], kappa[i, j], stiffness[i, j], CAR
            )
            np.testing.assert_allclose(batch[:, i, j], single, rtol=1e-14)


def test_straight_line_without_forces_keeps_speed_and_offset() -> None:
    x = np.array([10.0, 0.7, 0.0, 0.0, 15.0, 0.0])
    xd = frenet_bicycle_dynamics(x, np.zeros(3), 0.0, 1e5, TRUCK)
    np.testing.assert_allclose(xd, [15.0, 0.0, 0.0, 0.0, 0.0, 0.0], atol=1e-12)
    # Pure braking force decelerates at F/m.
    u = np.zeros(3)
    u[Input.fxf] = -20_000.0
    xd = frenet_bicycle_dynamics(x, u, 0.0, 1e5, TRUCK)
    assert xd[State.vx] == pytest.approx(-20_000.0 / TRUCK.mass_kg)


@pytest.mark.parametrize("kappa", [1 / 28.0, -1 / 50.0])
def test_steady_constant_curvature_cornering_is_an_equilibrium(kappa: float) -> None:
    speed, params = 12.0, TRUCK
    stiffness = rear_cornering_stiffness_n_per_rad(params, params.static_rear_load_n)
    lf, lr, m = params.cog_to_front_axle_m, params.cog_to_rear_axle_m, params.mass_kg
    vy = 0.0
    for _ in range(50):  # fixed point: side-slip, yaw rate and axle forces of steady cornering
        vx = np.sqrt(speed**2 - vy**2)
        yaw_rate = kappa * speed
        fyr = m * vx * yaw_rate * lf / (lf + lr)
        fyf = m * vx * yaw_rate * lr / (lf + lr)
        vy = lr * yaw_rate - fyr * vx / stiffness
    dpsi = -np.arctan2(vy, vx)
    x = np.array([0.0, 0.0, dpsi, yaw_rate, vx, vy])
    u = np.zeros(3)
    u[Input.fyf] = fyf
    u[Input.fxr] = -m * vy * yaw_rate  # keeps v_x constant
    xd = frenet_bicycle_dynamics(x, u, kappa, stiffness, params)
    assert xd[State.s] == pytest.approx(speed, rel=1e-9)
    np.testing.assert_allclose(xd[1:], 0.0, atol=1e-9)
    assert rear_lateral_force_n(x, stiffness, params) == pytest.approx(fyr, rel=1e-9)


def test_normal_loads_sum_to_weight_and_shift_forward_when_braking() -> None:
    fzf0, fzr0 = normal_loads_n(0.0, TRUCK)
    fzf, fzr = normal_loads_n(-5.0, TRUCK)
    assert fzf0 == pytest.approx(TRUCK.static_front_load_n)
    assert fzf + fzr == pytest.approx(TRUCK.mass_kg * GRAVITY_MPS2)
    assert fzf - fzf0 == pytest.approx(TRUCK.mass_kg * 5.0 * TRUCK.cog_height_m / 3.4)
    assert fzr < fzr0


@pytest.mark.parametrize("params", [TRUCK, CAR])
@pytest.mark.parametrize("utilization", [0.5, 0.9, 1.0])
def test_secant_rear_stiffness_never_promises_more_than_the_magic_formula(params, utilization):
    from mufusion.vehicle.tires import tire_forces

    mu, fz = 0.7, params.static_rear_load_n
    secant = float(rear_cornering_stiffness_n_per_rad(params, fz, utilization))
    tangent = float(rear_cornering_stiffness_n_per_rad(params, fz))
    assert secant < tangent
    # The linear force reaches the limit λ μ F_z at α*; up to there the real tire gives more.
    alpha_star = utilization * mu * fz / secant
    alphas = np.linspace(1e-4, alpha_star, 50)
    real = tire_forces(0.0, alphas, fz, mu, params.tire)[1]
    assert np.all(real >= secant * alphas - 1e-6 * fz)
    assert abs(real[-1] - utilization * mu * fz) < 1e-6 * fz


def test_secant_stiffness_rejects_utilization_outside_unit_interval():
    with pytest.raises(ValueError, match="utilization"):
        rear_cornering_stiffness_n_per_rad(TRUCK, 1e4, 1.2)
