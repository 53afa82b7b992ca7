"""The plans' rear tire saturated at the axle's friction (``PlannerConfig.rear_saturation``,
docs/decisions/0109): the clipped force, the same equations in numpy and CasADi, and a plan from
a state whose rear slides."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.plan import FallbackReason
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.vehicle.params import CAR
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    frenet_bicycle_dynamics,
    rear_lateral_force_n,
)
from mufusion.vehicle.rear_saturation import (
    REAR_ROW_EXCESS_SHARE,
    REAR_SATURATION_MIN_SPEED_MPS,
    rear_row_force_n,
    saturated_rear_force_n,
)

finite = st.floats(-5e4, 5e4, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(force=finite, limit=st.floats(10.0, 3e4), vx=st.floats(0.0, 40.0))
def test_the_force_is_the_linear_one_within_the_limit_and_the_limit_beyond(
    force: float, limit: float, vx: float
) -> None:
    clipped = float(saturated_rear_force_n(force, vx, limit))
    if vx <= REAR_SATURATION_MIN_SPEED_MPS or abs(force) <= limit:
        assert clipped == force  # bit for bit: plans within the tire's friction are unchanged
    else:
        assert clipped == np.copysign(limit, force)
    row = float(rear_row_force_n(force, vx, limit))
    assert row == pytest.approx(clipped + REAR_ROW_EXCESS_SHARE * (force - clipped), abs=1e-9)
    assert abs(clipped) <= abs(row) <= abs(force) + 1e-9


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_casadi_and_numpy_evaluate_the_same_saturated_dynamics(seed: int) -> None:
    import casadi as ca

    rng = np.random.default_rng(seed)
    x = np.array([0.0, rng.uniform(-1, 1), rng.uniform(-0.3, 0.3), rng.uniform(-1, 1),
                  rng.uniform(0.5, 30.0), rng.uniform(-3, 3)])
    u = rng.uniform(-5e3, 5e3, N_INPUTS)
    stiffness, limit, kappa = rng.uniform(2e4, 2e5), rng.uniform(500.0, 8e3), rng.uniform(-0.05,
                                                                                           0.05)
    xs, us = ca.SX.sym("x", N_STATES), ca.SX.sym("u", N_INPUTS)
    f = ca.Function("f", [xs, us], [frenet_bicycle_dynamics(xs, us, kappa, stiffness, CAR,
                                                            rear_force_limit_n=limit)])
    numeric = frenet_bicycle_dynamics(x, u, kappa, stiffness, CAR, rear_force_limit_n=limit)
    np.testing.assert_allclose(np.asarray(f(x, u)).ravel(), numeric, rtol=1e-12, atol=1e-9)
    # The yaw and lateral accelerations are those of the clipped rear force.
    fyr = float(saturated_rear_force_n(rear_lateral_force_n(x, stiffness, CAR), x[State.vx],
                                       limit))
    vy_dot = (u[Input.fyf] + fyr) / CAR.mass_kg - x[State.vx] * x[State.psidot]
    assert numeric[State.vy] == pytest.approx(vy_dot, rel=1e-12, abs=1e-9)


# The car sliding through a right-hand curve of 40 m on μ 0.3, as GT did in limits_general's
# variant 169 at 4.0 s (body slip 0.19 rad, the linear rear tire's force 12 times the axle's
# friction): lateral offset 0.6 m, heading error −0.12 rad, yaw rate −0.31 rad/s, v_x 10.3 m/s,
# v_y 2.0 m/s.
SLIDING = np.array([100.0, 0.6, -0.12, -0.31, 10.3, 2.0])


def _plan(rear_saturation: bool):
    cfg = PlannerConfig(lane_d_min_m=-0.9, lane_d_max_m=0.9, rear_saturation=rear_saturation)
    planner = TractionAdaptivePlanner(CAR, cfg)
    curve = lambda s: -1.0 / 40.0 + 0.0 * np.asarray(s, dtype=float)  # noqa: E731
    mu = lambda s: 0.3 + 0.0 * np.asarray(s, dtype=float)  # noqa: E731
    return planner.step(SLIDING, 0.0, curve, mu, [], "cruise", 10.0)


@pytest.fixture(scope="module")
def plans():
    return _plan(False), _plan(True)


def test_a_plan_from_a_sliding_rear_predicts_the_slide_and_is_used(plans) -> None:
    linear, saturated = plans
    assert saturated.fallback_reason is FallbackReason.NONE
    # The linear tire snaps the body slip back within a stage on 12 times what the road holds;
    # the saturated one keeps it for the time its friction needs.
    assert abs(linear.states[1, State.vy]) < 1.5
    assert saturated.states[1, State.vy] > 1.9 and saturated.states[2, State.vy] > 1.5
    # Its predicted lateral acceleration from the rear is what μ̂ F_zr gives, not more.
    limit = 0.3 * saturated.normal_load_rear_n[0]
    fyr = saturated_rear_force_n(saturated.rear_lateral_force_n[0], SLIDING[State.vx], limit)
    assert abs(fyr) <= limit + 1e-6


def test_a_sliding_rear_is_not_braked(plans) -> None:
    # Braking the rear while it slides takes what lateral force it has left: the rows price the
    # rear's longitudinal force against the saturated tire's force, not against a linear one
    # that is far beyond the polygon whatever the rear does.
    _, saturated = plans
    assert np.all(np.abs(saturated.inputs[:2, Input.fxr]) < 0.2 * 0.3 * CAR.static_rear_load_n)


def test_the_scenario_key_reaches_the_planner_and_off_is_the_linear_tire() -> None:
    from mufusion.scenarios import load_scenario
    from mufusion.scenarios.runner import planner_config

    assert not planner_config(load_scenario("turn"), CAR).rear_saturation
    assert planner_config(load_scenario("turn", ["planner.rear_saturation=true"]),
                          CAR).rear_saturation
    with pytest.raises(ValueError, match="rear_saturation"):
        load_scenario("turn", ["planner.rear_saturation=3"])
    # Off, the dynamics are the linear tire's, bit for bit.
    u = np.array([500.0, -800.0, 300.0])
    linear = frenet_bicycle_dynamics(SLIDING, u, -1.0 / 40.0, 1e5, CAR)
    assert np.array_equal(linear, frenet_bicycle_dynamics(SLIDING, u, -1.0 / 40.0, 1e5, CAR,
                                                          rear_force_limit_n=None))
    clipped = frenet_bicycle_dynamics(SLIDING, u, -1.0 / 40.0, 1e5, CAR, rear_force_limit_n=1e3)
    assert not np.array_equal(linear, clipped)


@pytest.mark.slow
def test_gt_recovers_from_the_slide_it_spun_in_with_the_linear_rear_tire() -> None:
    # limits_general's variant 156: the car at 19 m/s, μ 0.9 dropping to 0.3 10 m ahead, a
    # 40 m quarter turn 20 m ahead behind a 5 m clothoid (the point mass calls it infeasible:
    # it reaches the arc about 1.3 m/s too fast). With the linear rear tire the plans drive the
    # rear through the slide, predicting it snapping back: GT spins (body slip 1.55 rad), starts
    # the minimal-risk stop and ends 3.8 m out. With the saturated tire it counter-steers,
    # brakes on the front and recovers in the lane's neighbourhood. Measured with the front
    # polygon at the centre of gravity's μ̂: at the front axle's (0112, the default) the plans
    # no longer slide there (tests/planner/test_axle_friction.py); and with ESC of 0082: its
    # body-slip return (0115) catches the linear tire's slide too (the car stays in its lane),
    # and with its braked wheel's lateral force on top of the tire forces, as before 0117 (with
    # it lost: the linear tire spins, 2.93 m out without the minimal-risk stop; the saturated
    # one does not spin, 1.55 m out).
    from mufusion.metrics import compute_metrics
    from mufusion.scenarios import load_scenario
    from mufusion.scenarios.runner import run_scenario

    base = ["vehicle=car", "initial_speed_mps=19", "duration_s=10", "turn.radius_m=40",
            "turn.angle_rad=1.5708", "turn.start_ahead_m=20", "turn.clothoid_m=5",
            "turn.direction=left", "friction.mu_before=0.9", "friction.mu_turn=0.3",
            "friction.change_ahead_m=10", "planner.front_axle_polygon=false",
            "sim.esc_body_slip_return_s=null", "sim.esc_braked_wheel_lateral_loss=false"]
    outcome = {
        on: compute_metrics(run_scenario(load_scenario(
            "turn", [*base, f"planner.rear_saturation={str(on).lower()}"]), "GT"))
        for on in (False, True)
    }
    assert outcome[False].spun and outcome[False].minimal_risk
    saturated = outcome[True]
    assert not saturated.spun and not saturated.minimal_risk
    assert saturated.max_body_slip_rad < 0.3
    assert saturated.max_lane_excursion_m < 0.5 * outcome[False].max_lane_excursion_m
