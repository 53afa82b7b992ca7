"""The speed ceiling (``PlannerConfig.speed_ceiling``, off by default, docs/decisions/0088): the
speed reference as a soft upper bound on each stage's planned speed, written per solve by both
backends and passed by the real-time iteration in cruise only."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mufusion.planner.config import CostWeights
from mufusion.planner.ocp import MAX_SPEED_MPS, Param, PlannerConfig
from mufusion.planner.penalties import slack_penalties
from mufusion.planner.stability import state_bounds
from mufusion.vehicle.params import GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import N_STATES, State
from ocp_problems import cruise_problem

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=3.95, speed_ceiling=True)


def test_the_ceiling_lowers_only_the_speeds_upper_bound() -> None:
    n = CONFIG.horizon_steps
    guess_x = np.zeros((n + 1, N_STATES))
    p = np.zeros((n, len(Param)))
    ceiling = np.linspace(30.0, 10.0, n)
    ceiling[0] = 2.0 * MAX_SPEED_MPS  # above the box: the box stays
    lower, upper = state_bounds(np.zeros(n), np.ones(n), 0.5, guess_x, p, CONFIG, ceiling)
    np.testing.assert_array_equal(upper[:, 1], np.minimum(ceiling, MAX_SPEED_MPS))
    np.testing.assert_array_equal(lower[:, 1], 0.5)
    np.testing.assert_array_equal(upper[:, 0], 1.0)
    unbounded = state_bounds(np.zeros(n), np.ones(n), 0.5, guess_x, p, CONFIG)[1]
    np.testing.assert_array_equal(unbounded[:, 1], MAX_SPEED_MPS)


def test_the_ceiling_is_priced_below_the_lane_and_the_minimum_speed_as_the_lane() -> None:
    weights = CostWeights()
    pen = slack_penalties(weights, 6, 2, speed_ceiling=True)
    assert pen.linear_stage_upper[pen.speed][0] == weights.speed_ceiling_l1
    assert pen.linear_stage[pen.speed][0] == weights.slack_l1
    assert weights.speed_ceiling_l1 < weights.slack_l1
    # Every other slack is priced alike on both sides.
    others = np.ones(pen.linear_stage.shape, bool)
    others[pen.speed] = False
    np.testing.assert_array_equal(pen.linear_stage_upper[others], pen.linear_stage[others])
    assert pen.rear_polygon == slice(2, 8) and pen.heading == slice(8, None)
    # Without the ceiling the layout is the one before it: no speed slack, both sides alike.
    plain = slack_penalties(weights, 6, 2, speed_ceiling=False)
    assert pen.speed != plain.speed == slice(1, 1)
    assert plain.rear_polygon == slice(1, 7) and plain.heading == slice(7, None)
    np.testing.assert_array_equal(plain.linear_stage_upper, plain.linear_stage)


def _solve(backend, cfg, ceiling, iterations, speed_mps=20.0, mu=0.9):
    n = cfg.horizon_steps
    guess_x, guess_u, p, yref, weights = cruise_problem(cfg, speed_mps, mu)
    x0 = guess_x[0].copy()
    for _ in range(iterations):
        status, xs, us = backend.solve(x0, guess_x, guess_u, p, yref, weights,
                                       np.full(n, -1.0), np.full(n, 1.0), 0.5, None, None,
                                       ceiling)
        guess_x, guess_u = xs, us
    return status, xs


@pytest.mark.parametrize("backend_name", ["acados", "casadi"])
def test_a_plan_tracking_a_higher_speed_stays_under_the_ceiling(backend_name) -> None:
    """Asked to hold 20 m/s under a ceiling that falls to 14 m/s at 1.5 m/s², the plan brakes
    with it; without the ceiling it holds its speed."""
    cfg = dataclasses.replace(CONFIG, horizon_steps=20)
    if backend_name == "acados":
        from mufusion.planner.acados_backend import AcadosBackend

        backend, iterations = AcadosBackend(TRUCK, cfg, robust_retry=False), 10
    else:
        from mufusion.planner.casadi_backend import CasadiBackend

        backend, iterations = CasadiBackend(TRUCK, cfg), 1
    n = cfg.horizon_steps
    ceiling = np.maximum(20.0 - 1.5 * cfg.dt_s * np.arange(1, n + 1), 14.0)
    status, free = _solve(backend, cfg, None, iterations)
    assert status in (0, 2), status
    assert np.min(free[1:n, State.vx] - ceiling[: n - 1]) > -0.2  # it would stay above
    assert np.max(free[1:n, State.vx] - ceiling[: n - 1]) > 1.0
    status, capped = _solve(backend, cfg, ceiling, iterations)
    assert status in (0, 2), status
    # Stages 1 … N-1: the terminal stage bounds d only.
    assert np.max(capped[1:n, State.vx] - ceiling[: n - 1]) < 0.05


def test_a_vehicle_above_the_ceiling_gets_a_plan_that_brakes_at_the_friction_limit() -> None:
    """The ceiling is soft: 6 m/s below the vehicle's speed at once, the solve still succeeds
    and the plan brakes as hard as the friction lets it, not beyond."""
    from mufusion.planner.acados_backend import AcadosBackend

    cfg = dataclasses.replace(CONFIG, horizon_steps=20)
    backend = AcadosBackend(TRUCK, cfg, robust_retry=False)
    n, mu = cfg.horizon_steps, 0.5
    status, xs = _solve(backend, cfg, np.full(n, 14.0), 10, mu=mu)
    assert status in (0, 2), status
    decel = -np.diff(xs[: n, State.vx]) / cfg.dt_s
    assert xs[n - 1, State.vx] < 17.0  # it brakes towards the ceiling
    assert np.max(decel) < 1.05 * mu * GRAVITY_MPS2  # within the friction


class _Recording:
    """A backend that records the speed ceiling it is given and returns the guess."""

    last_solve_retried = False

    def __init__(self) -> None:
        self.ceilings: list[np.ndarray | None] = []
        self.speed_targets: list[np.ndarray] = []

    def solve(self, x0, guess_x, guess_u, p, yref, weights, d_lo, d_hi, min_speed_mps,
              max_drive_force_n=None, max_front_brake_force_n=None, max_speed_mps=None):
        self.ceilings.append(None if max_speed_mps is None else np.array(max_speed_mps))
        self.speed_targets.append(yref[:, State.vx].copy())
        return 0, guess_x.copy(), guess_u.copy()

    def reset(self) -> None:
        pass


@pytest.mark.parametrize(("mode", "enabled", "passed"), [
    ("cruise", True, True), ("cruise", False, False), ("evade", True, False),
    ("emergency", True, False)])
def test_the_iteration_passes_the_reference_as_ceiling_in_cruise_only(mode, enabled,
                                                                      passed) -> None:
    """In cruise the ceiling is the tracked reference, or, for a vehicle above it, the descent
    from its speed at the reference's braking share."""
    from mufusion.planner import rti
    from mufusion.planner.safeguards import SanitizedFriction

    cfg = dataclasses.replace(CONFIG, horizon_steps=20, speed_ceiling=enabled)
    n, mu = cfg.horizon_steps, 0.9
    guess_x, guess_u, *_ = cruise_problem(cfg, 20.0, mu)
    x0 = guess_x[0].copy()
    x0[State.vx] = 22.0  # above the cruise reference: the first stages descend from it
    # A curve 60 m ahead: the reference brakes inside the horizon.
    problem = rti.StepProblem(
        x0=x0, mode=mode, reference_speed_mps=20.0,
        curvature_of_s=lambda s: np.where(np.asarray(s) > 60.0, 0.05, 0.0),
        mu_of_s=SanitizedFriction(lambda s: np.full(np.shape(s), mu), None, 0.1),
        obstacles=[],
        lane_d_min_m=-0.45, lane_d_max_m=0.45, reference_d_m=0.0)
    backend = _Recording()
    rti.iterate(backend, TRUCK, cfg, problem, guess_x, guess_u, 1)
    (ceiling,) = backend.ceilings
    if not passed:
        assert ceiling is None
        return
    target = backend.speed_targets[0][1:]  # the speeds the plan tracks at stages 1 … N
    share = (cfg.reference_braking_fraction * cfg.reference_curve_fraction
             * cfg.utilization_factor * np.cos(np.pi / cfg.polygon_sides))
    descent = 22.0 - share * mu * GRAVITY_MPS2 * cfg.dt_s * np.arange(1, n + 1)
    np.testing.assert_allclose(ceiling, np.maximum(target, descent))
    assert ceiling[0] == pytest.approx(descent[0]) and ceiling[0] > target[0]
    assert ceiling[-1] == pytest.approx(target[-1]) and target[-1] < 18.0
