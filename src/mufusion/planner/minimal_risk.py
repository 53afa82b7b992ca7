"""Minimal-risk manoeuvre: brake to a stop in lane at a declared fraction of μ̂ g.

The manoeuvre a supervisor falls back to when the planner has not produced a usable solution for
``SafetySettings.max_consecutive_fallbacks`` steps in a row (or cannot be trusted otherwise). Its
roll-out needs no solver: the planner's model under a braking and lane-keeping law.

* Deceleration target ``a_k = minimal_risk_decel_fraction · μ̂(s_k) · g`` (default 0.8 μ̂ g),
  never more than stops the vehicle within the step; no traction. Below 1 m/s (the planner
  model's slip-speed floor) the vehicle is taken to rest and held there with the brakes on.
* The braking force is split over the axles by their normal loads, and each axle's share is
  capped at 80 % of its friction limit ``λ μ̂ F_z``, so the tires keep lateral reserve.
* Steering: the roll-outs' law of :mod:`mufusion.planner.sampling`, towards ``reference_d_m``
  (the lane centre) along the road's curvature, saturated at the front axle's remaining friction.

In :meth:`TractionAdaptivePlanner.step` with ``mode="minimal_risk"`` this roll-out is the
initial guess; the OCP then tracks its speed profile (corridor and friction polygons as in
every mode), and if the solve fails or is rejected the roll-out itself is the plan.

While no plan can be trusted at all the loop applies :func:`minimal_risk_command` directly:
curvature feed-forward plus lateral and heading feedback for steering, braking with what the
friction circle at the same share of μ̂ g leaves after the lateral acceleration that following
the lane takes (``v² κ``; where that is beyond the circle, the split that sheds the speed the
curve asks with the least depth, :func:`lane_keeping_braking_mps2`), split over the axles by
their static loads (no model, no optimisation; the vehicle's ABS keeps the wheels rolling if μ̂
over-estimates the road).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mufusion.planner.config import PlannerMode
from mufusion.planner.integration import stage_steps
from mufusion.planner.ocp import PlannerConfig, longitudinal_force_bounds_n
from mufusion.planner.sampling import SamplingConfig, rk4_step, steering_force_n
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import (
    MIN_SPEED_FOR_SLIP_MPS,
    N_INPUTS,
    Input,
    State,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
)
from mufusion.vehicle.tires import peak_slip_angle_rad

# Share of each axle's friction limit the braking force may use; the rest stays for steering.
BRAKING_SHARE_OF_LIMIT = 0.8

AT_REST_MPS = 0.1
"""Below this speed [m/s] (the body's, ``hypot(v_x, v_y)``: a spinning vehicle's ``v_x`` passes
through 0 while it slides) a vehicle that is stopping has stopped."""
HELD_AT_REST_MODES: tuple[PlannerMode, ...] = ("emergency", "minimal_risk")
"""The stopping modes whose plan, once the stop is done (:func:`stop_is_held`), is the stop
held with the brakes on (:func:`~mufusion.planner.rti.held_plan`), not a solve: the model's
brakes are kinetic friction, so the braking the wheels deliver (where the plan's forces start,
0068) would drive it backwards, against the speed's bound: the QP is infeasible
(docs/decisions/0098)."""


def at_rest(x: np.ndarray) -> bool:
    """Whether the Frenet state ``x`` is at rest: its body speed below :data:`AT_REST_MPS`."""
    return float(np.hypot(x[State.vx], x[State.vy])) < AT_REST_MPS


def stop_is_held(mode: str, x0: np.ndarray, longitudinal_forces_n: tuple[float, float] | None,
                 params: VehicleParams, config: PlannerConfig) -> bool:
    """Whether a step of a stopping mode (:data:`HELD_AT_REST_MODES`) holds the stop instead of
    solving: the vehicle is at rest (:data:`AT_REST_MPS`), or, with the longitudinal forces
    planned as lagged states (``config.torque_lag``), the braking the wheels deliver now
    (``longitudinal_forces_n``) brings it to rest even if released at once: the lagged force
    decays as ``e^{−t/τ}`` and takes ``a τ`` off the speed in all, so where ``v < a τ`` the OCP's
    speed would go below its bound and its QP is infeasible (docs/decisions/0098).

    >>> from mufusion.vehicle.params import CAR
    >>> from mufusion.planner.ocp import PlannerConfig
    >>> x0 = np.array([0.0, 0.0, 0.0, 0.0, 0.2, 0.0])  # the car: 5.5 m/s², τ 0.05 s: 0.27 m/s
    >>> [stop_is_held(m, x0, f, CAR, PlannerConfig()) for m, f in
    ...  [("emergency", (-4000.0, -2000.0)), ("emergency", (0.0, 0.0)), ("cruise", None)]]
    [True, False, False]
    """
    if mode not in HELD_AT_REST_MODES:
        return False
    if at_rest(x0):
        return True
    speed = float(np.hypot(x0[State.vx], x0[State.vy]))
    if not config.torque_lag or longitudinal_forces_n is None:
        return False
    decel = -float(sum(longitudinal_forces_n)) / params.mass_kg
    if not math.isfinite(decel) or decel <= 0.0:
        return False
    return speed < decel * params.torque_time_constant_s


def minimal_risk_rollout(
    x0: np.ndarray,
    reference_d_m: float,
    curvature_of_s: Callable[[np.ndarray], np.ndarray],
    mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
    params: VehicleParams,
    config: PlannerConfig,
    sampling: SamplingConfig | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Roll out the minimal-risk manoeuvre from ``x0`` over the planner's horizon.

    Parameters
    ----------
    x0
        Frenet state (6,), see :class:`~mufusion.vehicle.planner_model.State`.
    reference_d_m
        Lateral offset to hold [m] (the lane centre).
    curvature_of_s, mu_hat_of_s
        Road curvature [1/m] and a finite, positive friction estimate as functions of ``s`` [m]
        (the planner passes its sanitised estimate).
    params
        Vehicle parameters.
    config
        Planner configuration (horizon, ``dt``, utilisation factor, deceleration fraction).
    sampling
        Gains of the steering law (default :class:`SamplingConfig`).

    Returns
    -------
    states, inputs
        ``(N+1, 6)`` and ``(N, 3)``.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> cfg = PlannerConfig(horizon_steps=40)
    >>> xs, us = minimal_risk_rollout(np.array([0, 0.3, 0, 0, 10.0, 0]), 0.0,
    ...                               lambda s: 0 * s, lambda s: 0.8 + 0 * s, TRUCK, cfg)
    >>> bool(xs[-1, State.vx] < 0.1), bool(abs(xs[-1, State.d]) < 0.15)
    (True, True)
    """
    sc = sampling or SamplingConfig()
    n, dt, lam = config.horizon_steps, config.dt_s, config.utilization_factor
    steps = stage_steps(config, params)
    m = params.mass_kg
    x = np.asarray(x0, dtype=float).copy()
    xs, us = [x], []
    ax = 0.0
    for _ in range(n):
        s = np.array([x[State.s]])
        kappa = float(np.asarray(curvature_of_s(s), dtype=float).reshape(-1)[0])
        mu = float(np.asarray(mu_hat_of_s(s), dtype=float).reshape(-1)[0])
        fzf, fzr = (float(f) for f in normal_loads_n(ax, params))
        c_r = float(rear_cornering_stiffness_n_per_rad(
            params, fzr, lam, mu_hat=mu, table=config.stiffness_table
        ))
        limit_f, limit_r = lam * mu * fzf, lam * mu * fzr
        # Brake at the declared deceleration, but never past standstill within this step.
        decel_target = config.safety.minimal_risk_decel_fraction * mu * GRAVITY_MPS2
        decel = min(decel_target, max(x[State.vx], 0.0) / dt)
        fxf, fxr = _braking_forces_n(m * decel, fzf, fzr, limit_f, limit_r, params)
        hold_f, hold_r = _braking_forces_n(m * decel_target, fzf, fzr, limit_f, limit_r, params)
        u = np.zeros(N_INPUTS)
        if x[State.vx] <= MIN_SPEED_FOR_SLIP_MPS:
            # Below the model's slip-speed floor its lateral modes are too stiff for an explicit
            # step of dt; the remaining travel (v²/2a, under 0.2 m) is covered along the heading
            # and the vehicle is held at rest with the brakes on.
            travel = 0.5 * x[State.vx] ** 2 / max(decel_target, 1e-9)
            x = x.copy()
            x[State.s] += travel * np.cos(x[State.dpsi])
            x[State.d] += travel * np.sin(x[State.dpsi])
            x[State.vx] = x[State.vy] = x[State.psidot] = 0.0
            u[Input.fxf], u[Input.fxr] = hold_f, hold_r
            ax = 0.0
        else:
            v = max(x[State.vx], 1.0)
            fyf = float(steering_force_n(x, reference_d_m, kappa, v, params, sc))
            room = np.sqrt(max(limit_f**2 - fxf**2, 0.0)) * 0.95
            u[Input.fyf] = np.clip(fyf, -room, room)
            u[Input.fxf], u[Input.fxr] = fxf, fxr
            for _ in range(steps):  # as the OCP integrates its stages (planner/integration.py)
                x = rk4_step(x, u, kappa, c_r, params, dt / steps)
            x[State.vx] = max(x[State.vx], 0.0)
            ax = (fxf + fxr) / m
        xs.append(x)
        us.append(u)
    return np.stack(xs), np.stack(us)


def _braking_forces_n(
    force_n: float, fzf: float, fzr: float, limit_f: float, limit_r: float,
    params: VehicleParams,
) -> tuple[float, float]:
    """Braking force ``force_n`` ≥ 0 split by normal load, each axle capped (negative values)."""
    lower, _ = longitudinal_force_bounds_n(params)
    share_f = fzf / (fzf + fzr)
    fxf = -min(force_n * share_f, BRAKING_SHARE_OF_LIMIT * limit_f, -lower[0])
    fxr = -min(force_n * (1.0 - share_f), BRAKING_SHARE_OF_LIMIT * limit_r, -lower[1])
    return fxf, fxr


@dataclass(frozen=True)
class LaneKeepingGains:
    """Steering feedback of the manoeuvre (left positive, like the Frenet offset)."""

    lateral_rad_per_m: float = 0.05
    heading_rad_per_rad: float = 0.8


def lane_keeping_braking_mps2(speed_mps: float, curvature_1pm: float,
                              available_mps2: float) -> float:
    """Deceleration [m/s²] of the minimal-risk manoeuvre's braking on a friction circle of radius
    ``available_mps2``, beside the lateral acceleration that following the lane takes.

    Within the tires (``v² |κ| ≤ a``) the lane takes ``v² |κ|`` and the braking the rest,
    ``√(a² − v⁴κ²)``. Beyond them the vehicle leaves the lane whatever it does until it is slower
    than ``√(a / |κ|)``, and the lane's lateral acceleration is no share to reserve: at a split
    ``a_y = a sin θ``, ``a_x = a cos θ`` the depth it reaches meanwhile grows with the curvature
    it lacks, ``|κ| − a_y / v²``, times the square of the distance it needs to slow down,
    ``∝ 1 / cos² θ``. With ``c = a / (v² |κ|) < 1`` that is ``(1 − c sin θ) / cos² θ``, least at
    ``sin θ = (1 − √(1 − c²)) / c``: all lateral at the tires' edge (``c = 1``, continuous with
    the case within them), nearly all braking far beyond it (docs/decisions/0114).

    >>> round(lane_keeping_braking_mps2(10.0, 0.0, 4.0), 3)  # straight: all braking
    4.0
    >>> round(lane_keeping_braking_mps2(10.0, 0.02, 4.0), 3)  # 2 of 4 m/s² lateral
    3.464
    >>> round(lane_keeping_braking_mps2(10.0, 0.08, 4.0), 3)  # the lane asks 8: brake
    3.854
    """
    available = max(float(available_mps2), 0.0)
    lateral = float(speed_mps) ** 2 * abs(float(curvature_1pm))
    if lateral <= available:
        return math.sqrt(available * available - lateral * lateral)
    c = available / lateral
    lateral_share = (1.0 - math.sqrt(1.0 - c * c)) / c
    return available * math.sqrt(1.0 - lateral_share * lateral_share)


def minimal_risk_command(
    x_frenet: np.ndarray,
    curvature_1pm: float,
    params: VehicleParams,
    mu: float,
    utilization: float,
    gains: LaneKeepingGains | None = None,
) -> ActuatorCommand:
    """Actuator command of the minimal-risk manoeuvre at Frenet state ``x_frenet``.

    Parameters
    ----------
    x_frenet
        ``(s, d, Δψ, ψ̇, v_x, v_y)``.
    curvature_1pm
        Road curvature at the vehicle [1/m].
    params
        Vehicle parameters.
    mu
        Friction assumed for braking [-] (the last usable estimate under the vehicle, or the
        floor).
    utilization
        Share of ``μ g`` the manoeuvre may use [-], in (0, 1]: the lateral acceleration the
        lane's curvature asks at the current speed first, braking with the rest.

    Raises
    ------
    ValueError
        If ``mu`` or ``utilization`` is out of range.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> cmd = minimal_risk_command(np.array([0, 0, 0, 0, 10.0, 0]), 0.0, TRUCK, 0.4, 0.5)
    >>> cmd.steer_rad, cmd.torque_front_nm < 0 and cmd.torque_rear_nm < 0
    (0.0, True)
    """
    if not (np.isfinite(mu) and 0.0 < mu <= 2.0):
        raise ValueError(f"mu must be in (0, 2], got {mu!r}")
    if not 0.0 < utilization <= 1.0:
        raise ValueError(f"utilization must be in (0, 1], got {utilization!r}")
    g = gains or LaneKeepingGains()
    x = np.asarray(x_frenet, dtype=float)
    d = float(x[State.d]) if np.isfinite(x[State.d]) else 0.0
    dpsi = float(x[State.dpsi]) if np.isfinite(x[State.dpsi]) else 0.0
    speed = float(x[State.vx]) if np.isfinite(x[State.vx]) else 0.0
    steer = (
        params.wheelbase_m * curvature_1pm
        - g.lateral_rad_per_m * d
        - g.heading_rad_per_rad * dpsi
    )
    # No further than the front tire's peak slip angle on μ from the direction the front axle
    # moves: beyond it the tire gives less, not more. Sliding 5 m off the lane on μ 0.15 the
    # feedback asked the car for 0.35 rad with its front axle moving 0.27 rad the other way, a
    # slip angle 29 times the peak, and it spun (docs/decisions/0114).
    vy, yaw_rate = (float(x[i]) if np.isfinite(x[i]) else 0.0 for i in (State.vy, State.psidot))
    course = math.atan2(vy + params.cog_to_front_axle_m * yaw_rate, max(speed, 1.0))
    peak = peak_slip_angle_rad(params.tire, mu)
    steer = min(max(steer, course - peak), course + peak)
    force = params.mass_kg * lane_keeping_braking_mps2(
        speed, curvature_1pm, utilization * mu * GRAVITY_MPS2)
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    r = params.wheel_radius_m
    return ActuatorCommand(
        float(steer), -share_front * force * r, -(1.0 - share_front) * force * r
    ).clipped(params)
