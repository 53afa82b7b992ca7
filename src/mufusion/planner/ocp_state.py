"""The OCP's state beyond the planner's six: the tire forces an actuator cannot jump.

The planner plans tire forces (TAMP); a force input may change arbitrarily from one stage to the
next. Two actuators forbid that, and each becomes a state of the OCP when its switch is on:

- **the front lateral force** (``PlannerConfig.steering_rate_limit``): the steering turns at a
  bounded rate, so the force's *rate* is the input (:mod:`mufusion.planner.front_force`);
- **the longitudinal forces** (``PlannerConfig.torque_lag``): the wheel torques follow their
  commands with a first-order lag of time constant τ (``VehicleParams.torque_time_constant_s``,
  0.15 s for the truck, longer than a stage). The states are the *realised* forces ``F_xf``,
  ``F_xr`` with ``dF/dt = (F_cmd − F) / τ``, the input's slots the *commands*. The tires, the
  friction polygons and the pitch load transfer see the realised forces (docs/decisions/0068:
  with the forces free, the plans alternated braking and driving from stage to stage, each
  stage counting on the load its own force shifts onto an axle, which no lagging torque
  delivers).

The backends take and return the planner's ``(N+1, 6)`` states and ``(N, 3)`` tire forces:
:func:`augmented_problem` and :func:`plan_from_augmented` translate at the boundary, so nothing
outside the backends sees the augmented layout. A plan's forces are the *realised* ones; the
tracking controller's lag compensation turns them into torque commands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mufusion.planner.ocp import (
    MIN_LOAD_SHARE,
    Param,
    PlannerConfig,
    longitudinal_force_bounds_n,
    polygon_directions,
)
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import N_STATES, Input, floored_axle_loads_n

INITIAL_FORCE_SHARE = 0.999
"""Share of the first stage's inscribed front radius the initial front forces are clipped to."""


@dataclass(frozen=True)
class OcpState:
    """Where the force states sit in the OCP's state (``None``: that force is an input)."""

    front_force: int | None
    """Index of ``F_yf`` (its rate is the input's ``Input.fyf`` slot)."""
    longitudinal: int | None
    """Index of the realised ``F_xf``; the realised ``F_xr`` follows it."""
    lag_s: float
    """The torques' time constant τ [s] (used only with ``longitudinal``)."""

    @property
    def nx(self) -> int:
        """Length of the OCP's state."""
        return N_STATES + (self.front_force is not None) + 2 * (self.longitudinal is not None)

    @property
    def augmented(self) -> bool:
        """Whether the OCP's state differs from the planner's."""
        return self.nx != N_STATES


def ocp_state(config: PlannerConfig, params: VehicleParams) -> OcpState:
    """The layout of the OCP's state for ``config`` and the vehicle's torque lag."""
    front = N_STATES if config.steering_rate_limit else None
    longitudinal = None
    if config.torque_lag:
        longitudinal = N_STATES + (front is not None)
    return OcpState(front, longitudinal, float(params.torque_time_constant_s))


def tire_forces(x: Any, u: Any, layout: OcpState) -> Any:
    """``(F_yf, F_xf, F_xr)`` the tires carry, of an OCP state and input (CasADi symbols)."""
    import casadi as ca

    if not layout.augmented:
        return u
    fyf = u[Input.fyf] if layout.front_force is None else x[layout.front_force]
    if layout.longitudinal is None:
        return ca.vertcat(fyf, u[Input.fxf], u[Input.fxr])
    i = layout.longitudinal
    return ca.vertcat(fyf, x[i], x[i + 1])


def cost_forces(x: Any, u: Any, layout: OcpState) -> Any:
    """The forces the tracking cost weighs (CasADi): the front force where it is a state (its
    rate is bounded only), the longitudinal *commands* (as the paper weighs its inputs)."""
    import casadi as ca

    if layout.front_force is None:
        return u
    return ca.vertcat(x[layout.front_force], u[Input.fxf], u[Input.fxr])


def force_rates(x: Any, u: Any, layout: OcpState) -> list[Any]:
    """Time derivatives of the force states, in the layout's order (CasADi symbols)."""
    rates: list[Any] = []
    if layout.front_force is not None:
        rates.append(u[Input.fyf])
    if layout.longitudinal is not None:
        i, tau = layout.longitudinal, layout.lag_s
        rates += [(u[Input.fxf] - x[i]) / tau, (u[Input.fxr] - x[i + 1]) / tau]
    return rates


def initial_forces(forces: np.ndarray, p0: np.ndarray, params: VehicleParams,
                   config: PlannerConfig, layout: OcpState) -> np.ndarray:
    """The first stage's forces ``(3,)`` where they are states, clipped into its front polygon.

    The first stage's force states are fixed and its front rows are hard: a force fixed outside
    (after μ̂ dropped) would leave the QP without a solution. With the front force alone a
    state, it is clipped to :data:`INITIAL_FORCE_SHARE` of the inscribed radius at the guess's
    loads (``F_xf = 0`` then satisfies the rows). With the longitudinal forces states too, the
    fixed pair ``(F_xf, F_yf)`` is scaled towards zero until it lies within that share of the
    inscribed radius at its own loads (with load transfer the radius follows the braking that
    remains, hence a few passes).
    """
    out = np.array(forces, dtype=float)
    _, ratio = polygon_directions(config.polygon_sides)
    if layout.longitudinal is None:
        if layout.front_force is not None:
            limit = INITIAL_FORCE_SHARE * ratio * float(p0[Param.radius_front])
            out[Input.fyf] = min(max(out[Input.fyf], -limit), limit)
        return out
    fixed = [Input.fxf] + ([Input.fyf] if layout.front_force is not None else [])
    floor = MIN_LOAD_SHARE * params.mass_kg * GRAVITY_MPS2
    for _ in range(8):
        if config.load_transfer:
            radius = float(p0[Param.utilized_friction_front]) * float(
                floored_axle_loads_n(out, params, floor)[0])
        else:
            radius = float(p0[Param.radius_front])
        limit = INITIAL_FORCE_SHARE * ratio * radius
        size = math.hypot(*(out[i] for i in fixed))
        if size <= limit:
            break
        for i in fixed:
            out[i] *= max(limit, 0.0) / size
    return out


def anchored_first_forces(
    first: np.ndarray, previous: np.ndarray | None, front_force_n: float | None,
    longitudinal_forces_n: tuple[float, float] | None, config: PlannerConfig,
) -> np.ndarray:
    """The first stage's forces ``(3,)`` of a guess, those that are states anchored to what the
    vehicle delivers now.

    Each force that is a state (``F_yf`` with the steering's rate limit, ``F_xf`` and ``F_xr``
    with the torque lag) is the measured one (``front_force_n``, ``longitudinal_forces_n``)
    where it is finite, else the previous plan's at this time (``previous``), else the guess's
    own (``first``). Started from the previous plan's front force instead of the measured one,
    the plans carried a turn-in the lagging steering had not delivered (docs/decisions/0050).
    """
    out = np.array(first, dtype=float)
    if config.steering_rate_limit:
        if front_force_n is not None and math.isfinite(front_force_n):
            out[Input.fyf] = float(front_force_n)
        elif previous is not None:
            out[Input.fyf] = previous[Input.fyf]
    if config.torque_lag:
        slots = [Input.fxf, Input.fxr]
        if longitudinal_forces_n is not None and all(map(math.isfinite, longitudinal_forces_n)):
            out[slots] = longitudinal_forces_n
        elif previous is not None:
            out[slots] = previous[slots]
    return out


def augmented_problem(
    x0: np.ndarray, guess_x: np.ndarray, guess_u: np.ndarray, p: np.ndarray,
    params: VehicleParams, config: PlannerConfig, layout: OcpState,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The OCP's initial state ``(nx,)``, state guess ``(N+1, nx)`` and input guess ``(N, 3)``.

    The force states start at the guess's first forces (the caller puts there the forces the
    tires deliver, or the previous plan's forces now: they cannot jump), clipped by
    :func:`initial_forces`. Stage k's force states are the guess's forces (the last held for
    the terminal stage); the inputs are those that reproduce them: the front force's difference
    quotient, and the longitudinal commands that a first-order lag turns into the next stage's
    forces (``u = (F_{k+1} − e F_k) / (1 − e)``, ``e = exp(−dt/τ)``, within the actuators).
    """
    n = guess_u.shape[0]
    dt_s = config.dt_s
    forces = np.empty((n + 1, 3))
    forces[:n] = guess_u
    forces[n] = guess_u[n - 1]
    forces[0] = initial_forces(forces[0], p[0], params, config, layout)
    xa = np.empty((n + 1, layout.nx))
    xa[:, :N_STATES] = guess_x
    ua = np.array(guess_u, dtype=float, copy=True)
    if layout.front_force is not None:
        xa[:, layout.front_force] = forces[:, Input.fyf]
        ua[:, Input.fyf] = np.diff(forces[:, Input.fyf]) / dt_s
    if layout.longitudinal is not None:
        i = layout.longitudinal
        xa[:, i:i + 2] = forces[:, [Input.fxf, Input.fxr]]
        e = math.exp(-dt_s / layout.lag_s)
        lower, upper = longitudinal_force_bounds_n(params)
        commands = (forces[1:, [Input.fxf, Input.fxr]] - e * forces[:-1, [Input.fxf, Input.fxr]])
        ua[:, [Input.fxf, Input.fxr]] = np.clip(commands / (1.0 - e), lower, upper)
    x0a = np.array(xa[0], copy=True)
    x0a[:N_STATES] = x0
    return x0a, xa, ua


def plan_from_augmented(xa: np.ndarray, ua: np.ndarray,
                        layout: OcpState) -> tuple[np.ndarray, np.ndarray]:
    """The planner's states ``(N+1, 6)`` and tire forces ``(N, 3)`` of an OCP solution.

    Stage k's forces that are states are their values at the stage's start: what stage k's
    polygons bound.
    """
    us = np.array(ua, dtype=float, copy=True)
    if layout.front_force is not None:
        us[:, Input.fyf] = xa[:-1, layout.front_force]
    if layout.longitudinal is not None:
        i = layout.longitudinal
        us[:, [Input.fxf, Input.fxr]] = xa[:-1, i:i + 2]
    return np.array(xa[:, :N_STATES]), us


def ocp_rear_force_limit(p: Any, forces: Any, params: VehicleParams,
                         config: PlannerConfig) -> Any:
    """The rear tire's friction ``μ̂ F_zr`` [N] of a stage (CasADi), where the plan's rear
    lateral force saturates (``PlannerConfig.rear_saturation``; ``None`` without it, the
    linear tire). ``μ̂`` is the stage's ``λ μ̂`` over ``λ``; ``F_zr`` the plan's own rear load
    with ``load_transfer`` (as the polygons take it), the guess's without."""
    if not config.rear_saturation:
        return None
    mu_hat = p[Param.utilized_friction] / config.utilization_factor
    if config.load_transfer:
        rear_load = floored_axle_loads_n(forces, params,
                                         MIN_LOAD_SHARE * params.mass_kg * GRAVITY_MPS2)[1]
    else:
        rear_load = p[Param.radius_rear] / p[Param.utilized_friction]
    return mu_hat * rear_load
