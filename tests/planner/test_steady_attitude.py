"""The curve's steady attitude in the cruise reference (docs/decisions/0113)."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mufusion.planner.config import PlannerConfig
from mufusion.planner.ocp import tracking_reference
from mufusion.planner.steady_attitude import steady_cornering_attitude
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import Input, State, frenet_bicycle_dynamics


@given(kappa=st.floats(-1 / 15, 1 / 15), speed=st.floats(1.5, 35.0),
       stiffness=st.floats(5e4, 5e5), truck=st.booleans())
def test_the_attitude_is_the_plans_models_equilibrium_on_the_centre_line(
        kappa: float, speed: float, stiffness: float, truck: bool) -> None:
    params = TRUCK if truck else CAR
    vy, dpsi = steady_cornering_attitude(np.array(kappa), np.array(speed),
                                         np.array(stiffness), params)
    x = np.zeros(6)
    x[State.dpsi], x[State.psidot], x[State.vx], x[State.vy] = dpsi, kappa * speed, speed, vy
    u = np.zeros(3)
    # The front carries the rest of the lateral force, the longitudinal force holds v_x.
    lateral_n = params.mass_kg * kappa * speed**2
    u[Input.fyf] = lateral_n * params.cog_to_rear_axle_m / params.wheelbase_m
    u[Input.fxr] = -params.mass_kg * vy * kappa * speed
    xd = frenet_bicycle_dynamics(x, u, kappa, stiffness, params)
    weight = params.mass_kg * 9.81
    assert abs(xd[State.d]) <= 1e-9 * speed  # moving along the lane
    assert abs(xd[State.psidot]) * params.yaw_inertia_kgm2 <= 1e-9 * weight  # no yaw moment
    assert abs(xd[State.vy]) <= 1e-9 * 9.81  # no lateral acceleration left
    # The yaw rate follows the lane to first order in the heading (ṡ = v / cos Δψ).
    assert abs(xd[State.dpsi]) <= abs(kappa) * speed * dpsi**2 + 1e-12


def test_the_nose_points_into_the_curve_at_speed_and_the_rear_follows_the_path_when_slow():
    vy, dpsi = steady_cornering_attitude(np.array([0.02, 0.02, -0.02, 0.0]),
                                         np.array([1.5, 25.0, 25.0, 25.0]),
                                         np.full(4, 2e5), TRUCK)
    # Slow in a left curve: the kinematic attitude, the rear axle on the path (v_y = l_r κ v).
    assert vy[0] == pytest.approx(TRUCK.cog_to_rear_axle_m * 0.02 * 1.5, rel=0.05)
    # At speed the rear's slip angle turns the nose in: left curve +, right curve −.
    assert dpsi[1] > 0.02 and dpsi[2] == pytest.approx(-dpsi[1]) and vy[1] < 0.0
    assert vy[3] == 0.0 and dpsi[3] == 0.0


def test_a_stiffness_that_is_not_positive_is_refused():
    with pytest.raises(ValueError, match="rear_stiffness_n_per_rad"):
        steady_cornering_attitude(np.array([0.01]), np.array([10.0]), np.array([0.0]), TRUCK)


def test_the_reference_takes_the_attitude_and_is_zero_without_it():
    cfg = PlannerConfig(horizon_steps=10)
    kappa = np.full(10, 0.01)
    vy, dpsi = np.linspace(-1.0, 0.0, 11), np.linspace(0.05, 0.0, 11)
    plain, _ = tracking_reference(cfg, kappa, np.full(10, 0.9), "cruise", 20.0, 20.0, 0.0)
    with_it, _ = tracking_reference(cfg, kappa, np.full(10, 0.9), "cruise", 20.0, 20.0, 0.0,
                                    (vy, dpsi))
    assert np.all(plain[:, State.vy] == 0.0) and np.all(plain[:, State.dpsi] == 0.0)
    np.testing.assert_array_equal(with_it[:, State.vy], vy)
    np.testing.assert_array_equal(with_it[:, State.dpsi], dpsi)
    others = [c for c in range(plain.shape[1]) if c not in (State.vy, State.dpsi)]
    np.testing.assert_array_equal(with_it[:, others], plain[:, others])
