"""The planner's discretisation is stable down to rest (planner/integration.py)."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.integration import (
    RK4_STABILITY_LIMIT,
    fastest_mode_1ps,
    rk4_steps_per_stage,
)
from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.sampling import rk4_step
from mufusion.vehicle.params import CAR, TRUCK, VehicleParams
from mufusion.vehicle.planner_model import N_INPUTS, State, rear_cornering_stiffness_n_per_rad

CONFIG = PlannerConfig()


def _stage_amplification(params: VehicleParams, speed_mps: float, steps: int) -> float:
    """Spectral radius of one planning stage (``steps`` RK4 steps) of the lateral–yaw states."""
    c_r = float(rear_cornering_stiffness_n_per_rad(params, params.static_rear_load_n, 0.9))
    x0 = np.array([0.0, 0.0, 0.0, 0.0, speed_mps, 0.0])
    u = np.zeros(N_INPUTS)

    def stage(x):
        for _ in range(steps):
            x = rk4_step(x, u, 0.0, c_r, params, CONFIG.dt_s / steps)
        return x

    eps, idx = 1e-6, (State.psidot, State.vy)
    jac = np.empty((2, 2))
    for j, i in enumerate(idx):
        dx = np.zeros(6)
        dx[i] = eps
        jac[:, j] = (stage(x0 + dx)[list(idx)] - stage(x0 - dx)[list(idx)]) / (2 * eps)
    return float(np.abs(np.linalg.eigvals(jac)).max())


@pytest.mark.parametrize("params", [CAR, TRUCK], ids=["car", "truck"])
def test_one_rk4_step_per_stage_is_unstable_at_low_speed_and_the_substeps_are_not(params):
    steps = rk4_steps_per_stage(params, CONFIG.dt_s, CONFIG.utilization_factor,
                                CONFIG.max_cruise_accel_mps2)
    assert steps > 1
    # One step per stage amplifies the lateral mode near rest (the car by far the most) ...
    assert _stage_amplification(params, 1.0, 1) > 1.5
    # ... the derived number of steps damps it at every speed the model admits.
    for speed in (0.2, 0.5, 1.0, 2.0, 4.0, 8.0, 15.0, 30.0):
        assert _stage_amplification(params, speed, steps) <= 1.0 + 1e-9, speed


def test_the_steps_follow_the_fastest_mode():
    fastest = -fastest_mode_1ps(CAR, 0.9, 1.5)
    steps = rk4_steps_per_stage(CAR, 0.1, 0.9, 1.5)
    assert fastest * 0.1 / steps <= RK4_STABILITY_LIMIT < fastest * 0.1 / (steps - 1)
    # Shorter stages need fewer steps; the car's lighter body needs more than the truck.
    assert rk4_steps_per_stage(CAR, 0.05, 0.9, 1.5) < steps
    assert rk4_steps_per_stage(TRUCK, 0.1, 0.9, 1.5) < steps
    with pytest.raises(ValueError, match="dt_s must be > 0"):
        rk4_steps_per_stage(CAR, 0.0, 0.9, 1.5)


def test_the_torque_lag_state_gets_the_steps_its_own_mode_needs():
    # A first-order lag of τ is the mode −1/τ: one RK4 step of 0.1 s is unstable for τ below
    # 0.1 / 2.785 s. The package's vehicles are far from it (car 0.05 s, truck 0.15 s), so their
    # steps stay those of the lateral–yaw mode; a vehicle with 5 ms torques needs 8 per stage.
    from dataclasses import replace

    from mufusion.planner.integration import stage_steps

    lagged, free = PlannerConfig(torque_lag=True), PlannerConfig(torque_lag=False)
    for params in (CAR, TRUCK):
        assert stage_steps(lagged, params) == stage_steps(free, params)
    fast = replace(TRUCK, torque_time_constant_s=0.005)
    assert stage_steps(free, fast) == stage_steps(free, TRUCK)
    steps = stage_steps(lagged, fast)
    assert steps == 8
    # The lag over a stage, as the steps integrate it: decays (not amplified) with them, and
    # amplified with one step.
    def decay(n: int) -> float:
        z = -lagged.dt_s / n / fast.torque_time_constant_s
        return abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24) ** n
    assert decay(steps) < 1.0 < decay(1)
