"""Physics invariants of the plant that need no reference model."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import CAR, GRAVITY_MPS2, TRUCK, VehicleParams
from mufusion.vehicle.plant import (
    Plant,
    PlantState,
    axle_forces,
    axle_positions,
    initial_state,
    plant_derivative,
)


def _braking_command(params: VehicleParams, mu: float, fraction: float) -> ActuatorCommand:
    """Brake torques asking each axle for ``fraction`` of μ F_z at a = −μ g (load transfer)."""
    decel = mu * GRAVITY_MPS2
    per_length = params.mass_kg / params.wheelbase_m
    fzf = per_length * (GRAVITY_MPS2 * params.cog_to_rear_axle_m + decel * params.cog_height_m)
    fzr = per_length * (GRAVITY_MPS2 * params.cog_to_front_axle_m - decel * params.cog_height_m)
    radius = params.wheel_radius_m
    return ActuatorCommand(0.0, -fraction * mu * fzf * radius, -fraction * mu * fzr * radius)


@pytest.mark.parametrize("params", [TRUCK, CAR], ids=["truck", "car"])
@pytest.mark.parametrize("mu", [0.3, 0.8])
def test_full_braking_stops_in_about_v2_over_2_mu_g(params: VehicleParams, mu: float) -> None:
    speed = 20.0
    plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, speed))
    command = _braking_command(params, mu, 0.97)
    for _ in range(4000):
        out = plant.step(command, mu, mu)
        if out.speed_mps < 1e-3:
            break
    ideal = speed**2 / (2.0 * mu * GRAVITY_MPS2)
    # 97 % of the limit plus the torque build-up (≈ speed × time constant of dead travel).
    expected = ideal / 0.97 + speed * params.torque_time_constant_s
    assert out.speed_mps < 1e-3
    assert out.x[PlantState.X] == pytest.approx(expected, rel=0.05)
    assert out.utilization_front <= 1.0 and out.utilization_rear <= 1.0


def test_standstill_with_brakes_is_stable() -> None:
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 3.0))
    for _ in range(1000):
        out = plant.step(ActuatorCommand(0.3, -20_000.0, -20_000.0), 0.5, 0.5)
    x = out.x
    assert np.all(np.isfinite(x))
    assert abs(x[PlantState.VX]) < 1e-3 and abs(x[PlantState.VY]) < 1e-3
    assert x[PlantState.OMEGA_FRONT] == 0.0 and x[PlantState.OMEGA_REAR] == 0.0
    before = x[PlantState.X]
    for _ in range(400):
        out = plant.step(ActuatorCommand(0.3, -20_000.0, -20_000.0), 0.5, 0.5)
    assert abs(out.x[PlantState.X] - before) < 1e-3


def test_starts_from_rest_when_driving_torque_is_applied() -> None:
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 0.0))
    for _ in range(400):
        out = plant.step(ActuatorCommand(0.0, 0.0, 10_000.0), 0.8, 0.8)
    assert np.all(np.isfinite(out.x))
    assert 1.0 < out.speed_mps < 2.0 * 10_000.0 / TRUCK.wheel_radius_m / TRUCK.mass_kg * 2.0


@pytest.mark.parametrize("params", [TRUCK, CAR], ids=["truck", "car"])
@pytest.mark.parametrize("mu", [0.4, 0.9])
def test_steady_cornering_saturates_at_mu_g(params: VehicleParams, mu: float) -> None:
    plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, 12.0))
    lateral = []
    for k in range(1400):
        # Ramp steer at 0.08 rad/s, wheels rolling freely (a drive torque would use up rear grip).
        out = plant.step(ActuatorCommand(0.08 * k / 200.0, 0.0, 0.0), mu, mu)
        lateral.append(math.hypot(out.accel_x_mps2, out.accel_y_mps2))
    peak = max(lateral)
    assert 0.93 * mu * GRAVITY_MPS2 < peak <= mu * GRAVITY_MPS2 * (1.0 + 1e-9)


@settings(max_examples=25, deadline=None)
@given(
    steer=st.floats(-0.6, 0.6),
    torque_front=st.floats(-50_000.0, 0.0),
    torque_rear=st.floats(-40_000.0, 30_000.0),
    mu=st.floats(0.1, 1.2),
    speed=st.floats(0.0, 25.0),
)
def test_total_tire_force_never_exceeds_mu_m_g(
    steer: float, torque_front: float, torque_rear: float, mu: float, speed: float
) -> None:
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, speed))
    for _ in range(100):
        out = plant.step(ActuatorCommand(steer, torque_front, torque_rear), mu, mu)
        assert np.all(np.isfinite(out.x))
        assert math.hypot(out.accel_x_mps2, out.accel_y_mps2) <= mu * GRAVITY_MPS2 * (1 + 1e-9)
        assert 0.0 <= out.utilization_front <= 1.0 and 0.0 <= out.utilization_rear <= 1.0


def test_locked_wheels_request_more_than_the_road_gives() -> None:
    mu = 0.5
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 20.0))
    for _ in range(200):
        out = plant.step(ActuatorCommand(0.0, -1e6, -1e6), mu, mu)
    assert out.x[PlantState.OMEGA_FRONT] == 0.0 and out.x[PlantState.OMEGA_REAR] == 0.0
    assert out.front.requested_utilization > 1.0 and out.rear.requested_utilization > 1.0
    assert out.utilization_front <= 1.0 and out.utilization_rear <= 1.0
    # Sliding: the wheel runs at zero speed while the truck still moves.
    assert out.front.slip_ratio == pytest.approx(-1.0)


def test_cornering_above_the_limit_slides_and_leaves_the_kinematic_path() -> None:
    """Same steering on high and low μ: on low μ the truck ploughs, side-slip and offset grow."""
    steer, speed = 0.06, 15.0
    runs = {}
    for mu in (1.0, 0.3):
        plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, speed))
        path = []
        for _ in range(400):
            out = plant.step(ActuatorCommand(steer, 0.0, 0.0), mu, mu)
            path.append(out)
        runs[mu] = path
    low = runs[0.3]
    assert low[-1].front.requested_utilization > 1.0
    assert low[-1].front.utilization <= 1.0
    # High μ follows the steering (a_y ≈ v² tan δ / L > 0.3 g); low μ is capped at μ g and the
    # side-slip angle keeps growing.
    kinematic = speed**2 * math.tan(steer) / TRUCK.wheelbase_m
    assert runs[1.0][-1].accel_y_mps2 == pytest.approx(kinematic, rel=0.15)
    assert max(abs(o.accel_y_mps2) for o in low) <= 0.3 * GRAVITY_MPS2 * (1 + 1e-9)

    def side_slip(o) -> float:
        return abs(math.atan2(o.x[PlantState.VY], o.x[PlantState.VX]))

    assert side_slip(low[399]) > side_slip(low[300]) > side_slip(low[200])
    assert side_slip(low[399]) > 2.0 * side_slip(runs[1.0][399])
    # Lateral distance between the two paths grows over time.
    gaps = [
        math.dist(a.x[: PlantState.Y + 1], b.x[: PlantState.Y + 1])
        for a, b in zip(runs[1.0], low, strict=True)
    ]
    assert gaps[399] > gaps[300] > gaps[200] > gaps[100]


def test_friction_under_one_axle_only_affects_that_axle() -> None:
    x = initial_state(TRUCK, 0.0, 0.0, 0.0, 15.0)
    x[PlantState.VY] = -0.8
    x[PlantState.YAW_RATE] = 0.3
    x[PlantState.STEER] = 0.1
    base_front, base_rear = axle_forces(x, 0.8, 0.8, TRUCK)
    front, rear = axle_forces(x, 0.8, 0.2, TRUCK)
    assert rear.fy_n != pytest.approx(base_rear.fy_n, rel=0.05)
    assert front.fy_n / front.fz_n == pytest.approx(base_front.fy_n / base_front.fz_n, rel=1e-12)
    assert front.utilization == pytest.approx(base_front.utilization, rel=1e-12)
    assert rear.requested_utilization == pytest.approx(
        4.0 * base_rear.requested_utilization, rel=1e-9
    )
    assert (front.mu, rear.mu) == (0.8, 0.2)


def test_split_mu_braking_locks_only_the_low_mu_axle() -> None:
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 15.0))
    command = _braking_command(TRUCK, 0.8, 0.9)
    for _ in range(100):
        out = plant.step(command, 0.2, 0.8)
    assert out.x[PlantState.OMEGA_FRONT] == 0.0
    assert out.x[PlantState.OMEGA_REAR] > 0.8 * out.speed_mps / TRUCK.wheel_radius_m
    assert out.front.requested_utilization > 1.0 > out.rear.requested_utilization


def test_steering_actuator_respects_rate_and_angle_limits() -> None:
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 10.0))
    previous = 0.0
    for _ in range(600):
        out = plant.step(ActuatorCommand(5.0, 0.0, 0.0), 0.8, 0.8)
        steer = out.x[PlantState.STEER]
        assert steer - previous <= TRUCK.max_steer_rate_radps * plant.dt_s + 1e-12
        previous = steer
    assert previous <= TRUCK.max_steer_rad + 1e-12
    assert previous == pytest.approx(TRUCK.max_steer_rad, abs=1e-3)


def test_step_agrees_with_fine_integration_of_the_pure_derivative() -> None:
    x = initial_state(CAR, 0.0, 0.0, 0.0, 15.0)
    plant = Plant(CAR, x)

    def command(t: float) -> ActuatorCommand:
        return ActuatorCommand(0.05 * math.sin(2.0 * t), -500.0 if t > 0.5 else 0.0, 0.0)

    fine_dt = 1.0 / 4000.0
    for k in range(400):
        t = k * plant.dt_s
        plant.step(command(t), 0.9, 0.9)
        for j in range(20):
            u = command(t)
            k1 = plant_derivative(x, u, 0.9, 0.9, CAR)
            k2 = plant_derivative(x + 0.5 * fine_dt * k1, u, 0.9, 0.9, CAR)
            x = x + fine_dt * k2
            del j
    error = np.abs(plant.x - x)
    assert error[PlantState.X] < 0.01 and error[PlantState.Y] < 0.01
    assert error[PlantState.YAW_RATE] < 1e-3 and error[PlantState.VX] < 5e-3
    assert error[PlantState.OMEGA_FRONT] * CAR.wheel_radius_m < 5e-3


def test_initial_state_rolls_freely_and_axles_are_a_wheelbase_apart() -> None:
    x = initial_state(TRUCK, 3.0, -2.0, 0.7, 12.0)
    front, rear = axle_forces(x, 0.8, 0.8, TRUCK)
    assert front.slip_ratio == pytest.approx(0.0, abs=1e-12)
    assert rear.slip_ratio == pytest.approx(0.0, abs=1e-12)
    xd = plant_derivative(x, ActuatorCommand(0.0, 0.0, 0.0), 0.8, 0.8, TRUCK)
    assert xd[PlantState.VX] == pytest.approx(0.0, abs=1e-9)
    front, rear = axle_positions(x, TRUCK)
    assert math.dist(front, rear) == pytest.approx(TRUCK.wheelbase_m)


@pytest.mark.parametrize(
    "mu_front, mu_rear, name", [(0.0, 0.5, "mu_front"), (0.5, -1.0, "mu_rear")]
)
def test_non_positive_mu_is_rejected(mu_front: float, mu_rear: float, name: str) -> None:
    plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 10.0))
    with pytest.raises(ValueError, match=name):
        plant.step(ActuatorCommand(0.0, 0.0, 0.0), mu_front, mu_rear)
    with pytest.raises(ValueError, match=name):
        plant_derivative(plant.x, np.zeros(3), mu_front, mu_rear, TRUCK)


def test_bad_arguments_are_rejected_with_their_names() -> None:
    with pytest.raises(ValueError, match="mass_kg"):
        replace(TRUCK, mass_kg=-1.0)
    with pytest.raises(ValueError, match="dt_s"):
        Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, 1.0), dt_s=0.01)
    with pytest.raises(ValueError, match="x must have shape"):
        Plant(TRUCK, np.zeros(5))
    with pytest.raises(ValueError, match="speed_mps"):
        initial_state(TRUCK, 0.0, 0.0, 0.0, -1.0)
    with pytest.raises(ValueError, match="command"):
        plant_derivative(initial_state(TRUCK, 0.0, 0.0, 0.0, 1.0), np.zeros(2), 0.5, 0.5, TRUCK)


def test_the_front_lateral_force_is_the_body_frame_share_of_the_lateral_balance() -> None:
    # Steered and braking: the wheel frame's F_x has a lateral share sin δ in the body frame, so
    # the body-frame force differs from the wheel frame's F_y, and with the rear's F_y it is
    # what accelerates the body sideways (the planner's F_yf, docs/decisions/0051).
    plant = Plant(CAR, initial_state(CAR, 0.0, 0.0, 0.0, 15.0))
    for _ in range(60):
        out = plant.step(ActuatorCommand(0.08, -900.0, -300.0), 0.9, 0.9)
    steer = out.x[PlantState.STEER]
    assert steer > 0.05 and out.front.fx_n < -500.0
    assert out.front_lateral_force_n == pytest.approx(
        CAR.mass_kg * out.accel_y_mps2 - out.rear.fy_n, rel=1e-9)
    assert abs(out.front_lateral_force_n - out.front.fy_n) > 0.04 * abs(out.front.fx_n)
