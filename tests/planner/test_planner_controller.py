"""Tracking controller: inverse tire model, limits, rate limit, signs."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.controller import (
    ControllerGains,
    TrackingController,
    _magic_formula_lateral,
    front_slip_angle_for_force_rad,
)
from mufusion.planner.planner import Plan
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import Input, State


def _plan(fyf: float, fxf: float, fxr: float, v: float = 15.0, d: float = 0.0) -> Plan:
    n = 40
    states = np.zeros((n + 1, 6))
    states[:, State.vx] = v
    states[:, State.d] = d
    states[:, State.s] = v * 0.1 * np.arange(n + 1)
    inputs = np.tile([fyf, fxf, fxr], (n, 1)).astype(float)
    ones = np.ones(n)
    return Plan(0.0, states, inputs, 0 * ones, 0.8 * ones, 5e4 * ones, 3e4 * ones,
                3.6e4 * ones, 2.2e4 * ones, 0, True, False, 0.0)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 0.95), st.floats(0.2, 1.2), st.floats(1e4, 6e4))
def test_inverse_tire_model_recovers_force(fraction, mu, fz):
    force = fraction * mu * fz
    alpha = front_slip_angle_for_force_rad(force, fz, mu, TRUCK.tire)
    assert np.isclose(_magic_formula_lateral(alpha, fz, mu, TRUCK.tire), force, rtol=1e-2,
                      atol=20.0)
    assert np.isclose(front_slip_angle_for_force_rad(-force, fz, mu, TRUCK.tire), -alpha)


@settings(max_examples=40, deadline=None)
@given(st.floats(-6e4, 6e4), st.floats(-1e5, 0.0), st.floats(-1e5, 1e5), st.floats(-0.5, 0.5),
       st.floats(-2.0, 2.0), st.floats(0.0, 3.9))
def test_commands_never_exceed_limits_or_steer_rate(fyf, fxf, fxr, steer_now, d_err, t):
    ctrl = TrackingController(TRUCK)
    steer_now = float(np.clip(steer_now, -TRUCK.max_steer_rad, TRUCK.max_steer_rad))
    x = np.array([15.0 * t, d_err, 0.0, 0.0, 15.0, 0.0])
    cmd = ctrl.command(t, x, steer_now, _plan(fyf, fxf, fxr), 0.0)
    assert abs(cmd.steer_rad) <= TRUCK.max_steer_rad + 1e-12
    assert abs(cmd.steer_rad - steer_now) <= TRUCK.max_steer_rate_radps / 50.0 + 1e-12
    assert cmd.torque_front_nm <= 0.0
    assert -TRUCK.max_brake_torque_rear_nm <= cmd.torque_rear_nm <= TRUCK.max_drive_torque_nm


def test_left_force_steers_left_and_offset_right_steers_back():
    ctrl = TrackingController(TRUCK, gains=ControllerGains())
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    # Many small rate-limited steps converge on the feed-forward angle.
    steer = 0.0
    for _ in range(50):
        steer = ctrl.command(0.0, x, steer, _plan(2e4, 0.0, 0.0), 0.0).steer_rad
    assert steer > 0.0
    x_right = x.copy()
    x_right[State.d] = -1.0
    assert ctrl.command(0.0, x_right, 0.0, _plan(0.0, 0.0, 0.0), 0.0).steer_rad > 0.0


def test_braking_plan_gives_braking_torques_and_slow_plan_brakes():
    ctrl = TrackingController(TRUCK)
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    cmd = ctrl.command(0.0, x, 0.0, _plan(0.0, -2e4, -2e4), 0.0)
    assert cmd.torque_front_nm < 0.0 and cmd.torque_rear_nm < 0.0
    fast = x.copy()
    fast[State.vx] = 20.0
    cmd = ctrl.command(0.0, fast, 0.0, _plan(0.0, 0.0, 0.0, v=15.0), 0.0)
    assert cmd.torque_rear_nm < 0.0
    assert Input.fyf == 0


def test_steer_rate_is_limited_against_the_last_command_not_the_lagging_actuator():
    # The servo lags: the measured angle stays at 0 while the command ramps. Limiting against the
    # measured angle would pin every command at one step; the actuator's rate allows a ramp.
    ctrl = TrackingController(TRUCK)
    x = np.array([0.0, 0.0, 0.0, 0.0, 20.0, 0.0])
    step = TRUCK.max_steer_rate_radps / 50.0
    commands = [ctrl.command(0.0, x, 0.0, _plan(4e4, 0.0, 0.0), 0.0).steer_rad for _ in range(5)]
    assert np.allclose(np.diff(commands), step)
    assert abs(commands[-1] - 5 * step) < 1e-12
    ctrl.reset()
    assert abs(ctrl.command(0.0, x, 0.0, _plan(4e4, 0.0, 0.0), 0.0).steer_rad - step) < 1e-12


def _brake_from_stage(k_brake: int, fxf: float = -2e4, fxr: float = -1e4) -> Plan:
    plan = _plan(0.0, 0.0, 0.0)
    plan.inputs[k_brake:, Input.fxf] = fxf
    plan.inputs[k_brake:, Input.fxr] = fxr
    return plan


def test_torque_compensation_commands_the_force_one_torque_time_constant_ahead():
    # The truck's torques lag by 0.15 s = 1.5 planning stages; braking planned from stage 2
    # (t = 0.2 s) is commanded from t = 0.05 s on, and not before.
    assert TRUCK.torque_time_constant_s == 0.15
    plan = _brake_from_stage(2)
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    ahead = TrackingController(TRUCK)
    now = TrackingController(TRUCK, gains=ControllerGains(torque_compensation=False))
    r = TRUCK.wheel_radius_m
    before = ahead.command(0.049, x, 0.0, plan, 0.0)
    at = ahead.command(0.051, x, 0.0, plan, 0.0)
    assert before.torque_front_nm == 0.0 and before.torque_rear_nm == 0.0
    assert np.isclose(at.torque_front_nm, -2e4 * r) and np.isclose(at.torque_rear_nm, -1e4 * r)
    # Without the preview the same braking starts at the stage's own time.
    assert now.command(0.19, x, 0.0, plan, 0.0).torque_front_nm == 0.0
    assert np.isclose(now.command(0.2, x, 0.0, plan, 0.0).torque_front_nm, -2e4 * r)
    # At the plan's end the preview holds the last stage.
    end = ahead.command(3.99, x, 0.0, plan, 0.0)
    assert np.isclose(end.torque_rear_nm, -1e4 * r)


def _through_the_lag(ctrl: TrackingController, plan: Plan, feedback: bool, t_end_s: float = 3.0):
    """The front torque [N m] of the plant's first-order lag (1 ms steps) under the controller at
    its 50 Hz, each command held for its period; with ``feedback`` the controller is given the
    measured torques."""
    tau, dt = TRUCK.torque_time_constant_s, 0.001
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    torque, cmd, out = 0.0, 0.0, []
    for i in range(round(t_end_s / dt)):
        t = i * dt
        if i % 20 == 0:
            measured = (torque, 0.0) if feedback else None
            cmd = ctrl.command(t, x, 0.0, plan, 0.0, measured).torque_front_nm
        torque += dt * (cmd - torque) / tau
        out.append((t + dt, torque))
    return np.array(out)


def test_torque_compensation_lets_the_lagging_brake_deliver_a_planned_ramp_on_time():
    # A planned brake ramp (-20 kN/s, held per 0.1 s stage, so the stages trail the ramp by half
    # a stage: 1 kN) through the plant's first-order torque lag: commanded as planned, the
    # realised force trails the ramp by (τ + 0.05 s) × 20 kN/s = 4 kN; fed forward by τ, by the
    # half stage only; the feedback on the measured torque keeps it there.
    plan = _plan(0.0, 0.0, 0.0)
    plan.inputs[:, Input.fxf] = -2e4 * 0.1 * np.arange(plan.inputs.shape[0])
    errors = {}
    for name, gains, feedback in (("none", ControllerGains(torque_compensation=False), False),
                                  ("feed-forward", ControllerGains(), False),
                                  ("both", ControllerGains(), True)):
        run = _through_the_lag(TrackingController(TRUCK, gains=gains), plan, feedback)
        late = run[run[:, 0] >= 1.0]  # past the start-up transient
        err = np.abs(late[:, 1] / TRUCK.wheel_radius_m - (-2e4 * late[:, 0]))
        errors[name] = err.mean(), err.max()
    assert 3.5e3 < errors["none"][0] < 4.5e3
    assert errors["feed-forward"][0] < 1.2e3 and errors["feed-forward"][1] < 1.5e3
    assert errors["both"][0] < 1.2e3 and errors["both"][1] < 2.5e3


def test_torque_feedback_closes_a_new_plans_first_stage_in_one_controller_period():
    # A new plan brakes from its first stage (2 kN front, within the actuator's range even at
    # the feedback's gain of 7): no feed-forward can have anticipated it. Fed forward only, the
    # lag has built 1 - exp(-0.02/0.15) = 12.5 % of it after one controller period; with the
    # measured torque fed back, all of it (to the plant's 1 ms integration).
    plan = _brake_from_stage(0, fxf=-2e3, fxr=0.0)
    target = -2e3 * TRUCK.wheel_radius_m
    ff = _through_the_lag(TrackingController(TRUCK), plan, False, 0.02)
    fb = _through_the_lag(TrackingController(TRUCK), plan, True, 0.02)
    assert np.isclose(ff[-1, 1] / target, 1.0 - np.exp(-0.02 / 0.15), atol=0.01)
    assert np.isclose(fb[-1, 1] / target, 1.0, atol=0.01)
    # Then it holds the plan's torque (the feedback term vanishes there).
    held = _through_the_lag(TrackingController(TRUCK), plan, True, 0.5)
    assert np.allclose(held[held[:, 0] >= 0.02, 1], target, rtol=0.01)


def test_a_non_finite_force_ahead_degrades_like_one_now():
    # The previewed stage is checked as the current one is: NaN there holds the wheel and
    # brakes gently instead of passing NaN torques to the actuators.
    plan = _brake_from_stage(2, fxf=float("nan"))
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    cmd = TrackingController(TRUCK).command(0.06, x, 0.01, plan, 0.0)
    assert cmd.steer_rad == 0.01
    assert np.isfinite(cmd.torque_front_nm) and cmd.torque_front_nm < 0.0
    assert np.isfinite(cmd.torque_rear_nm) and cmd.torque_rear_nm < 0.0


def test_a_non_finite_torque_measurement_is_not_fed_back():
    # A broken torque sensor must not turn the command into NaN: the controller falls back to
    # its feed-forward, the command it gives without a measurement.
    plan = _brake_from_stage(0, fxf=-2e3, fxr=-1e3)
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    without = TrackingController(TRUCK).command(0.05, x, 0.0, plan, 0.0)
    broken = TrackingController(TRUCK).command(0.05, x, 0.0, plan, 0.0, (float("nan"), 0.0))
    assert broken == without and np.isfinite(broken.torque_front_nm)
