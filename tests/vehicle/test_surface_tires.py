"""Surface-dependent tires: the authors' coefficient sets, checked against CommonRoad's PAC2002."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from vehiclemodels.parameters_vehicle2 import parameters_vehicle2
from vehiclemodels.utils.tire_model import formula_lateral, formula_longitudinal

from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.surface_tires import (
    AUTHORS_TIRES,
    AUTHORS_TIRES_INTERPOLATED,
    SurfaceTire,
    SurfaceTireTable,
    cornering_stiffness_per_load,
    lateral_force_n,
    tire_for_surface,
    tire_table,
)
from mufusion.vehicle.tires import tire_forces, tire_forces_scalar

TABLES = [AUTHORS_TIRES, AUTHORS_TIRES_INTERPOLATED]
ALPHAS = np.linspace(0.0, 1.2, 24001)


def _bce(table, mu):
    return tuple(float(v) for v in table.coefficients(mu))


@pytest.mark.parametrize(
    ("mu", "name", "bce"),
    [
        (0.2, "ice", (4.0, 2.0, 1.0)),
        (0.4, "snow", (5.0, 2.0, 1.0)),
        (0.5, "wet", (12.0, 2.3, 1.0)),
        (0.8, "wet", (12.0, 2.3, 1.0)),
        (0.89, "wet", (12.0, 2.3, 1.0)),
        (0.9, "dry", (10.0, 1.9, 0.97)),
        (1.6, "dry-racing", (12.56, 1.38, 1.0)),
    ],
)
def test_authors_table_switches_sets_by_mu_interval(mu, name, bce):
    assert AUTHORS_TIRES.at(mu).name == name
    assert _bce(AUTHORS_TIRES, mu) == pytest.approx(bce)


def test_interpolated_table_is_exact_at_the_turn_surfaces_and_linear_between():
    for mu in (0.4, 0.8):
        assert _bce(AUTHORS_TIRES_INTERPOLATED, mu) == pytest.approx(_bce(AUTHORS_TIRES, mu))
    assert _bce(AUTHORS_TIRES_INTERPOLATED, 0.6) == pytest.approx((8.5, 2.15, 1.0))
    assert _bce(AUTHORS_TIRES_INTERPOLATED, 1.2) == pytest.approx((12.0, 2.3, 1.0))  # held
    assert _bce(AUTHORS_TIRES_INTERPOLATED, 0.05) == pytest.approx((4.0, 2.0, 1.0))


def test_cornering_stiffness_for_mu_hat_is_bcmu_and_default_is_fixed():
    assert cornering_stiffness_per_load([0.4, 0.8], TRUCK.tire, AUTHORS_TIRES) == pytest.approx(
        [4.0, 22.08]
    )
    mu_hat = np.array([[0.3, 0.45], [0.6, 1.0]])
    fixed = cornering_stiffness_per_load(mu_hat, TRUCK.tire)
    assert fixed.shape == mu_hat.shape and np.all(fixed == 7.0)


@pytest.mark.parametrize("table", TABLES, ids=lambda t: t.name)
@pytest.mark.parametrize("mu", [0.2, 0.4, 0.55, 0.8, 0.89, 1.0])
def test_helper_stiffness_is_the_force_models_slope(table, mu):
    fz, small = 20_000.0, 1e-7
    tire = tire_for_surface(mu, TRUCK.tire, table)
    _, fy, _, _ = tire_forces_scalar(0.0, small, fz, mu, tire)
    expected = float(cornering_stiffness_per_load(mu, TRUCK.tire, table))
    assert fy / (small * fz) == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("table", TABLES, ids=lambda t: t.name)
@pytest.mark.parametrize("mu", [0.2, 0.4, 0.7, 0.8, 1.0])
def test_pure_slip_matches_commonroad_pac2002_with_the_sets_coefficients(table, mu):
    b, c, e = _bce(table, mu)
    p = parameters_vehicle2().tire
    p.p_dy1, p.p_cy1, p.p_ey1 = mu, c, e
    p.p_ky1 = -b * c * mu  # CommonRoad: K_y = p_ky1 F_z, negative with its slip-angle sign
    p.p_dx1, p.p_cx1, p.p_ex1 = mu, c, e
    p.p_kx1 = TRUCK.tire.longitudinal_stiffness_per_load
    p.p_hx1 = p.p_vx1 = 0.0  # offsets without a counterpart here
    fz = 30_000.0
    tire = tire_for_surface(mu, TRUCK.tire, table)
    for alpha in np.linspace(-0.6, 0.6, 25):
        theirs, _ = formula_lateral(-alpha, 0.0, fz, p)
        _, ours, _, _ = tire_forces_scalar(0.0, alpha, fz, mu, tire)
        assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-6)
        assert float(lateral_force_n(alpha, fz, mu, table)) == pytest.approx(theirs, rel=1e-9,
                                                                            abs=1e-6)
    for kappa in np.linspace(-0.5, 0.5, 21):
        theirs = formula_longitudinal(-kappa, 0.0, fz, p)
        ours, _, _, _ = tire_forces_scalar(kappa, 0.0, fz, mu, tire)
        assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-6)


def _peak(fy):
    i = int(np.argmax(fy))
    return float(fy[i]), float(ALPHAS[i])


def test_authors_sets_against_the_commonroad_car_tire_scaled_by_mu():
    # CommonRoad's BMW 320i tire with its peak factor scaled to μ (docs: references) keeps its
    # stiffness, 21.92 /rad per unit load, on every surface; the authors' tire is about as stiff
    # on their μ 0.8 set and 5.5 times softer on snow, where it peaks at 5.5 times the slip angle.
    fz = 4000.0
    p = parameters_vehicle2().tire
    rows = {}
    for mu in (0.4, 0.8):
        p.p_dy1 = mu
        cr = np.array([formula_lateral(-a, 0.0, fz, p)[0] for a in ALPHAS[::10]])
        cr_peak, cr_alpha = float(cr.max()), float(ALPHAS[::10][int(np.argmax(cr))])
        ours_peak, ours_alpha = _peak(lateral_force_n(ALPHAS, fz, mu, AUTHORS_TIRES))
        k_cr = abs(p.p_ky1)
        k_ours = float(cornering_stiffness_per_load(mu, CAR.tire, AUTHORS_TIRES))
        rows[mu] = (k_cr, k_ours, cr_alpha, ours_alpha)
        # Both peaks are μ F_z (CommonRoad's shifts S_hy, S_vy vanish at zero camber).
        assert cr_peak == pytest.approx(mu * fz, rel=1e-3)
        assert ours_peak == pytest.approx(mu * fz, rel=1e-6)
    assert rows[0.4][0] == rows[0.8][0] == pytest.approx(21.92)
    assert rows[0.4][1] == pytest.approx(4.0) and rows[0.8][1] == pytest.approx(22.08)
    assert rows[0.4][2] == pytest.approx(0.057, abs=1e-3)
    assert rows[0.8][2] == pytest.approx(0.114, abs=1e-3)
    assert rows[0.4][3] == pytest.approx(0.311, abs=1e-3)
    assert rows[0.8][3] == pytest.approx(0.088, abs=1e-3)


def test_default_truck_tire_keeps_its_stiffness_so_its_peak_slip_grows_with_mu():
    # The default model, for contrast: 7 /rad per unit load on every surface, so the peak moves
    # to larger slip angles as μ grows (the opposite of the authors' sets).
    fz = 4000.0
    peaks = {}
    for mu in (0.4, 0.8):
        _, fy, _, _ = tire_forces(0.0, ALPHAS, fz, mu, TRUCK.tire)
        peaks[mu] = _peak(fy)[1]
        assert float(cornering_stiffness_per_load(mu, TRUCK.tire)) == 7.0
    assert peaks[0.4] == pytest.approx(0.196, abs=1e-3)
    assert peaks[0.8] == pytest.approx(0.391, abs=1e-3)


@pytest.mark.parametrize(
    ("mu", "stiffness", "alpha_peak"),
    [(0.2, 1.6, 0.389), (0.4, 4.0, 0.311), (0.8, 22.08, 0.088), (1.0, 19.0, 0.180)],
)
def test_each_authors_set_stiffness_and_peak_slip_angle(mu, stiffness, alpha_peak):
    fz = 1000.0
    peak, alpha = _peak(lateral_force_n(ALPHAS, fz, mu, AUTHORS_TIRES))
    assert peak == pytest.approx(mu * fz, rel=1e-6)
    assert alpha == pytest.approx(alpha_peak, abs=1e-3)
    assert float(cornering_stiffness_per_load(mu, TRUCK.tire, AUTHORS_TIRES)) == pytest.approx(
        stiffness
    )


def test_past_the_peak_the_wet_set_falls_off_far_more_than_snow():
    fz = 1000.0
    snow = lateral_force_n(np.pi / 2, fz, 0.4, AUTHORS_TIRES) / (0.4 * fz)
    wet = lateral_force_n(np.pi / 2, fz, 0.8, AUTHORS_TIRES) / (0.8 * fz)
    # With E = 1 the curve tends to sin(C atan(π/2)) as α grows: 0.906 (C = 2), 0.739 (C = 2.3).
    assert float(snow) == pytest.approx(0.936, abs=1e-3)
    assert float(wet) == pytest.approx(0.763, abs=1e-3)


@settings(max_examples=80, deadline=None)
@given(
    kappa=st.floats(-1.0, 1.0),
    alpha=st.floats(-1.5, 1.5),
    mu=st.floats(0.05, 2.0),
    interpolated=st.booleans(),
)
def test_combined_slip_stays_in_the_circle_and_never_reverses(kappa, alpha, mu, interpolated):
    table = AUTHORS_TIRES_INTERPOLATED if interpolated else AUTHORS_TIRES
    tire = tire_for_surface(mu, TRUCK.tire, table)
    fz = 25_000.0
    fx, fy, used, _ = tire_forces_scalar(kappa, alpha, fz, mu, tire)
    vec = tire_forces(np.array([kappa]), np.array([alpha]), fz, mu, tire)
    assert float(vec[0][0]) == pytest.approx(fx, rel=1e-9, abs=1e-9)
    assert float(vec[1][0]) == pytest.approx(fy, rel=1e-9, abs=1e-9)
    assert np.hypot(fx, fy) <= mu * fz * (1.0 + 1e-12)
    assert 0.0 <= used <= 1.0
    if abs(kappa) > 1e-6 or abs(alpha) > 1e-6:
        assert used > 0.0
        # The force opposes the slip: same signs as the slip components.
        assert fx * kappa >= 0.0 and fy * alpha >= 0.0


def test_no_table_is_the_default_tire_and_bases_are_kept_apart():
    assert tire_for_surface(0.4, TRUCK.tire) is TRUCK.tire
    truck = tire_for_surface(0.4, TRUCK.tire, AUTHORS_TIRES)
    car = tire_for_surface(0.4, CAR.tire, AUTHORS_TIRES)
    assert truck is tire_for_surface(0.4, TRUCK.tire, AUTHORS_TIRES)  # cached
    assert truck.longitudinal_stiffness_per_load == TRUCK.tire.longitudinal_stiffness_per_load
    assert car.longitudinal_stiffness_per_load == CAR.tire.longitudinal_stiffness_per_load
    stiffness = "cornering_stiffness_per_load_1_per_rad"
    assert getattr(truck, stiffness) == getattr(car, stiffness) == pytest.approx(4.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(stiffness_factor_b_1_per_rad=0.0), "stiffness_factor_b"),
        (dict(curvature_factor_e=1.1), "curvature_factor_e"),
        (dict(shape_factor_c=2.1, curvature_factor_e=0.9), "shape_factor_c"),
        (dict(shape_factor_c=3.2), "shape_factor_c"),
        (dict(shape_factor_c=-1.0), "shape_factor_c"),
    ],
)
def test_surface_tire_rejects_reversing_or_bad_coefficients(kwargs, match):
    fields = dict(stiffness_factor_b_1_per_rad=5.0, shape_factor_c=2.0, curvature_factor_e=1.0)
    with pytest.raises(ValueError, match=match):
        SurfaceTire("x", **(fields | kwargs))


def test_table_rejects_bad_layouts():
    snow, wet, dry = AUTHORS_TIRES.sets[1], AUTHORS_TIRES.sets[2], AUTHORS_TIRES.sets[3]
    with pytest.raises(ValueError, match="strictly increasing"):
        SurfaceTireTable("x", (0.8, 0.4), (snow, wet))
    with pytest.raises(ValueError, match="one mu_point per set"):
        SurfaceTireTable("x", (0.4,), (snow, wet))
    with pytest.raises(ValueError, match="interpolation"):
        SurfaceTireTable("x", (0.4, 0.8), (snow, wet), interpolation="cubic")
    with pytest.raises(ValueError, match="reverses"):
        SurfaceTireTable("x", (0.8, 1.0), (wet, dry), interpolation="linear")
    assert dataclasses.replace(AUTHORS_TIRES, name="copy") == dataclasses.replace(
        AUTHORS_TIRES, name="copy"
    )


def test_bad_mu_and_names_are_value_errors():
    with pytest.raises(ValueError, match="mu must be finite and > 0"):
        tire_for_surface(0.0, TRUCK.tire, AUTHORS_TIRES)
    with pytest.raises(ValueError, match="mu must be finite and > 0"):
        cornering_stiffness_per_load([0.4, np.nan], TRUCK.tire, AUTHORS_TIRES)
    with pytest.raises(ValueError, match="mu must be finite and > 0"):
        lateral_force_n(0.1, 1000.0, -0.4, AUTHORS_TIRES)
    assert tire_table("authors") is AUTHORS_TIRES
    with pytest.raises(ValueError, match="authors-interpolated"):
        tire_table("pacejka")
