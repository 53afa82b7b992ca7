"""The front braking's bound at the friction where the front brake torque lands (decision 0062)."""

import numpy as np

from mufusion.planner.ocp import (
    INACTIVE_BRAKE_FRICTION,
    Param,
    constraint_bounds,
    polygon_rows,
    stage_parameters,
)
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_INPUTS, N_STATES, State


def _guess(s0_m: float, speed_mps: float, n: int = 10, dt_s: float = 0.1):
    xs = np.zeros((n + 1, N_STATES))
    xs[:, State.s] = s0_m + speed_mps * dt_s * np.arange(n + 1)
    xs[:, State.vx] = speed_mps
    return xs, np.zeros((n, N_INPUTS))


def _drop_at(s_drop_m: float):
    return lambda s: np.where(np.asarray(s, dtype=float) < s_drop_m, 0.9, 0.3)


def test_front_braking_is_bounded_by_the_friction_past_the_drop_the_cog_has_not_reached():
    lf = TRUCK.cog_to_front_axle_m
    # The front axle 0.15 m short of the drop: the CoG's μ̂ is the high one, the front brake
    # torque lands past the drop.
    xs, us = _guess(100.0 - lf - 0.15, 6.0)
    stage = stage_parameters(xs, us, lambda s: 0.0 * np.asarray(s), _drop_at(100.0), TRUCK,
                             0.9, axle_lag_s=TRUCK.torque_time_constant_s)
    assert stage.mu_hat[0] == 0.9
    assert stage.mu_hat_front_brake[0] == 0.3
    assert np.isclose(stage.p[0, Param.utilized_friction_front_brake], 0.9 * 0.3)
    # Without the lag the row is out of reach (the polygon's face alone bounds the braking).
    plain = stage_parameters(xs, us, lambda s: 0.0 * np.asarray(s), _drop_at(100.0), TRUCK,
                             0.9)
    assert np.allclose(plain.p[:, Param.utilized_friction_front_brake],
                       0.9 * INACTIVE_BRAKE_FRICTION)


def test_the_row_is_out_of_reach_where_the_front_brakes_on_the_stages_friction():
    xs, us = _guess(20.0, 15.0)
    stage = stage_parameters(xs, us, lambda s: 0.0 * np.asarray(s), _drop_at(1e3), TRUCK,
                             0.9, axle_lag_s=TRUCK.torque_time_constant_s)
    assert np.allclose(stage.p[:, Param.utilized_friction_front_brake],
                       0.9 * INACTIVE_BRAKE_FRICTION)


def test_the_braking_row_follows_the_polygon_rows_one_sided():
    for load_transfer in (False, True):
        rows = polygon_rows(12, load_transfer=load_transfer)
        lower, upper = constraint_bounds(rows)
        assert lower.shape == upper.shape == (rows.count + 1,)
        assert upper[-1] == 0.0 and lower[-1] < -1.0
