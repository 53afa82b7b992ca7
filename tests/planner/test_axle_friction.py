"""The front braking bounded where the front brake torque lands (docs/decisions/0063)."""

import numpy as np
import pytest

from mufusion.planner.ocp import front_brake_limit_n, polygon_directions, stage_parameters
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
