"""The longitudinal forces as OCP states that follow their commands with the torques' lag: the
layout, the translation at the backends' boundary, plans that a lagging torque can deliver, and
a controller that delivers them (docs/decisions/0068)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.controller import lagged_forces_n, stage_commands_n
from mufusion.planner.ocp import (
    Param,
    PlannerConfig,
    longitudinal_force_bounds_n,
    polygon_directions,
)
from mufusion.planner.ocp_state import (
    INITIAL_FORCE_SHARE,
    augmented_problem,
    initial_forces,
    ocp_state,
    plan_from_augmented,
)
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import N_STATES, Input, floored_axle_loads_n

N, DT = 8, 0.1
CONFIG = PlannerConfig(dt_s=DT, torque_lag=True)  # front force and longitudinal forces states
LAYOUT = ocp_state(CONFIG, TRUCK)


@pytest.mark.parametrize(("rate", "lag", "nx", "front", "longitudinal"), [
    (False, False, N_STATES, None, None), (True, False, N_STATES + 1, N_STATES, None),
    (False, True, N_STATES + 2, None, N_STATES), (True, True, N_STATES + 3, N_STATES, N_STATES + 1),
])
def test_layout_follows_the_switches(rate, lag, nx, front, longitudinal):
    layout = ocp_state(PlannerConfig(steering_rate_limit=rate, torque_lag=lag), CAR)
    assert (layout.nx, layout.front_force, layout.longitudinal) == (nx, front, longitudinal)
    assert layout.augmented is (rate or lag)
    assert layout.lag_s == CAR.torque_time_constant_s


def _stage_params(radius_n: float, utilized_friction: float = 1.0) -> np.ndarray:
    p = np.ones((N + 1, len(Param)))
    p[:, Param.radius_front] = radius_n
    p[:, Param.utilized_friction] = p[:, Param.utilized_friction_front] = utilized_friction
    return p


def _lag(force: np.ndarray, command: np.ndarray, dt_s: float, tau_s: float) -> np.ndarray:
    """A first-order lag over ``dt_s`` from ``force`` under the held ``command``."""
    e = math.exp(-dt_s / tau_s)
    return command + (force - command) * e


lower, upper = longitudinal_force_bounds_n(TRUCK)
brakes = st.lists(st.floats(0.2 * lower[0], 0.0), min_size=N, max_size=N)
rears = st.lists(st.floats(0.2 * lower[1], 0.2 * upper[1]), min_size=N, max_size=N)


@given(fxf=brakes, fxr=rears, seed=st.integers(0, 2**16))
@settings(max_examples=50, deadline=None)
def test_translation_round_trip_and_the_commands_reproduce_the_forces(fxf, fxr, seed):
    rng = np.random.default_rng(seed)
    guess_x = rng.normal(size=(N + 1, N_STATES))
    guess_u = rng.normal(size=(N, 3)) * 1e3
    guess_u[:, Input.fxf], guess_u[:, Input.fxr] = fxf, fxr
    # Every force of the draw lies well inside the first stage's polygon.
    x0a, xa, ua = augmented_problem(guess_x[0] + 0.1, guess_x, guess_u, _stage_params(1e6),
                                    TRUCK, CONFIG, LAYOUT)
    i = LAYOUT.longitudinal
    assert x0a.shape == (LAYOUT.nx,) and xa.shape == (N + 1, LAYOUT.nx)
    np.testing.assert_array_equal(x0a[i:i + 2], guess_u[0, [Input.fxf, Input.fxr]])
    xs, us = plan_from_augmented(xa, ua, LAYOUT)
    np.testing.assert_array_equal(xs, guess_x)
    np.testing.assert_array_equal(us, guess_u)
    # Where the commands are within the actuators, the lag carries each stage's forces to the
    # next one's (the guess is consistent with the OCP's dynamics).
    commands = ua[:, [Input.fxf, Input.fxr]]
    inside = np.all((commands > lower + 1.0) & (commands < upper - 1.0), axis=1)
    reached = _lag(xa[:-1, i:i + 2], commands, DT, LAYOUT.lag_s)
    np.testing.assert_allclose(reached[inside], xa[1:, i:i + 2][inside], atol=1e-6)


def test_the_initial_pair_is_clipped_into_the_first_polygon_at_its_own_load():
    guess_x = np.zeros((N + 1, N_STATES))
    guess_u = np.zeros((N, 3))
    guess_u[:, Input.fyf], guess_u[:, Input.fxf] = 3e4, -4e4  # after μ̂ dropped to 0.2
    p = _stage_params(1.0, utilized_friction=0.2)
    x0a, _, _ = augmented_problem(guess_x[0], guess_x, guess_u, p, TRUCK, CONFIG, LAYOUT)
    fyf, fxf = x0a[LAYOUT.front_force], x0a[LAYOUT.longitudinal]
    assert fyf > 0.0 > fxf and fyf / fxf == pytest.approx(3e4 / -4e4)  # scaled, not rotated
    first = np.array([fyf, fxf, x0a[LAYOUT.longitudinal + 1]])
    fzf, _ = floored_axle_loads_n(first, TRUCK, 0.05 * TRUCK.mass_kg * 9.81)
    _, ratio = polygon_directions(CONFIG.polygon_sides)
    inscribed = ratio * 0.2 * float(fzf)
    # Inside the inscribed circle of the polygon at the load its own braking gives, by a hair.
    assert math.hypot(fyf, fxf) <= INITIAL_FORCE_SHARE * inscribed * (1.0 + 1e-9)
    assert math.hypot(fyf, fxf) >= 0.99 * INITIAL_FORCE_SHARE * inscribed
    # A pair already inside is left alone.
    inside = np.array([1e3, -1e3, 0.0])
    np.testing.assert_array_equal(initial_forces(inside, p[0], TRUCK, CONFIG, LAYOUT), inside)


def _plan(inputs: np.ndarray, t0_s: float = 0.0) -> SimpleNamespace:
    return SimpleNamespace(inputs=inputs, dt_s=DT, t0_s=t0_s)


def test_the_controller_targets_the_plans_lagged_forces():
    # Stage forces that a lag of τ reaches from commands within the actuators.
    tau = TRUCK.torque_time_constant_s
    commands = np.array([[-3e4, 5e3], [-6e4, -8e3], [0.0, 8e3], [-1e4, 0.0]])
    forces = np.zeros((5, 2))
    for k, command in enumerate(commands):
        forces[k + 1] = _lag(forces[k], command, DT, tau)
    inputs = np.zeros((5, 3))
    inputs[:, [Input.fxf, Input.fxr]] = forces
    plan = _plan(inputs, t0_s=2.0)
    for k in range(4):
        np.testing.assert_allclose(stage_commands_n(plan, k, tau), commands[k], atol=1e-6)
        for sigma in (0.0, 0.03, 0.07):
            expected = _lag(forces[k], commands[k], sigma, tau)
            np.testing.assert_allclose(lagged_forces_n(plan, 2.0 + k * DT + sigma, tau),
                                       expected, atol=1e-6)
    # The last stage holds its forces.
    np.testing.assert_allclose(stage_commands_n(plan, 4, tau), forces[4])


def _mu(s):
    return 0.9 + 0.0 * np.asarray(s)


def _curve(s):
    s = np.asarray(s)
    return np.where(s < 30.0, 0.0, 1.0 / 40.0)


@pytest.mark.parametrize("measured", [(-2e4, 3e3), None, (float("nan"), 0.0)],
                         ids=["measured", "none", "not-finite"])
def test_plans_start_from_the_delivered_forces_and_follow_the_lag(measured):
    # A truck at 19 m/s brakes for a 40 m arc 30 m ahead: the plans brake as hard as the
    # polygons allow, and a lagging torque cannot jump there.
    config = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45, use_sampling=False,
                           torque_lag=True)
    planner = TractionAdaptivePlanner(TRUCK, config)
    x = np.array([0.0, 0.0, 0.0, 0.0, 19.0, 0.0])
    first = planner.step(x, 0.0, _curve, _mu, [], "cruise", 19.0)
    previous = first.inputs[1, [Input.fxf, Input.fxr]]
    second = planner.step(first.states[1], 0.1, _curve, _mu, [], "cruise", 19.0,
                          longitudinal_forces_n=measured)
    assert second.ok
    anchor = (measured if measured is not None and all(map(math.isfinite, measured))
              else previous)
    np.testing.assert_allclose(second.inputs[0, [Input.fxf, Input.fxr]], anchor, atol=1.0)
    # Every stage's commands (recovered from the forces) lie within the actuators: the forces
    # move by at most (1 − e) of the way to a bound per stage.
    tau = TRUCK.torque_time_constant_s
    for plan in (first, second):
        assert float(plan.inputs[:, Input.fxf].min()) < -1e4  # the case brakes
        commands = np.array([stage_commands_n(_plan(plan.inputs), k, tau)
                             for k in range(plan.inputs.shape[0] - 1)])
        assert np.all(commands >= lower - 50.0) and np.all(commands <= upper + 50.0)
