"""Wheel-slip control (ABS, TCS): locked wheels without it, rolling wheels with it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mufusion.metrics.run_metrics import LOCKED_SLIP, ONE_ABS_CYCLE_S, _longest_run_s
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import CAR, GRAVITY_MPS2, TRUCK, VehicleParams
from mufusion.vehicle.plant import Plant, PlantState, initial_state
from mufusion.vehicle.slip_control import SlipControlSettings, SlipPhase


def _brake(params: VehicleParams, mu: float, steer_rad: float, slip_control, *, speed=20.0,
           duration_s=8.0, fraction=1.0):
    """Full brake torque (or ``fraction`` of it) from ``speed``; per-step records until rest."""
    plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, speed), slip_control=slip_control)
    command = ActuatorCommand(steer_rad, -fraction * params.max_brake_torque_front_nm,
                              -fraction * params.max_brake_torque_rear_nm)
    rows = []
    for _ in range(round(duration_s / plant.dt_s)):
        out = plant.step(command, mu, mu)
        locked = min(out.front.slip_ratio, out.rear.slip_ratio) <= LOCKED_SLIP
        rows.append((out.time_s, float(out.x[PlantState.X]), out.speed_mps,
                     locked and out.speed_mps > 2.0, abs(out.front.fy_n), out.slip_control))
        if out.speed_mps < 0.3:
            break
    return rows


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
@pytest.mark.parametrize("mu", [0.3, 0.8])
def test_abs_keeps_the_wheels_rolling_and_restores_lateral_force(params, mu) -> None:
    steer = 0.02
    without = _brake(params, mu, steer, None)
    with_abs = _brake(params, mu, steer, SlipControlSettings())
    dt = with_abs[1][0] - with_abs[0][0]
    lock_without = _longest_run_s(np.array([r[3] for r in without]), dt)
    lock_with = _longest_run_s(np.array([r[3] for r in with_abs]), dt)
    # Without slip control the full brake torque locks both axles for the rest of the stop.
    assert lock_without > 1.0
    # With it no wheel stays locked beyond 0.1 s (measured 0-0.085 s), far inside one ABS
    # cycle ...
    assert lock_with <= 0.1 < ONE_ABS_CYCLE_S
    assert with_abs[-1][5].cycles_front + with_abs[-1][5].cycles_rear >= 2
    # ... and the steered front axle gives lateral force again (a locked tire gives none).
    fy_without = np.mean([r[4] for r in without[:200]])
    fy_with = np.mean([r[4] for r in with_abs[:200]])
    assert fy_with > 3.0 * fy_without


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
@pytest.mark.parametrize("mu", [0.3, 0.5, 0.9])
def test_abs_stops_straight_near_the_friction_limit(params, mu) -> None:
    rows = _brake(params, mu, 0.0, SlipControlSettings(), speed=20.0, duration_s=15.0)
    locked = _brake(params, mu, 0.0, None, speed=20.0, duration_s=15.0)
    ideal = 20.0**2 / (2.0 * mu * GRAVITY_MPS2)
    assert rows[-1][2] < 0.3 and locked[-1][2] < 0.3  # both stopped
    # Sliding tires return 58-68 % of the peak: the locked stop is far longer, the ABS stop is
    # within 30 % of v²/2μg (brake lag and the release phases included; measured 1.07-1.26,
    # the truck's pneumatic brakes on μ 0.3 the longest, as conventional truck ABS is).
    assert rows[-1][1] < 1.3 * ideal
    assert rows[-1][1] < 0.85 * locked[-1][1]


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
def test_slip_control_passes_a_braking_within_the_tires_peak_through_unchanged(params) -> None:
    # 30 % of the brake torque at μ 0.9 stays well below the tires' force peak: the controller
    # must not touch the command (the published grids rely on this).
    plain = _brake(params, 0.9, 0.01, None, fraction=0.1, duration_s=2.0)
    controlled = _brake(params, 0.9, 0.01, SlipControlSettings(), fraction=0.1, duration_s=2.0)
    assert [r[:5] for r in plain] == [r[:5] for r in controlled]
    assert all(r[5].front.phase is SlipPhase.PASS and r[5].rear.phase is SlipPhase.PASS
               for r in controlled)


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
def test_traction_control_limits_wheel_spin(params) -> None:
    def launch(slip_control):
        plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, 5.0),
                      slip_control=slip_control)
        slips = []
        for _ in range(400):
            out = plant.step(ActuatorCommand(0.0, 0.0, params.max_drive_torque_nm), 0.2, 0.2)
            slips.append(out.rear.slip_ratio)
        return np.array(slips), out.speed_mps

    spin, speed_spin = launch(None)
    held, speed_held = launch(SlipControlSettings())
    assert spin[-100:].min() > 0.5  # the driven wheel spins freely without it
    assert np.median(held[100:]) < 0.2
    assert speed_held > speed_spin  # a gripping tire drives harder than a spinning one


def test_abs_can_be_switched_off_alone() -> None:
    rows = _brake(CAR, 0.3, 0.0, SlipControlSettings(abs_enabled=False), duration_s=2.0)
    assert _longest_run_s(np.array([r[3] for r in rows]), 0.005) > 1.0
    assert all(r[5].front.phase is SlipPhase.PASS for r in rows)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("onset_slip", 0.0, "onset_slip must be in"),
        ("release_slip", 0.01, "release_slip must be in"),
        ("recovered_slip", 0.3, "recovered_slip must be in"),
        ("max_hold_s", -1.0, "max_hold_s must be > 0"),
        ("wheel_accel_margin_mps2", math.nan, "wheel_accel_margin_mps2 must be a finite"),
        ("abs_enabled", 1, "abs_enabled must be true or false"),
        ("min_speed_mps", -0.5, "min_speed_mps must be >= 0"),
    ],
)
def test_settings_name_the_field_out_of_range(field, value, message) -> None:
    with pytest.raises(ValueError, match=message):
        SlipControlSettings(**{field: value})


def test_longest_lock_counts_consecutive_ticks() -> None:
    flags = np.array([0, 1, 1, 0, 1, 1, 1, 0, 1], dtype=bool)
    assert _longest_run_s(flags, 0.02) == pytest.approx(0.06)
    assert _longest_run_s(np.zeros(5, dtype=bool), 0.02) == 0.0


def test_the_run_summary_says_whether_a_lock_outlasted_one_abs_cycle() -> None:
    import pandas as pd

    from mufusion.metrics.run_metrics import _wheels

    tick = 0.02
    n = 60
    slip = np.zeros(n)
    slip[5:5 + round(ONE_ABS_CYCLE_S / tick) + 3] = -1.0  # locked a little over one cycle
    ts = pd.DataFrame({
        "speed_mps": np.full(n, 10.0), "vx_mps": np.full(n, 10.0), "body_slip_rad": np.zeros(n),
        "wheel_slip_front": slip, "wheel_slip_rear": np.zeros(n),
        "slip_control_front": slip < -0.5, "slip_control_rear": np.zeros(n, dtype=bool),
        "slip_cycles": np.arange(n) // 15,
    })
    out = _wheels(ts, tick)
    assert out["wheel_lock_max_s"] == pytest.approx(ONE_ABS_CYCLE_S + 3 * tick)
    assert out["wheel_lock_within_abs_cycle"] is False
    assert out["slip_control_cycles"] == 3
    # Below 2 m/s a stopped wheel is no lock (the brakes hold the vehicle).
    out = _wheels(ts.assign(speed_mps=1.0, vx_mps=1.0), tick)
    assert out["wheel_lock_max_s"] == 0.0 and out["wheel_lock_within_abs_cycle"] is True
    # Spinning, the wheels roll across their own plane: no lock counted.
    out = _wheels(ts.assign(body_slip_rad=1.5), tick)
    assert out["wheel_lock_max_s"] == 0.0
    assert _wheels(ts.assign(vx_mps=-3.0), tick)["wheel_lock_max_s"] == 0.0  # backwards
    # A record from before wheel slips were logged: nothing to say.
    assert _wheels(ts.assign(wheel_slip_front=np.nan, wheel_slip_rear=np.nan), tick) == {}


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
def test_a_curves_imu_bias_does_not_read_braking_within_grip_as_a_lock(params) -> None:
    # Braking in a curve with body slip, the IMU measures a_x = v̇_x − ψ̇ v_y: here it reads
    # 0.8 m/s² less deceleration than the vehicle has. The wheels brake within their grip (2 %,
    # then 4 % slip, decelerating with the body). An estimate that may only fall with the IMU
    # drifted 2.4 m/s above them in 3 s, read a lock and dumped the firm brake torque the road
    # could take (docs/decisions/0080); the reference must follow the wheels.
    from mufusion.vehicle.slip_control import WheelSlipController

    dt, radius = 0.005, params.wheel_radius_m
    control = WheelSlipController(params, SlipControlSettings(), dt, 20.0)
    speed, decel, bias = 20.0, 2.0, 0.8
    removed, worst_gap = 0.0, 0.0
    for step in range(round(4.0 / dt)):
        t = step * dt
        light = t < 3.0
        slip = 0.02 if light else 0.04
        torque = -0.05 * params.max_brake_torque_front_nm if light else \
            -0.4 * params.max_brake_torque_front_nm
        rate = decel if light else 3.0 * decel
        omega = speed * (1.0 - slip) / radius
        _cmd, status = control.modulate((0.0, torque, 0.0), omega, omega, -rate + bias,
                                       torque, 0.0, t)
        removed = max(removed, status.front.torque_removed_nm)
        worst_gap = max(worst_gap, status.reference_speed_mps - speed)
        speed -= rate * dt
    assert removed == 0.0
    assert worst_gap < 0.05  # the reference stays with the wheels (2.4 m/s above before)


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
@pytest.mark.parametrize("front_torque_nm", [-1e-9, -300.0], ids=["dust", "light-brake"])
def test_traction_control_sees_a_spin_while_the_front_brakes(params, front_torque_nm) -> None:
    # The plans may brake the front while they drive the rear, and a brake torque's lag leaves
    # a tail (down to numerical dust, -1e-10 N m in limits_general's spinning car). While any
    # torque brakes, the reference speed is the fastest wheel's; if that may be the driven one,
    # a spinning rear wheel is its own reference, reads no slip, and traction control lets it
    # run away (GT's rear wheel at 125 times the vehicle's speed there, docs/decisions/0110).
    def launch(slip_control):
        plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, 8.0),
                      slip_control=slip_control)
        command = ActuatorCommand(0.0, front_torque_nm, params.max_drive_torque_nm)
        slips = [plant.step(command, 0.2, 0.2).rear.slip_ratio for _ in range(400)]
        return np.array(slips)

    spin = launch(None)
    held = launch(SlipControlSettings())
    assert spin[-100:].min() > 0.5  # the command spins the driven wheel
    assert np.median(held[100:]) < 0.2  # as without the front's brake torque (the test above)
    assert held.max() < 1.0


def test_a_front_wheel_at_full_lock_is_read_in_its_own_plane_and_keeps_its_brake() -> None:
    # Skidding at full steering lock (a minimal-risk stop beyond the limit), the front wheel
    # rolls along its own plane at v cos δ, about half the body's speed for the car (1.07 rad):
    # read as the body's speed it looked locked, its brake was dumped at once, and since the
    # torque "that locked it" was none, the reapply never built it up again (limits_turn: 1 s
    # and more in 60 runs, docs/decisions/0111). The truck's lock (0.6 rad) reads 17.5 %, below
    # the release threshold without a runaway.
    from mufusion.vehicle.slip_control import WheelSlipController

    params = CAR
    dt, radius = 0.005, params.wheel_radius_m
    steer, yaw_rate, decel = params.max_steer_rad, 0.1, 0.8
    brake = -0.3 * params.max_brake_torque_front_nm

    def run(steer_seen: float) -> float:
        control = WheelSlipController(params, SlipControlSettings(), dt, 8.0)
        speed, removed = 8.0, 0.0
        for step in range(round(1.0 / dt)):
            in_plane = (speed * math.cos(steer)
                        + params.cog_to_front_axle_m * yaw_rate * math.sin(steer))
            _cmd, status = control.modulate(
                (steer, brake, brake), in_plane / radius, speed / radius, -decel,
                brake, brake, step * dt, steer_seen, yaw_rate)
            removed = max(removed, status.front.torque_removed_nm)
            speed -= decel * dt
        return removed

    assert run(steer) == 0.0  # the rolling wheel keeps its brake torque
    assert run(0.0) == pytest.approx(-brake)  # read without the steering: dumped throughout


def _drifted_release(settings: SlipControlSettings | None = None):
    """A car braking while its reference reads 15 m/s and both wheels roll at 11 (the IMU's
    drift in a slide, which misses ψ̇ v_y): 27 % slip, past the release threshold."""
    from mufusion.vehicle.slip_control import WheelSlipController

    control = WheelSlipController(CAR, settings or SlipControlSettings(), 0.005, 15.0)
    wheel = 11.0 / CAR.wheel_radius_m
    control.modulate((0.0, -800.0, -500.0), wheel, wheel, 0.0, -800.0, -500.0, 0.0)
    _cmd, status = control.modulate((0.0, -800.0, -500.0), wheel, wheel, 0.0, -800.0, -500.0,
                                    0.005)
    assert status.front.phase is SlipPhase.RELEASE  # dumped, as a lock would be
    return control, wheel


def test_a_released_wheel_rolling_freely_ends_the_release_and_the_brake_comes_back() -> None:
    # The torque is gone and the wheels neither spin up nor slow against the body: they roll
    # at the vehicle's speed. Before, the release waited for a spin-up that could not come and
    # the brakes stayed dumped to the end of the run (limits_turn_heldout7, the car on μ 0.15:
    # 5 s; docs/decisions/0114).
    control, wheel = _drifted_release()
    torques = []
    for step in range(2, 80):
        cmd, status = control.modulate((0.0, -800.0, -500.0), wheel, wheel, 0.0, 0.0, 0.0,
                                       step * 0.005)
        torques.append(-cmd[1])
    assert control.reference_speed_mps == pytest.approx(11.0)
    assert status.front.phase is not SlipPhase.RELEASE
    assert max(torques) >= 0.7 * 800.0  # reapplied from a share of the torque that "locked"


def test_a_released_wheel_still_spinning_up_is_no_reference() -> None:
    # Right after a dump the wheel's brake torque is gone but it spins up fast: it is below
    # the vehicle's speed and must not pull the reference down.
    control, wheel = _drifted_release()
    spin_up = 40.0 / CAR.wheel_radius_m * 0.005  # 40 m/s² faster than the body
    control.modulate((0.0, -800.0, -500.0), wheel + spin_up, wheel + spin_up, 0.0, 0.0, 0.0,
                     0.010)
    assert control.reference_speed_mps == pytest.approx(15.0, abs=0.05)
