"""The transient oracle: its model is the plant's, and its verdict separates what physics allows."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.road import FrictionMap, turn_road
from mufusion.scenarios.feasibility.transient import (
    _spatial_model,
    _unit_tire,
    least_lane_excursion,
)
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.plant_kernel import PlantKernel, unit_tire


@settings(max_examples=60, deadline=None)
@given(kappa=st.floats(-0.4, 0.4), alpha=st.floats(-0.4, 0.4), mu=st.floats(0.1, 1.2),
       truck=st.booleans())
def test_unit_tire_is_the_plants(kappa: float, alpha: float, mu: float, truck: bool) -> None:
    tire = (TRUCK if truck else CAR).tire
    if math.hypot(kappa, alpha) < 1e-4:
        return  # the smoothing of the slip's magnitude: a force of order 1e-6 per unit load there
    gx, gy = _unit_tire(ca, kappa, alpha, mu, tire)
    ref = unit_tire(kappa, alpha, mu, tire)
    assert float(gx) == pytest.approx(ref[0], rel=1e-6, abs=1e-9)
    assert float(gy) == pytest.approx(ref[1], rel=1e-6, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(vx=st.floats(5.0, 35.0), vy=st.floats(-1.5, 1.5), r=st.floats(-0.5, 0.5),
       steer=st.floats(-0.1, 0.1), kappa_f=st.floats(-0.1, 0.0), kappa_r=st.floats(-0.1, 0.1),
       truck=st.booleans())
def test_spatial_model_is_the_plants_rates(vx: float, vy: float, r: float, steer: float,
                                           kappa_f: float, kappa_r: float, truck: bool) -> None:
    """On a straight lane with the body along it, ``dx/ds · ṡ`` are the plant's body rates."""
    params = TRUCK if truck else CAR
    model = _spatial_model(ca, params, params.tire, params.tire)
    mu_f, mu_r = 0.7, 0.5
    x = [0.0, 0.0, vx, vy, r, steer, 0.0]
    rates_per_m, fx_f, fx_r = model(x, [steer, kappa_f, kappa_r], [0.0, mu_f, mu_r])
    rates = np.asarray(rates_per_m).ravel() * vx  # ṡ = v_x on a straight, ψ = 0
    kernel = PlantKernel(params, 0.005)
    speeds = kernel.wheel_speeds(vx, vy, r, steer)
    radius = params.wheel_radius_m
    # Wheel spins that give these slip ratios (κ = (R ω − u) / u).
    omega_f = (1.0 + kappa_f) * speeds[0] / radius
    omega_r = (1.0 + kappa_r) * speeds[2] / radius
    front, rear = kernel.axles(speeds, omega_f, omega_r, mu_f, mu_r, params.tire, params.tire)
    ref = kernel.rates(0.0, vx, vy, r, steer, 0.0, 0.0, speeds[4], speeds[5], front, rear,
                       (steer, 0.0, 0.0))
    assert float(fx_f) == pytest.approx(front[0], rel=1e-6, abs=1e-3)
    assert float(fx_r) == pytest.approx(rear[0], rel=1e-6, abs=1e-3)
    # v̇_x, v̇_y, ψ̈ of the plant; lateral speed n' = v_y; heading rate ψ̇ on a straight.
    assert rates[2:5] == pytest.approx(ref[3:6], rel=1e-6, abs=1e-6)
    assert rates[0] == pytest.approx(vy, rel=1e-9, abs=1e-9)
    assert rates[1] == pytest.approx(r, rel=1e-9, abs=1e-9)
    assert rates[6] == pytest.approx(1.0)  # dt/ds · ṡ


def _car_turn(mu: float, radius_m: float, approach_m: float, lane_width_m: float = 3.5):
    road = turn_road(radius_m=radius_m, approach_m=approach_m, exit_m=60.0, clothoid_m=0.0,
                     direction="left", lane_width_m=lane_width_m,
                     friction=FrictionMap.uniform(mu), angle_rad=0.8)
    return road, approach_m + radius_m * 0.8 + 15.0


def test_a_turn_within_the_tires_is_kept_and_the_least_time_is_driven() -> None:
    """R 40 m on μ 0.9 from 14 m/s: a point mass needs no braking (v²/R = 0.50 g); the body
    stays in the lane and nothing forces the speed down."""
    road, end_m = _car_turn(0.9, 40.0, 20.0)
    verdict = least_lane_excursion(road, CAR, 0.0, 14.0, end_m, ds_m=2.0)
    assert verdict.converged
    assert verdict.excursion_m < 1e-3
    assert verdict.speed_mps.min() > 13.0
    assert np.all(np.diff(verdict.time_s) > 0.0)


def test_a_turn_beyond_the_tires_leaves_the_lane() -> None:
    """R 15 m on μ 0.3 entered from 20 m/s with 8 m to brake: the point mass holds 6.6 m/s there
    and reaches 18.8 m/s at best, so no driver keeps the body in the lane."""
    road, end_m = _car_turn(0.3, 15.0, 8.0)
    verdict = least_lane_excursion(road, CAR, 0.0, 20.0, end_m, ds_m=2.0)
    assert verdict.converged
    assert verdict.excursion_m > 0.5
    assert verdict.excursion_at_m.max() == pytest.approx(verdict.excursion_m, abs=1e-3)


@pytest.mark.parametrize(("field", "kwargs"), [
    ("entry_speed_mps", {"entry_speed_mps": -1.0}),
    ("end_s_m", {"end_s_m": 5.0}),
    ("ds_m", {"ds_m": 0.0}),
    ("start_s_m", {"start_s_m": math.nan}),
])
def test_bad_input_names_the_field(field: str, kwargs: dict) -> None:
    road, end_m = _car_turn(0.9, 40.0, 20.0)
    args = {"start_s_m": 0.0, "entry_speed_mps": 14.0, "end_s_m": end_m, **kwargs}
    with pytest.raises(ValueError, match=field):
        least_lane_excursion(road, CAR, **args)
