"""Yaw stability control (ESC): when it acts, which way, how much, and that it is on by default."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mufusion.scenarios import load_scenario
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.plant import Plant, initial_state
from mufusion.vehicle.stability_control import StabilityControlSettings, YawStabilityController


def test_it_acts_only_on_a_yaw_rate_beyond_what_steering_and_cornering_explain() -> None:
    # The rule of 0082 (without the body-slip return of 0115, tested below).
    esc = YawStabilityController(TRUCK, StabilityControlSettings(body_slip_return_s=None))
    wheelbase = TRUCK.cog_to_front_axle_m + TRUCK.cog_to_rear_axle_m
    # Turning as the steering asks (ψ̇ = v δ / L, with the lateral acceleration to match).
    assert esc.moment(15.0, 15.0 * 0.05 / wheelbase, 0.05, 15.0**2 * 0.05 / wheelbase, 0.9,
                      -0.1) == (0.0, 0.0)
    # Cornering at speed with little (here slightly opposite) steering: the lateral acceleration
    # explains the yaw rate; braking against it turned the truck out of a 150 m arc (0061).
    assert esc.moment(17.0, 0.08, -0.008, 17.0 * 0.08, 0.9, -0.1) == (0.0, 0.0)
    # Slow, or within the deadband: passive.
    assert esc.moment(2.0, 1.0, 0.0, 0.0, 0.9, -0.1) == (0.0, 0.0)
    assert esc.moment(15.0, 0.04, 0.0, 0.0, 0.9, -0.1) == (0.0, 0.0)
    # A right turn rotating faster than its steering and its lateral acceleration explain: a
    # moment to the left, and the braked wheel's force slows the vehicle.
    mz, fx = esc.moment(15.0, -0.6, -0.09, -6.0, 0.9, 0.1)
    assert mz > 0.0 > fx
    assert fx == pytest.approx(-mz / (0.5 * TRUCK.track_width_m))
    # Mirrored, the same magnitudes.
    mz_left, fx_left = esc.moment(15.0, 0.6, 0.09, 6.0, 0.9, -0.1)
    assert mz_left == pytest.approx(-mz) and fx_left == pytest.approx(fx)

    # The same excess with the rear not swung out (body slip within the deadband, or pointing
    # into the rotation): a steering transient, not a skid; production ESC keeps out (0082).
    assert esc.moment(15.0, -0.6, -0.09, -6.0, 0.9, 0.04) == (0.0, 0.0)
    assert esc.moment(15.0, -0.6, -0.09, -6.0, 0.9, -0.1) == (0.0, 0.0)


def test_the_run_summary_says_how_long_it_acted() -> None:
    import numpy as np
    import pandas as pd

    from mufusion.metrics.run_metrics import _wheels

    n, tick = 50, 0.02
    moment = np.zeros(n)
    moment[10:17] = 4.0e3
    ts = pd.DataFrame({
        "vx_mps": np.full(n, 15.0), "body_slip_rad": np.zeros(n),
        "wheel_slip_front": np.zeros(n), "wheel_slip_rear": np.zeros(n),
        "slip_control_front": np.zeros(n, dtype=bool), "slip_control_rear": np.zeros(n, dtype=bool),
        "slip_cycles": np.zeros(n, dtype=int), "esc_yaw_moment_nm": moment,
    })
    assert _wheels(ts, tick)["stability_control_active_s"] == pytest.approx(7 * tick)
    # A record from before the moment was logged: nothing counted.
    assert _wheels(ts.drop(columns="esc_yaw_moment_nm"), tick)["stability_control_active_s"] == 0.0


def test_the_moment_is_bounded_by_the_braked_wheels_friction() -> None:
    esc = YawStabilityController(CAR, StabilityControlSettings())
    wheel_load = 0.5 * CAR.mass_kg * 9.81 * CAR.cog_to_rear_axle_m / (
        CAR.cog_to_front_axle_m + CAR.cog_to_rear_axle_m)
    for mu in (0.2, 0.9):
        mz, _ = esc.moment(20.0, 2.0, 0.0, 0.0, mu, -0.2)  # far beyond any target
        assert mz == pytest.approx(-mu * wheel_load * 0.5 * CAR.track_width_m)


def test_settings_are_checked_by_name() -> None:
    with pytest.raises(ValueError, match="response_time_s"):
        StabilityControlSettings(response_time_s=0.0)
    with pytest.raises(ValueError, match="yaw_rate_deadband_radps"):
        StabilityControlSettings(yaw_rate_deadband_radps=-0.1)
    for bad in (0.0, -1.0, float("inf"), True):
        with pytest.raises(ValueError, match="body_slip_return_s"):
            StabilityControlSettings(body_slip_return_s=bad)
    with pytest.raises(ValueError, match="esc_body_slip_return_s"):
        load_scenario("turn", ["sim.esc_body_slip_return_s=0"])
    assert load_scenario("turn", ["sim.esc_body_slip_return_s=null"]).sim.stability_control() == (
        StabilityControlSettings(body_slip_return_s=None))
    with pytest.raises(ValueError, match="stability_control"):
        Plant(CAR, initial_state(CAR, 0.0, 0.0, 0.0, 10.0), stability_control=True)  # type: ignore[arg-type]


def test_it_is_on_by_default_and_damps_a_spinning_plant() -> None:
    assert load_scenario("turn").sim.stability_control() is not None
    assert load_scenario("turn", ["sim.esc=false"]).sim.stability_control() is None
    # The truck at 15 m/s with a yaw rate twice what its steering asks, the steering held:
    # with ESC the yaw rate falls towards the steering's within a second, without it it does not.
    final = {}
    for esc in (None, StabilityControlSettings()):
        x0 = initial_state(TRUCK, 0.0, 0.0, 0.0, 15.0)
        x0[5] = -0.6  # yaw rate [rad/s]
        plant = Plant(TRUCK, x0, stability_control=esc)
        for _ in range(200):
            out = plant.step(ActuatorCommand(-0.09, 0.0, 0.0), 0.9, 0.9)
        final[esc is None] = (abs(float(out.x[5])), plant.stability_control_active_s)
        if esc is None:
            assert out.esc_yaw_moment_nm == 0.0
    assert final[True][1] == 0.0 < final[False][1]
    assert final[False][0] < final[True][0]


def test_a_closed_loop_run_logs_its_moment_and_sums_it_in_the_summary() -> None:
    # The truck's evasion at 24 m/s on μ 0.85 (a held-out pop-up): its rear swings out in the
    # lane change at 0.7 s and ESC acts (decision 0082); without ESC nothing is logged.
    from mufusion.metrics import compute_metrics
    from mufusion.scenarios.runner import run_scenario

    overrides = ["vehicle=truck", "friction.mu=0.85", "initial_speed_mps=24",
                 "obstacle.distance_m=35", "obstacle.lateral_offset_m=1.5", "duration_s=1.0"]
    for esc in (True, False):
        log = run_scenario(load_scenario("popup", [*overrides, f"sim.esc={str(esc).lower()}"]),
                           "F-safe")
        moments = log.timeseries["esc_yaw_moment_nm"].to_numpy()
        tick_s = float(log.timeseries["t_s"].diff().median())
        active_s = compute_metrics(log).stability_control_active_s
        assert active_s == pytest.approx((moments != 0.0).sum() * tick_s)
        if esc:
            assert active_s > 0.0 and moments.min() < 0.0  # against the leftward rotation
        else:
            assert active_s == 0.0 and not moments.any()


def test_with_drive_cut_it_withholds_drive_only_while_the_rear_is_swung_out() -> None:
    # The truck turning left at 20 m/s, rear drive torque asked: with the body slip 0.1 rad
    # against the rotation (the rear out, beyond the 0.05 rad deadband) the drive cut keeps the
    # rear's torque from building up; within the deadband, or without the cut, it builds up.
    def rear_torque_after(body_slip_rad: float, drive_cut: bool) -> tuple[float, float]:
        x0 = initial_state(TRUCK, 0.0, 0.0, 0.0, 20.0)
        x0[4] = 20.0 * body_slip_rad  # v_y: β = v_y / v_x
        x0[5] = 0.25  # a left turn's yaw rate [rad/s]
        plant = Plant(TRUCK, x0, stability_control=StabilityControlSettings(drive_cut=drive_cut))
        for _ in range(20):  # 0.1 s
            out = plant.step(ActuatorCommand(0.05, 0.0, 3000.0), 0.9, 0.9)
        assert plant._esc is not None
        return float(out.x[10]), plant._esc.drive_cut_s

    out_torque, cut_s = rear_torque_after(-0.1, True)
    assert out_torque <= 0.0 and cut_s > 0.0
    for slip, cut in ((-0.1, False), (-0.02, True)):
        torque, cut_s = rear_torque_after(slip, cut)
        assert torque > 500.0 and cut_s == 0.0
    with pytest.raises(ValueError, match="drive_cut"):
        StabilityControlSettings(drive_cut=1)  # type: ignore[arg-type]
    assert load_scenario("turn", ["sim.esc_drive_cut=true"]).sim.stability_control() == (
        StabilityControlSettings(drive_cut=True))


def test_with_the_rear_out_the_steering_no_longer_explains_the_rotation() -> None:
    # The car at 10 m/s turning left at 0.3 rad/s with a_y / v = 0.28 rad/s, the rear 0.1 rad
    # out, the steering asking 0.4 rad/s (a driver steering into the slide). The rule of 0082
    # takes the steering's rate as the explanation and stays passive; returning the body slip
    # (0115), the explained rate is a_y / v less (0.1 − 0.05) / 0.5 s = 0.18 rad/s and the moment
    # removes the 0.12 rad/s beyond it in the response time.
    wheelbase = CAR.cog_to_front_axle_m + CAR.cog_to_rear_axle_m
    steer = 0.4 * wheelbase / 10.0
    old = YawStabilityController(CAR, StabilityControlSettings(body_slip_return_s=None))
    assert old.moment(10.0, 0.3, steer, 2.8, 0.9, -0.1) == (0.0, 0.0)
    esc = YawStabilityController(CAR, StabilityControlSettings())
    assert esc.settings.body_slip_return_s == 0.5
    mz, fx = esc.moment(10.0, 0.3, steer, 2.8, 0.9, -0.1)
    assert mz == pytest.approx(-CAR.yaw_inertia_kgm2 * 0.12 / 0.2)
    assert fx == pytest.approx(-abs(mz) / (0.5 * CAR.track_width_m))
    # Mirrored: the same magnitude, the other way.
    assert esc.moment(10.0, -0.3, -steer, -2.8, 0.9, 0.1)[0] == pytest.approx(-mz)
    # Within the body-slip deadband, or with the slip pointing into the rotation: passive.
    assert esc.moment(10.0, 0.3, steer, 2.8, 0.9, -0.05) == (0.0, 0.0)
    assert esc.moment(10.0, 0.3, steer, 2.8, 0.9, 0.1) == (0.0, 0.0)


@given(slip=st.floats(0.0501, 0.5), more=st.floats(0.0, 0.3), yaw=st.floats(0.05, 1.0),
       accel=st.floats(0.0, 9.0))
def test_the_moment_grows_from_zero_at_the_deadband_with_the_slip(
        slip: float, more: float, yaw: float, accel: float) -> None:
    # Without the yaw-rate deadband the moment is continuous where the controller engages:
    # at a slip just beyond its deadband and a rotation the velocity's turning explains, it is
    # the small one that returns that slip; and it never shrinks as the rear swings further.
    esc = YawStabilityController(CAR, StabilityControlSettings())
    speed = 12.0
    turning = min(accel / speed, yaw)
    at_edge, _ = esc.moment(speed, turning, 0.0, accel, 1.0, -0.05000001)
    assert abs(at_edge) <= CAR.yaw_inertia_kgm2 * 1e-6
    first, _ = esc.moment(speed, yaw, 0.0, accel, 1.0, -slip)
    further, _ = esc.moment(speed, yaw, 0.0, accel, 1.0, -(slip + more))
    assert further <= first <= 0.0


def test_a_drift_on_low_friction_is_held_at_the_deadband_where_it_grew_before() -> None:
    # The car drifting left at 10 m/s on μ 0.3 (rear 0.06 rad out, yaw rate 0.32 rad/s, a little
    # steering, rear drive 100 N m held), 2 s: under the rule of 0082 the yaw rate stays within
    # its deadband of a_y / v and the slip keeps growing (past 0.15 rad); returning the slip,
    # ESC holds it at its deadband.
    import math

    final = {}
    for ret in (None, 0.5):
        x0 = initial_state(CAR, 0.0, 0.0, 0.0, 10.0)
        x0[4], x0[5] = 10.0 * math.tan(-0.06), 0.32
        plant = Plant(CAR, x0, stability_control=StabilityControlSettings(body_slip_return_s=ret))
        for _ in range(400):
            out = plant.step(ActuatorCommand(0.02, 0.0, 100.0), 0.3, 0.3)
        final[ret] = -math.atan2(float(out.x[4]), float(out.x[3]))
    assert final[None] > 0.15
    assert final[0.5] < 0.06


@given(force=st.floats(0.0, 2e4), more=st.floats(0.0, 2e4), mu=st.floats(0.1, 1.2),
       truck=st.booleans())
def test_the_braked_wheel_gives_up_lateral_force_on_the_friction_ellipse(
    force: float, more: float, mu: float, truck: bool,
) -> None:
    params = TRUCK if truck else CAR
    esc = YawStabilityController(params, StabilityControlSettings())
    wheel = mu * 0.5 * params.mass_kg * 9.81 * params.cog_to_rear_axle_m / (
        params.cog_to_front_axle_m + params.cog_to_rear_axle_m)
    share = esc.front_lateral_share(-force, mu)
    r = min(force / wheel, 1.0)
    # The unbraked wheel keeps its half; the braked one keeps √(1 − r²) of its half.
    assert share == pytest.approx(0.5 + 0.5 * (1.0 - r * r) ** 0.5, rel=1e-12)
    assert 0.5 <= share <= 1.0
    assert esc.front_lateral_share(-(force + more), mu) <= share  # more braking, less lateral
    off = YawStabilityController(params, StabilityControlSettings(braked_wheel_lateral_loss=False))
    assert off.front_lateral_share(-force, mu) == 1.0


def test_the_lost_lateral_force_turns_the_spinning_truck_back_sooner() -> None:
    # The truck of the test above, its rear out (body slip 0.1 rad against a right turn): the
    # braked front wheel's lost lateral force takes turning moment off the front axle, so the
    # yaw rate falls faster than with the braking force on top of the tire forces, and ESC
    # acts for less time.
    import math

    runs = {}
    for loss in (False, True):
        x0 = initial_state(TRUCK, 0.0, 0.0, 0.0, 15.0)
        x0[4], x0[5] = 15.0 * math.tan(0.1), -0.6
        esc = StabilityControlSettings(braked_wheel_lateral_loss=loss)
        plant = Plant(TRUCK, x0, stability_control=esc)
        yaw = [float(plant.step(ActuatorCommand(-0.09, 0.0, 0.0), 0.9, 0.9).x[5])
               for _ in range(200)]
        runs[loss] = (yaw, plant.stability_control_active_s)
    (kept, active_kept), (lost, active_lost) = runs[False], runs[True]
    assert abs(lost[0]) < abs(kept[0])  # from the first step on
    assert abs(lost[20]) < abs(kept[20]) - 0.02
    assert active_lost < active_kept


def test_the_lateral_loss_is_a_scenario_setting() -> None:
    assert load_scenario("turn").sim.stability_control() == StabilityControlSettings()
    assert load_scenario("turn", ["sim.esc_braked_wheel_lateral_loss=false"]
                         ).sim.stability_control() == StabilityControlSettings(
                             braked_wheel_lateral_loss=False)
    with pytest.raises(ValueError, match="esc_braked_wheel_lateral_loss"):
        load_scenario("turn", ["sim.esc_braked_wheel_lateral_loss=3"])
    with pytest.raises(ValueError, match="braked_wheel_lateral_loss"):
        StabilityControlSettings(braked_wheel_lateral_loss=1)  # type: ignore[arg-type]
