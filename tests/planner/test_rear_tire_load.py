"""The planner's linear rear tire at the rear load of the plan's own braking (decision 0066)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.ocp import (
    MIN_LOAD_SHARE,
    Param,
    constraint_expressions,
    ocp_rear_stiffness,
    plan_rear_stiffness,
    polygon_directions,
    stage_parameters,
)
from mufusion.planner.plan import StageParameters
from mufusion.vehicle.params import GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    rear_lateral_force_n,
    secant_stiffness_factor,
)
from mufusion.vehicle.tires import tire_forces

N = 8
MU, LAMBDA = 0.9, 0.9


def _stage() -> StageParameters:
    """A straight, unbraked guess at 17 m/s: the rear stiffness at the static rear load."""
    guess_x = np.zeros((N + 1, N_STATES))
    guess_x[:, State.vx] = 17.0
    guess_x[:, State.s] = 1.7 * np.arange(N + 1)
    return stage_parameters(guess_x, np.zeros((N, N_INPUTS)), lambda s: 0.0 * s,
                            lambda s: MU + 0.0 * s, TRUCK, LAMBDA)


def _braking(total_n: float) -> np.ndarray:
    forces = np.zeros((N, N_INPUTS))
    forces[:, Input.fxf], forces[:, Input.fxr] = 0.7 * total_n, 0.3 * total_n
    return forces


def _rear_load_n(total_n: float) -> float:
    # F_zr = m (g l_f + a_x h) / L by hand, floored as the polygons are.
    m = TRUCK.mass_kg
    load = m * (GRAVITY_MPS2 * TRUCK.cog_to_front_axle_m
                + total_n / m * TRUCK.cog_height_m) / TRUCK.wheelbase_m
    return max(load, MIN_LOAD_SHARE * m * GRAVITY_MPS2)


def test_without_load_transfer_the_stiffness_is_the_guess_s() -> None:
    stage = _stage()
    got = plan_rear_stiffness(stage.rear_stiffness_n_per_rad, stage.fzr_n, _braking(-40e3).T,
                              TRUCK, load_transfer=False)
    assert np.array_equal(got, stage.rear_stiffness_n_per_rad)


@pytest.mark.parametrize("total_n", [0.0, -20e3, -45e3, -80e3])
def test_braking_scales_the_stiffness_with_the_rear_load(total_n: float) -> None:
    stage = _stage()
    got = plan_rear_stiffness(stage.rear_stiffness_n_per_rad, stage.fzr_n, _braking(total_n).T,
                              TRUCK, load_transfer=True)
    expected = stage.rear_stiffness_n_per_rad * _rear_load_n(total_n) / _rear_load_n(0.0)
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    if total_n < 0.0:
        assert (got < 0.8 * stage.rear_stiffness_n_per_rad).all()


def test_the_ocp_rows_and_dynamics_take_the_same_stiffness_as_the_plan() -> None:
    """The CasADi expression (both backends) and the numpy one (the plan's logged rear force,
    the solution checks) agree, and the rear polygon's rows use it."""
    import casadi as ca

    stage = _stage()
    x, u, p = ca.SX.sym("x", N_STATES), ca.SX.sym("u", N_INPUTS), ca.SX.sym("p", len(Param))
    stiffness = ca.Function("c", [u, p], [ocp_rear_stiffness(p, u, TRUCK, True)])
    rows = ca.Function("h", [x, u, p], [constraint_expressions(x, u, p, TRUCK, 12,
                                                               load_transfer=True)])
    state = np.zeros(N_STATES)
    state[State.vx], state[State.vy], state[State.psidot] = 15.0, -1.0, 0.3
    for total in (0.0, -30e3, -60e3):
        forces = _braking(total)
        numpy_c = plan_rear_stiffness(stage.rear_stiffness_n_per_rad, stage.fzr_n, forces.T,
                                      TRUCK, load_transfer=True)
        casadi_c = float(stiffness(forces[0], stage.p[0]))
        assert casadi_c == pytest.approx(float(numpy_c[0]), rel=1e-12)
        fyr = float(rear_lateral_force_n(state, numpy_c[0], TRUCK))
        normals, ratio = polygon_directions(12)
        limit = ratio * LAMBDA * MU * _rear_load_n(total)
        rear = np.array([forces[0, Input.fxr], fyr])
        expected = (normals @ rear - limit) / stage.radius_rear_n[0]
        got = np.asarray(rows(state, forces[0], stage.p[0])).ravel()[12:]
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(accel=st.floats(-6.0, 0.0), share=st.floats(0.05, 1.0))
def test_the_plan_never_counts_on_rear_grip_the_braked_tire_lacks(accel: float,
                                                                  share: float) -> None:
    """At any rear slip angle up to where the linear tire reaches λ μ F_zr, the plan's rear force
    at its own braking stays at or below the tire's (Magic Formula at the braked load); the
    guess's stiffness (unbraked load) over-estimates it once the plan brakes hard."""
    stage = _stage()
    total = accel * TRUCK.mass_kg
    own_c = float(plan_rear_stiffness(stage.rear_stiffness_n_per_rad, stage.fzr_n,
                                      _braking(total).T, TRUCK, load_transfer=True)[0])
    load = _rear_load_n(total)
    slip_at_limit = LAMBDA * MU * load / own_c
    alpha = share * slip_at_limit
    tire = float(tire_forces(0.0, alpha, load, MU, TRUCK.tire)[1])
    assert own_c * alpha <= tire * (1.0 + 1e-9)
    guess_c = float(stage.rear_stiffness_n_per_rad[0])
    if accel < -3.0 and share > 0.9:
        assert guess_c * alpha > tire


def test_the_secant_factor_is_what_makes_the_bound_tight() -> None:
    """The property above holds with equality at the limit: the linear tire at the braked load
    meets the Magic Formula exactly at λ μ F_zr (the secant stiffness of the vehicle's tire)."""
    stage = _stage()
    total = -5.0 * TRUCK.mass_kg
    own_c = float(plan_rear_stiffness(stage.rear_stiffness_n_per_rad, stage.fzr_n,
                                      _braking(total).T, TRUCK, load_transfer=True)[0])
    load = _rear_load_n(total)
    per_load = TRUCK.tire.cornering_stiffness_per_load_1_per_rad
    assert own_c == pytest.approx(per_load * secant_stiffness_factor(TRUCK.tire, LAMBDA) * load,
                                  rel=1e-9)
    alpha = LAMBDA * MU * load / own_c
    assert float(tire_forces(0.0, alpha, load, MU, TRUCK.tire)[1]) == pytest.approx(
        LAMBDA * MU * load, rel=1e-6)
