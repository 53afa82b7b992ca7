"""The cruising plans' rear tire at the secant of the utilisation their guess asks for
(planner/rear_secant.py, docs/decisions/0121)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.body_fit import body_fit_cap
from mufusion.planner.config import PlannerConfig
from mufusion.planner.ocp import Param, stage_parameters
from mufusion.planner.rear_secant import (
    UTILIZATION_FLOOR,
    guessed_rear_utilization,
    secant_factors,
    with_rear_secant_at_guess,
)
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    rear_cornering_stiffness_n_per_rad,
    secant_stiffness_factor,
)

LAMBDA = 0.9


def _guess(speed_mps: float, yaw_rate_radps: float = 0.0, fxr_n: float = 0.0, n: int = 8):
    xs = np.zeros((n + 1, N_STATES))
    xs[:, State.s] = 50.0 + speed_mps * 0.1 * np.arange(n + 1)
    xs[:, State.vx] = speed_mps
    xs[:, State.psidot] = yaw_rate_radps
    us = np.zeros((n, N_INPUTS))
    us[:, Input.fxr] = fxr_n
    return xs, us


def _stage(xs, us, params, mu=0.6):
    return stage_parameters(xs, us, lambda s: 0.0 * np.asarray(s),
                            lambda s: np.full(np.shape(s), mu), params, LAMBDA)


@pytest.mark.parametrize("params", [TRUCK, CAR], ids=["truck", "car"])
def test_the_table_is_the_secant_factor(params) -> None:
    u = np.array([0.05, 0.2, 0.37, 0.6, 0.9, 1.0])
    exact = np.array([secant_stiffness_factor(params.tire, float(x)) for x in u])
    np.testing.assert_allclose(secant_factors(params.tire, u), exact, rtol=2e-3)
    # Softer the nearer the peak.
    assert np.all(np.diff(secant_factors(params.tire, np.linspace(0.01, 1.0, 50))) < 0.0)


def test_a_stage_takes_the_secant_of_its_guessed_utilization_plus_the_reserve() -> None:
    """By hand: a truck at 20 m/s turning at 0.1 rad/s while braking the rear with 3 kN."""
    xs, us = _guess(20.0, 0.1, -3000.0)
    stage = _stage(xs, us, TRUCK)
    lateral = TRUCK.mass_kg * 20.0 * 0.1 * TRUCK.cog_to_front_axle_m / TRUCK.wheelbase_m
    u = math.hypot(lateral, 3000.0) / (0.6 * stage.fzr_n)
    assert np.all((u > 0.2) & (u < 0.7))  # a moderate demand, where the secants differ
    fitted = with_rear_secant_at_guess(stage, xs, us, TRUCK, LAMBDA, 0.1)
    expected = (TRUCK.tire.cornering_stiffness_per_load_1_per_rad
                * secant_factors(TRUCK.tire, u + 0.1) * stage.fzr_n)
    np.testing.assert_allclose(fitted.rear_stiffness_n_per_rad, expected, rtol=1e-12)
    np.testing.assert_array_equal(fitted.p[:, Param.rear_stiffness],
                                  fitted.rear_stiffness_n_per_rad)
    # Stiffer than λ's secant, which the stage had; nothing else moves.
    assert np.all(fitted.rear_stiffness_n_per_rad > stage.rear_stiffness_n_per_rad * 1.05)
    other = [c for c in range(stage.p.shape[1]) if c != Param.rear_stiffness]
    np.testing.assert_array_equal(fitted.p[:, other], stage.p[:, other])
    np.testing.assert_array_equal(fitted.radius_rear_n, stage.radius_rear_n)
    # The input stage is left as it was.
    assert not np.shares_memory(fitted.p, stage.p)


@settings(max_examples=80, deadline=None)
@given(speed=st.floats(0.0, 40.0), yaw=st.floats(-1.0, 1.0), fxr=st.floats(-3e4, 3e4),
       reserve=st.floats(0.0, 0.95), truck=st.booleans())
def test_never_softer_than_lambdas_secant_nor_stiffer_than_the_tangent_or_the_integrator_allows(
        speed: float, yaw: float, fxr: float, reserve: float, truck: bool) -> None:
    params = TRUCK if truck else CAR
    xs, us = _guess(speed, yaw, fxr)
    stage = _stage(xs, us, params)
    fitted = with_rear_secant_at_guess(stage, xs, us, params, LAMBDA, reserve)
    per_load = fitted.rear_stiffness_n_per_rad / stage.fzr_n
    at_lambda = float(rear_cornering_stiffness_n_per_rad(params, 1.0, LAMBDA))
    tangent = params.tire.cornering_stiffness_per_load_1_per_rad
    assert np.all(per_load >= at_lambda * (1.0 - 1e-9))
    assert np.all(per_load <= tangent * secant_stiffness_factor(params.tire, UTILIZATION_FLOOR))
    # The RK4 steps are sized for λ's secant at 1 m/s: C / v never beyond that.
    assert np.all(per_load / max(speed, 1.0) <= at_lambda * (1.0 + 1e-12))
    # At or beyond λ the reserve changes nothing.
    u = guessed_rear_utilization(xs, us, stage.mu_hat, stage.fzr_n, params)
    beyond = u + reserve >= LAMBDA
    np.testing.assert_allclose(per_load[beyond], at_lambda, rtol=2e-3)


@pytest.mark.parametrize("reserve", [0.0, 0.1, 0.3])
def test_the_bodys_fit_solves_its_utilization_with_the_guessed_secant(reserve: float) -> None:
    """At the cap ``u``, the tire at ``min(λ, u + reserve)``'s secant slips what the band leaves:
    ``u μ̂ = slip K f(min(λ, u + reserve))``, with ``slip`` the cap at λ's secant times its
    stiffness; the stiffer tire fits more."""
    band = 0.2
    plain, fitted = body_fit_cap(TRUCK, band, LAMBDA), body_fit_cap(TRUCK, band, LAMBDA,
                                                                   secant_reserve=reserve)
    at_lambda = float(rear_cornering_stiffness_n_per_rad(TRUCK, 1.0, LAMBDA))
    tangent = TRUCK.tire.cornering_stiffness_per_load_1_per_rad
    checked = 0
    for mu in (0.3, 0.6, 0.9):
        for radius in (60.0, 100.0, 145.0):
            mus, kappas = np.array([mu]), np.array([1.0 / radius])
            u0, u1 = float(plain(mus, kappas)[0]), float(fitted(mus, kappas)[0])
            if u0 >= 1.0:
                continue
            slip = u0 * mu / at_lambda  # the steady slip the band leaves (the cap's relation)
            if u1 < 1.0:
                checked += 1
                factor = float(secant_factors(TRUCK.tire, np.array([min(LAMBDA, max(
                    u1 + reserve, UTILIZATION_FLOOR))]))[0])
                assert u1 * mu == pytest.approx(slip * tangent * factor, rel=2e-3)
            assert u1 >= u0
    assert checked >= 4


@pytest.mark.parametrize("bad", [-0.1, 1.0, 1.5])
def test_a_reserve_outside_its_range_is_refused(bad: float) -> None:
    with pytest.raises(ValueError, match="rear_secant_reserve"):
        PlannerConfig(rear_secant_reserve=bad)


def test_the_scenario_field_reaches_the_planner_and_is_checked() -> None:
    from mufusion.scenarios import load_scenario

    assert load_scenario("turn", ["planner.rear_secant_reserve=0.1"]).planner.rear_secant_reserve \
        == 0.1
    assert load_scenario("turn", ["planner.rear_secant_reserve=null"]).planner.rear_secant_reserve \
        is None
    with pytest.raises(ValueError, match=r"planner\.rear_secant_reserve"):
        load_scenario("turn", ["planner.rear_secant_reserve=1.5"])
