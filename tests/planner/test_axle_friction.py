"""The friction under the axles: the polygons at the lowest μ̂ from the rear axle to the front
one (docs/decisions/0112), the front braking bounded where its torque lands (0063, 0064)."""

import numpy as np
import pytest

from mufusion.planner.ocp import (
    Param,
    front_brake_limit_n,
    polygon_directions,
    stage_parameters,
)
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_INPUTS, N_STATES, Input, State, normal_loads_n

LAMBDA = 0.9


def _guess(s0_m: float, speed_mps: float, n: int = 10, dt_s: float = 0.1):
    xs = np.zeros((n + 1, N_STATES))
    xs[:, State.s] = s0_m + speed_mps * dt_s * np.arange(n + 1)
    xs[:, State.vx] = speed_mps
    return xs, np.zeros((n, N_INPUTS))


def _drop_at(s_drop_m: float):
    return lambda s: np.where(np.asarray(s, dtype=float) < s_drop_m, 0.9, 0.3)


def _flat(s):
    return 0.0 * np.asarray(s, dtype=float)


def test_the_front_braking_is_bounded_past_a_drop_the_cog_has_not_reached():
    lf = TRUCK.cog_to_front_axle_m
    # The front axle 0.15 m short of the drop (the logged case): the CoG's μ̂ is the high one,
    # the front brake torque commanded now lands past the drop.
    xs, us = _guess(100.0 - lf - 0.15, 6.0)
    stage = stage_parameters(xs, us, _flat, _drop_at(100.0), TRUCK, LAMBDA,
                             axle_lag_s=TRUCK.torque_time_constant_s)
    assert stage.mu_hat[0] == 0.9 and stage.mu_hat_front_brake[0] == 0.3
    ratio = polygon_directions(12)[1]
    assert stage.front_brake_limit_n[0] == pytest.approx(
        front_brake_limit_n(np.array([ratio * LAMBDA * 0.3]), np.zeros(1), TRUCK)[0])
    # Less than the front polygon's braking face at the CoG's μ̂ by the friction ratio.
    assert stage.front_brake_limit_n[0] < 0.5 * ratio * stage.radius_front_n[0]
    # Stages the CoG has carried onto the low friction are bounded by their own polygon.
    assert np.all(np.isinf(stage.front_brake_limit_n[stage.mu_hat == 0.3]))
    # Without the lag: no bound beyond the polygon anywhere.
    plain = stage_parameters(xs, us, _flat, _drop_at(100.0), TRUCK, LAMBDA)
    assert np.all(np.isinf(plain.front_brake_limit_n))


def test_the_front_polygon_takes_the_friction_under_the_front_axle():
    lf = TRUCK.cog_to_front_axle_m
    # A drop 0.5 m behind the front axle: the CoG is still on μ 0.9, the front tires are not.
    xs, us = _guess(100.0 - lf + 0.5, 1.0, n=4)
    assert np.all(xs[:-1, State.s] < 100.0)
    drop = stage_parameters(xs, us, _flat, _drop_at(100.0), TRUCK, LAMBDA, front_axle=True)
    np.testing.assert_allclose(drop.mu_hat_front, 0.3)
    np.testing.assert_allclose(drop.radius_front_n, LAMBDA * 0.3 * drop.fzf_n)
    np.testing.assert_allclose(drop.p[:, Param.utilized_friction_front], LAMBDA * 0.3)
    # The rear polygon keeps the CoG's μ̂ (the road behind it is not read, 0099).
    np.testing.assert_allclose(drop.mu_hat, 0.9)
    np.testing.assert_allclose(drop.radius_rear_n, LAMBDA * 0.9 * drop.fzr_n)
    np.testing.assert_allclose(drop.utilized_friction, LAMBDA * 0.9)
    # The paper's planner: both polygons at the CoG's μ̂.
    paper = stage_parameters(xs, us, _flat, _drop_at(100.0), TRUCK, LAMBDA)
    np.testing.assert_allclose(paper.mu_hat_front, 0.9)
    np.testing.assert_allclose(paper.radius_front_n, LAMBDA * 0.9 * paper.fzf_n)
    # A rise ahead of the front axle: the lower, the CoG's, holds for both.
    rise = stage_parameters(xs, us, _flat, lambda s: np.where(np.asarray(s) < 100.0, 0.3, 0.9),
                            TRUCK, LAMBDA, front_axle=True)
    np.testing.assert_allclose(rise.mu_hat_front, 0.3)


def test_the_ocps_front_rows_read_the_front_axles_friction_and_the_rear_rows_the_cogs():
    """The OCP's rows (CasADi, load transfer on): forces that fit μ̂ 0.9 but not 0.3 on both
    axles violate the front rows only, where the front axle is past the drop."""
    import casadi as ca

    from mufusion.planner.ocp import constraint_expressions

    xs, us = _guess(100.0 - TRUCK.cog_to_front_axle_m + 0.5, 10.0, n=1)
    stage = stage_parameters(xs, us, _flat, _drop_at(100.0), TRUCK, LAMBDA, front_axle=True)
    x, u, p = ca.SX.sym("x", N_STATES), ca.SX.sym("u", N_INPUTS), ca.SX.sym("p", stage.p.shape[1])
    rows = ca.Function("rows", [x, u, p],
                       [constraint_expressions(x, u, p, TRUCK, 12, load_transfer=True)])
    static_front, static_rear = normal_loads_n(0.0, TRUCK)
    inputs = np.zeros(N_INPUTS)
    inputs[Input.fyf] = 0.4 * static_front  # μ 0.3's polygon holds 0.26 of the load
    inputs[Input.fxr] = -0.4 * static_rear
    values = np.asarray(rows(xs[0], inputs, stage.p[0])).ravel()
    assert values[:12].max() > 0.0
    assert values[12:24].max() < 0.0
    # The paper's planner (both at the CoG's 0.9): no row binds.
    paper = stage_parameters(xs, us, _flat, _drop_at(100.0), TRUCK, LAMBDA)
    assert np.asarray(rows(xs[0], inputs, paper.p[0])).max() < 0.0


def test_no_bound_where_the_front_axle_meets_the_stages_own_friction():
    xs, us = _guess(20.0, 15.0)
    stage = stage_parameters(xs, us, _flat, _drop_at(1e3), TRUCK, LAMBDA,
                             axle_lag_s=TRUCK.torque_time_constant_s)
    assert np.all(np.isinf(stage.front_brake_limit_n))
    # A rise ahead (the front meets more friction than the CoG) is no bound either.
    rise = stage_parameters(xs, us, _flat, lambda s: np.where(np.asarray(s) < 22.0, 0.3, 0.9),
                            TRUCK, LAMBDA, axle_lag_s=TRUCK.torque_time_constant_s)
    assert np.all(np.isinf(rise.front_brake_limit_n))


def test_the_bound_is_the_braking_face_at_the_load_the_braking_itself_gives():
    k = polygon_directions(12)[1] * LAMBDA * 0.3
    for fxr in (0.0, -8e3, 5e3):
        brake = float(front_brake_limit_n(np.array([k]), np.array([fxr]), TRUCK)[0])
        fzf = normal_loads_n((-brake + fxr) / TRUCK.mass_kg, TRUCK)[0]
        assert brake == pytest.approx(k * fzf, rel=1e-9)
    # Rear braking moves load to the front: more front braking allowed.
    assert (front_brake_limit_n(np.array([k]), np.array([-8e3]), TRUCK)[0]
            > front_brake_limit_n(np.array([k]), np.array([0.0]), TRUCK)[0])


def test_the_backend_holds_the_plan_within_the_bound():
    from mufusion.planner.casadi_backend import CasadiBackend
    from mufusion.planner.ocp import PlannerConfig, tracking_reference

    config = PlannerConfig(backend="casadi", horizon_steps=10)
    backend = CasadiBackend(TRUCK, config)
    xs, us = _guess(0.0, 15.0)
    stage = stage_parameters(xs, us, _flat, lambda s: 0.0 * np.asarray(s) + 0.9, TRUCK, LAMBDA)
    # Track a standstill: the plan brakes as hard as it may.
    yref, weights = tracking_reference(config, stage.curvature_1pm, stage.mu_hat, "emergency",
                                       15.0, 15.0, 0.0)
    args = (xs[0], xs, us, stage.p, yref, weights, np.full(10, -1.0), np.full(10, 1.0), 0.0, 0.0)
    _, _, free = backend.solve(*args)
    limit = np.full(10, 5e3)
    status, _, bounded = backend.solve(*args, limit)
    assert status in (0, 2)
    assert free[:, Input.fxf].min() < -2.0 * 5e3
    assert bounded[:, Input.fxf].min() >= -5e3 - 1e-3


@pytest.mark.slow
def test_gt_keeps_its_lane_where_the_drop_reached_its_front_tires_first() -> None:
    # limits_general's variant 156 (the car at 19 m/s, μ 0.9 dropping to 0.3 10 m ahead, a
    # 40 m quarter turn 20 m ahead): with the front polygon at the centre of gravity's μ̂ GT
    # spun and ended 3.95 m out (tests/planner/test_rear_saturation.py); at the front axle's it
    # keeps its lane.
    from mufusion.metrics import compute_metrics
    from mufusion.scenarios import load_scenario
    from mufusion.scenarios.runner import run_scenario

    overrides = ["vehicle=car", "initial_speed_mps=19", "duration_s=10", "turn.radius_m=40",
                 "turn.angle_rad=1.5708", "turn.start_ahead_m=20", "turn.clothoid_m=5",
                 "turn.direction=left", "friction.mu_before=0.9", "friction.mu_turn=0.3",
                 "friction.change_ahead_m=10"]
    metrics = compute_metrics(run_scenario(load_scenario("turn", overrides), "GT"))
    assert not metrics.spun and not metrics.minimal_risk
    assert metrics.max_lane_excursion_m == 0.0
