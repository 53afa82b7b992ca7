"""The speed reference corners no faster than the plans' own attitude leaves the corridor a
width (planner/body_fit.py, docs/decisions/0097)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.body_fit import body_fit_cap, body_fitted_curvature
from mufusion.planner.corridor import MAX_SWING_HEADING_RAD, lateral_corridor, reach_taken_m
from mufusion.planner.ocp import State
from mufusion.planner.speed_profile import max_speed_profile_mps
from mufusion.vehicle.params import CAR, GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import rear_cornering_stiffness_n_per_rad

LAMBDA = 0.9


@settings(max_examples=60, deadline=None)
@given(dpsi=st.floats(-MAX_SWING_HEADING_RAD, MAX_SWING_HEADING_RAD),
       kappa=st.floats(-0.07, 0.07), exact=st.booleans())
def test_the_reach_counted_is_what_the_corridor_takes_off(dpsi: float, kappa: float,
                                                          exact: bool) -> None:
    """One count of the body's reach for the cap and the corridor: a wide lane loses exactly
    :func:`reach_taken_m` of its width at any heading the corridor swings by."""
    guess = np.zeros((3, len(State)))
    guess[:, State.dpsi] = dpsi
    guess[:, State.vx] = 10.0
    lo, hi = lateral_corridor(guess, [], -4.0, 4.0, TRUCK, 0.5, np.full(2, kappa),
                              exact_reach=exact)
    taken = reach_taken_m(np.full(2, math.sin(dpsi)), np.full(2, kappa), TRUCK, exact)
    np.testing.assert_allclose(8.0 - (hi - lo), taken, atol=1e-12)


@pytest.mark.parametrize("exact", [False, True])
@pytest.mark.parametrize("band_m", [0.2, 0.7])
def test_at_the_cap_the_plans_steady_attitude_fills_the_band(band_m: float, exact: bool) -> None:
    """At the cap, the heading the plans' linear rear tire gives in the steady turn
    (``α_r = u μ / c̄``, ``ψ = α_r − l_r κ``) takes the whole band; above it, more."""
    cap = body_fit_cap(TRUCK, band_m, LAMBDA, exact)
    per_load = float(rear_cornering_stiffness_n_per_rad(TRUCK, 1.0, LAMBDA))
    checked = 0
    for mu in (0.35, 0.6, 0.8, 1.0):
        for radius in (25.0, 60.0, 150.0):
            kappa = 1.0 / radius
            u = float(cap(np.array([mu]), np.array([kappa]))[0])
            if u >= 1.0:
                continue
            checked += 1
            for fraction, relation in ((1.0, "equal"), (1.05, "more")):
                psi = fraction * u * mu / per_load - TRUCK.cog_to_rear_axle_m * kappa
                taken = float(reach_taken_m(np.array([math.sin(psi)]), np.array([kappa]),
                                            TRUCK, exact)[0])
                if relation == "equal":
                    assert taken == pytest.approx(band_m, abs=2e-3)
                else:
                    assert taken > band_m
    assert checked >= 6
    # The cap falls with μ (the same utilisation asks more slip of the linear tire) and
    # rises with the band.
    mus = np.array([0.5, 0.7, 0.9])
    kappas = np.full(3, 1 / 60)
    caps, wider = cap(mus, kappas), body_fit_cap(TRUCK, band_m + 0.2, LAMBDA, exact)(mus, kappas)
    assert np.all(np.diff(caps) <= 0.0) and caps[-1] < caps[0]
    assert np.all(wider >= caps) and np.any(wider > caps)


def test_the_car_is_never_capped_in_a_3_m_lane() -> None:
    """The car's stiff tire and short body fit a 3.0 m lane at the polygon's reach."""
    cap = body_fit_cap(CAR, 3.0 - CAR.width_m - 0.2, LAMBDA)
    mu, kappa = np.meshgrid(np.linspace(0.2, 1.2, 11), np.linspace(0.0, 1 / 15, 11))
    assert np.all(cap(mu.ravel(), kappa.ravel()) == 1.0)


def test_the_profile_corners_at_the_cap_on_the_fitted_curvature() -> None:
    """The speed profile on the fitted curvature reaches an arc at ``√(cap μ g / κ)`` and brakes
    for it earlier than the point mass's."""
    s = np.arange(0.0, 121.0)
    kappa = np.where(s >= 80.0, -1 / 60, 0.0)
    mu = np.full(s.size, 0.8)
    accel = LAMBDA * math.cos(math.pi / 12)
    cap = body_fit_cap(TRUCK, 0.2, LAMBDA)
    fitted = body_fitted_curvature(lambda x: np.interp(x, s, kappa), lambda x: np.full(
        np.shape(x), 0.8), cap, accel)(s)
    v_fit = max_speed_profile_mps(s, fitted, mu, accel, 30.0)
    v_point = max_speed_profile_mps(s, kappa, mu, accel, 30.0)
    u = float(cap(np.array([0.8]), np.array([1 / 60]))[0])
    assert u < accel
    assert v_fit[-1] == pytest.approx(math.sqrt(u * 0.8 * GRAVITY_MPS2 * 60.0), rel=1e-9)
    assert v_point[-1] == pytest.approx(math.sqrt(accel * 0.8 * GRAVITY_MPS2 * 60.0), rel=1e-9)
    assert np.all(v_fit <= v_point + 1e-12) and v_fit[40] < v_point[40]
