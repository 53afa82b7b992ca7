"""How many RK4 steps per planning stage keep the planner's discretised model stable.

The planner's model divides the rear tire's slip by ``max(v_x, 1 m/s)``
(:data:`~mufusion.vehicle.planner_model.MIN_SPEED_FOR_SLIP_MPS`), so its lateral and yaw mode
gets faster as the vehicle slows: ``λ ≈ −C_r (1/m + l_r²/I_z) / v_x``. At the slip-speed floor
that is −131 1/s for the car (−33 1/s for the truck). One classical RK4 step per 0.1 s stage
is stable only for ``|λ| dt ≤ 2.785`` on the negative real axis: the car's model, integrated
that way, amplifies its lateral state 939-fold per stage at 1 m/s (45-fold at 2 m/s, 1.7-fold
at 4 m/s), and a plan that stops within its horizon passes through those speeds. The real-time
QP linearised around such a plan is ill-conditioned beyond what HPIPM solves (status 4 at every
step of an emergency stop), while IPOPT on the same problem converges (docs/planner.md,
"Stops within the horizon").

The remedy is the integrator's, not the model's: each stage takes as many RK4 steps as make
the fastest mode stable at every speed the model admits. The backends (acados' ERK, the CasADi
reference) and the planner's own roll-outs of a plan all use :func:`rk4_steps_per_stage`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from mufusion.planner.ocp import PlannerConfig
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import (
    MIN_SPEED_FOR_SLIP_MPS,
    rear_cornering_stiffness_n_per_rad,
)

RK4_STABILITY_LIMIT = 2.785
"""Where classical RK4's stability region meets the negative real axis (|λ dt| ≤ this)."""


def fastest_mode_1ps(params: VehicleParams, utilization: float, max_accel_mps2: float) -> float:
    """The most negative eigenvalue [1/s] of the model's lateral–yaw mode at the slip-speed floor.

    The mode of ``(v_y, ψ̇)`` with the front force an input, at ``v_x`` =
    :data:`~mufusion.vehicle.planner_model.MIN_SPEED_FOR_SLIP_MPS`, with the planner's rear
    cornering stiffness (the secant at ``utilization``) at the largest rear load a plan has:
    the load transfer of ``max_accel_mps2`` [m/s²], the planner's traction cap.
    """
    rear_load = params.mass_kg * (
        GRAVITY_MPS2 * params.cog_to_front_axle_m + max_accel_mps2 * params.cog_height_m
    ) / params.wheelbase_m
    stiffness = float(rear_cornering_stiffness_n_per_rad(params, rear_load, utilization))
    v, m, iz, lr = MIN_SPEED_FOR_SLIP_MPS, params.mass_kg, params.yaw_inertia_kgm2, (
        params.cog_to_rear_axle_m)
    # ∂(v̇_y, ψ̈)/∂(v_y, ψ̇) of frenet_bicycle_dynamics at Δψ = 0, v_y = ψ̇ = 0.
    jacobian = np.array([
        [-stiffness / (m * v), stiffness * lr / (m * v) - v],
        [stiffness * lr / (iz * v), -stiffness * lr * lr / (iz * v)],
    ])
    return float(np.linalg.eigvals(jacobian).real.min())


@functools.lru_cache(maxsize=16)
def rk4_steps_per_stage(
    params: VehicleParams, dt_s: float, utilization: float, max_accel_mps2: float
) -> int:
    """RK4 steps per planning stage of ``dt_s`` [s] that keep the model stable down to rest.

    ``utilization`` and ``max_accel_mps2``: the planner's utilisation factor and traction cap
    (:class:`~mufusion.planner.config.PlannerConfig`), see :func:`fastest_mode_1ps`.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR, TRUCK
    >>> rk4_steps_per_stage(CAR, 0.1, 0.9, 1.5), rk4_steps_per_stage(TRUCK, 0.1, 0.9, 1.5)
    (6, 2)
    """
    if not (math.isfinite(dt_s) and dt_s > 0.0):
        raise ValueError(f"dt_s must be > 0 s, got {dt_s!r}")
    fastest = -fastest_mode_1ps(params, utilization, max_accel_mps2)
    return max(1, math.ceil(fastest * dt_s / RK4_STABILITY_LIMIT))


def stage_steps(config: PlannerConfig, params: VehicleParams) -> int:
    """:func:`rk4_steps_per_stage` for a planner configuration and vehicle; with
    ``config.torque_lag`` at least enough for the lag's own mode ``−1/τ``
    (planner/ocp_state.py): a vehicle whose torques settle much faster than a stage would make
    that state unstable too."""
    steps = rk4_steps_per_stage(params, config.dt_s, config.utilization_factor,
                                config.max_cruise_accel_mps2)
    if config.torque_lag:
        lag_steps = math.ceil(config.dt_s / (params.torque_time_constant_s * RK4_STABILITY_LIMIT))
        steps = max(steps, lag_steps)
    return steps
