"""Tire model and parameter sets."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from vehiclemodels.parameters_vehicle2 import parameters_vehicle2
from vehiclemodels.utils.tire_model import formula_lateral, formula_longitudinal

from mufusion.vehicle.params import CAR, TRUCK, TireParams, vehicle_preset
from mufusion.vehicle.tires import tire_forces, tire_forces_scalar


@settings(max_examples=60, deadline=None)
@given(
    kappa=st.floats(-1.0, 1.0),
    alpha=st.floats(-1.2, 1.2),
    fz=st.floats(-100.0, 60_000.0),
    mu=st.floats(0.05, 1.3),
)
def test_scalar_and_vectorised_tire_agree_and_stay_in_the_circle(
    kappa: float, alpha: float, fz: float, mu: float
) -> None:
    vec = tire_forces(np.array([kappa]), np.array([alpha]), fz, mu, TRUCK.tire)
    scalar = tire_forces_scalar(kappa, alpha, fz, mu, TRUCK.tire)
    for a, b in zip(vec, scalar, strict=True):
        assert float(a[0]) == pytest.approx(b, rel=1e-9, abs=1e-9)
    fx, fy, used, asked = scalar
    assert np.hypot(fx, fy) <= mu * max(fz, 0.0) * (1.0 + 1e-12)
    assert 0.0 <= used <= 1.0
    if fz > 1.0:
        assert used == pytest.approx(np.hypot(fx, fy) / (mu * fz), abs=1e-12)
    assert asked >= 0.0


@pytest.mark.parametrize("mu", [0.3, 0.7, 1.0])
def test_pure_slip_matches_commonroad_pac2002_with_peak_mu(mu: float) -> None:
    p = parameters_vehicle2()
    p.tire.p_dy1 = mu
    p.tire.p_dx1 = mu
    fz = 4500.0
    for alpha in np.linspace(-0.4, 0.4, 17):
        # CommonRoad's slip angle has the opposite sign (and p_ky1 < 0), the force the same.
        theirs, _ = formula_lateral(-alpha, 0.0, fz, p.tire)
        _, ours, _, _ = tire_forces_scalar(0.0, alpha, fz, mu, CAR.tire)
        assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-6)
    p.tire.p_hx1 = 0.0  # drop the small offsets that have no counterpart here
    p.tire.p_vx1 = 0.0
    for kappa in np.linspace(-0.3, 0.3, 13):
        # CommonRoad passes the negated slip of its own definition; its κ_x equals ours.
        theirs = formula_longitudinal(-kappa, 0.0, fz, p.tire)
        ours, _, _, _ = tire_forces_scalar(kappa, 0.0, fz, mu, CAR.tire)
        assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-6)


def test_stiffness_is_independent_of_mu_and_peak_scales_with_it() -> None:
    fz, small = 30_000.0, 1e-6
    for mu in (0.2, 0.5, 1.0):
        _, fy, _, _ = tire_forces_scalar(0.0, small, fz, mu, TRUCK.tire)
        assert fy / small == pytest.approx(
            TRUCK.tire.cornering_stiffness_per_load_1_per_rad * fz, rel=1e-6
        )
        alphas = np.linspace(0.0, 1.5, 3001)
        _, fys, used, _ = tire_forces(0.0, alphas, fz, mu, TRUCK.tire)
        assert np.max(fys) == pytest.approx(mu * fz, rel=1e-5)
        assert np.max(used) == pytest.approx(1.0, rel=1e-5)


def test_tire_rejects_non_positive_mu() -> None:
    with pytest.raises(ValueError, match="mu"):
        tire_forces(0.0, 0.1, 1000.0, np.array([0.5, 0.0]), TRUCK.tire)


def test_car_preset_is_commonroad_parameter_set_2() -> None:
    p = parameters_vehicle2()
    assert CAR.mass_kg == pytest.approx(p.m)
    assert CAR.yaw_inertia_kgm2 == pytest.approx(p.I_z)
    assert CAR.cog_to_front_axle_m == pytest.approx(p.a)
    assert CAR.cog_to_rear_axle_m == pytest.approx(p.b)
    assert CAR.cog_height_m == pytest.approx(p.h_cg)
    assert CAR.width_m == pytest.approx(p.w)
    assert CAR.length_m == pytest.approx(p.l)
    assert CAR.wheel_radius_m == pytest.approx(p.R_w)
    assert CAR.wheel_inertia_kgm2 == pytest.approx(p.I_y_w)
    assert CAR.max_steer_rad == pytest.approx(p.steering.max)
    assert CAR.max_steer_rate_radps == pytest.approx(p.steering.v_max)
    assert CAR.track_width_m == pytest.approx(0.5 * (p.T_f + p.T_r))
    assert CAR.tire.cornering_stiffness_per_load_1_per_rad == pytest.approx(-p.tire.p_ky1)
    assert CAR.tire.longitudinal_stiffness_per_load == pytest.approx(p.tire.p_kx1)
    assert CAR.tire.shape_lateral == pytest.approx(p.tire.p_cy1)
    assert CAR.tire.shape_longitudinal == pytest.approx(p.tire.p_cx1)


def test_truck_preset_matches_the_documented_data() -> None:
    assert TRUCK.mass_kg == 8350.0
    assert TRUCK.wheelbase_m == pytest.approx(3.4)
    assert TRUCK.static_front_load_n / 9.81 == pytest.approx(8350.0 * 5375.0 / 8335.0, rel=1e-9)
    assert TRUCK.yaw_inertia_kgm2 == pytest.approx(8350.0 * (6.28**2 + 2.6**2) / 12.0)


@pytest.mark.parametrize(
    "field, value",
    [("mass_kg", -1.0), ("yaw_inertia_kgm2", 0.0), ("wheel_radius_m", float("nan"))],
)
def test_bad_vehicle_parameters_name_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        replace(TRUCK, **{field: value})


@pytest.mark.parametrize(
    "field, value",
    [("shape_lateral", 2.5), ("curvature_longitudinal", 1.5),
     ("cornering_stiffness_per_load_1_per_rad", -3.0)],
)
def test_bad_tire_parameters_name_the_field(field: str, value: float) -> None:
    tire = TireParams(**{**TRUCK.tire.__dict__, field: value})
    with pytest.raises(ValueError, match=field):
        replace(TRUCK, tire=tire)


def test_unknown_preset_is_rejected() -> None:
    with pytest.raises(ValueError, match="vehicle must be one of"):
        vehicle_preset("bus")
