"""The plant against an independent reference: CommonRoad's single-track drift model (STD).

Design of the comparison (see docs/vehicle.md):
* same vehicle: our CAR preset is CommonRoad's parameter set 2; the load-transfer height is set to
  STD's ``h_s`` (STD uses the sprung-mass CoG height there);
* same tires: STD's peak factors ``p_dx1``, ``p_dy1`` are set to μ (ours peak at μ F_z), keeping
  its stiffness ``p_kx1 F_z``, ``p_ky1 F_z`` and shapes, which our CAR preset copies;
* same inputs: STD takes a steering rate and an acceleration; it is fed our plant's own steering
  rate over each step (so both steering-angle histories coincide at every sample) and our plant's
  lagged wheel torque divided by ``m R_w`` (STD converts it back to the same torques with its
  front/rear brake split ``T_sb``, which our command uses as well).
STD is integrated with RK4 at 10 sub-steps per plant step.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest
from vehiclemodels.init_std import init_std
from vehiclemodels.parameters_vehicle2 import parameters_vehicle2
from vehiclemodels.vehicle_dynamics_std import vehicle_dynamics_std

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import CAR
from mufusion.vehicle.plant import Plant, PlantState, initial_state

DT_S = 1.0 / 200.0
STD_SUBSTEPS = 10


def _std_params(mu: float):
    p = parameters_vehicle2()
    p.tire.p_dx1 = mu
    p.tire.p_dy1 = mu
    return p


def _rk4(x: list[float], u: list[float], p, h: float) -> list[float]:
    k1 = vehicle_dynamics_std(list(x), u, p)
    k2 = vehicle_dynamics_std([a + 0.5 * h * b for a, b in zip(x, k1, strict=True)], u, p)
    k3 = vehicle_dynamics_std([a + 0.5 * h * b for a, b in zip(x, k2, strict=True)], u, p)
    k4 = vehicle_dynamics_std([a + h * b for a, b in zip(x, k3, strict=True)], u, p)
    return [
        a + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
        for a, b1, b2, b3, b4 in zip(x, k1, k2, k3, k4, strict=True)
    ]


def run_pair(
    speed_mps: float,
    steer_rad: Callable[[float], float],
    total_torque_nm: Callable[[float], float],
    duration_s: float,
    mu: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Columns: X, Y, ψ, speed, yaw rate, side-slip β, steering angle; one row per plant step."""
    p = _std_params(mu)
    params = replace(CAR, cog_height_m=p.h_s)
    plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, speed_mps), DT_S)
    xs = init_std([0.0, 0.0, 0.0, speed_mps, 0.0, 0.0, 0.0], p)
    ours, theirs = [], []
    for k in range(round(duration_s / DT_S)):
        t = k * DT_S
        x0 = plant.x
        torque = total_torque_nm(t)
        plant.step(ActuatorCommand(steer_rad(t), p.T_sb * torque, (1 - p.T_sb) * torque), mu, mu)
        x1 = plant.x
        steer_rate = (x1[PlantState.STEER] - x0[PlantState.STEER]) / DT_S
        applied = 0.5 * (
            x0[PlantState.TORQUE_FRONT] + x0[PlantState.TORQUE_REAR]
            + x1[PlantState.TORQUE_FRONT] + x1[PlantState.TORQUE_REAR]
        )
        u = [steer_rate, applied / (p.m * p.R_w)]
        for _ in range(STD_SUBSTEPS):
            xs = _rk4(xs, u, p, DT_S / STD_SUBSTEPS)
        vx, vy = x1[PlantState.VX], x1[PlantState.VY]
        ours.append([x1[PlantState.X], x1[PlantState.Y], x1[PlantState.PSI], math.hypot(vx, vy),
                     x1[PlantState.YAW_RATE], math.atan2(vy, vx), x1[PlantState.STEER]])
        theirs.append([xs[0], xs[1], xs[4], xs[3], xs[5], xs[6], xs[2]])
    return np.asarray(ours), np.asarray(theirs)


COLUMNS = {"X": 0, "Y": 1, "psi": 2, "speed": 3, "yaw_rate": 4, "beta": 5, "steer": 6}


def _max_error(ours: np.ndarray, theirs: np.ndarray, name: str) -> float:
    return float(np.max(np.abs(ours[:, COLUMNS[name]] - theirs[:, COLUMNS[name]])))


def _max_abs(values: np.ndarray, name: str) -> float:
    return float(np.max(np.abs(values[:, COLUMNS[name]])))


@pytest.mark.parametrize("amplitude_rad", [0.01, 0.03])
def test_step_steer_agrees_in_the_linear_range(amplitude_rad: float) -> None:
    # 15 m/s, lateral acceleration up to ≈ 2.7 m/s² (≈ 0.28 g): linear tire range.
    ours, theirs = run_pair(15.0, lambda t: amplitude_rad if t > 0.2 else 0.0, lambda t: 0.0, 3.0)
    assert _max_error(ours, theirs, "steer") < 1e-9
    # Tolerances: 2 % of the peak yaw rate, 2 % of the peak side-slip, 5 cm in position.
    assert _max_error(ours, theirs, "yaw_rate") < 0.02 * _max_abs(theirs, "yaw_rate")
    assert _max_error(ours, theirs, "beta") < 0.02 * _max_abs(theirs, "beta")
    assert _max_error(ours, theirs, "Y") < 0.05
    assert _max_error(ours, theirs, "X") < 0.05
    assert _max_error(ours, theirs, "speed") < 0.01


def test_sine_steer_agrees_in_the_linear_range() -> None:
    ours, theirs = run_pair(
        15.0, lambda t: 0.04 * math.sin(2.0 * math.pi * 0.5 * t), lambda t: 0.0, 4.0
    )
    assert _max_error(ours, theirs, "yaw_rate") < 0.02 * _max_abs(theirs, "yaw_rate")
    assert _max_error(ours, theirs, "psi") < 0.02 * _max_abs(theirs, "psi")
    assert _max_error(ours, theirs, "Y") < 0.05


@pytest.mark.parametrize("decel_mps2", [2.0, 5.0])
def test_straight_braking_agrees(decel_mps2: float) -> None:
    torque = -decel_mps2 * CAR.mass_kg * CAR.wheel_radius_m
    ours, theirs = run_pair(20.0, lambda t: 0.0, lambda t: torque if t > 0.2 else 0.0, 1.5)
    # 2 cm/s in speed and 3 cm in distance after 1.5 s.
    assert _max_error(ours, theirs, "speed") < 0.02
    assert _max_error(ours, theirs, "X") < 0.03
    speed_drop = theirs[0, COLUMNS["speed"]] - theirs[-1, COLUMNS["speed"]]
    assert speed_drop == pytest.approx(decel_mps2 * 1.3, rel=0.1)


@pytest.mark.parametrize("mu", [0.4, 1.0])
def test_both_models_saturate_near_mu_g_in_a_slow_ramp_steer(mu: float) -> None:
    # At the limit the models differ (combined-slip law, STD's offsets and kinematic blend), but
    # both must saturate their lateral acceleration near μ g. Ramp steer at 12 m/s.
    ours, theirs = run_pair(12.0, lambda t: 0.05 * t, lambda t: 0.0, 6.0, mu=mu)
    for traj in (ours, theirs):
        speed, yaw_rate = traj[:, COLUMNS["speed"]], traj[:, COLUMNS["yaw_rate"]]
        beta_rate = np.gradient(traj[:, COLUMNS["beta"]], DT_S)
        lateral = speed * (yaw_rate + beta_rate)
        peak = float(np.max(lateral[100:]))
        assert 0.9 * mu * 9.81 < peak < 1.05 * mu * 9.81
