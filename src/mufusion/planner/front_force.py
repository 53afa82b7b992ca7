"""The front lateral force as an OCP state whose rate the steering bounds (beyond the paper).

The planner plans tire forces (TAMP). A force input may jump from one stage to the next, which a
steering actuator cannot follow: at the truck's limit the plans reverse the front force between
the polygon's bounds from one stage to the next (+38, +38, +12, −38, −38 kN on a straight at
11 m/s), the next plan starts from a state the last one did not predict, and the loop weaves
(docs/decisions/0011, "Tracking at the limit"). With ``PlannerConfig.steering_rate_limit`` the
OCP's state is the planner's six states plus ``F_yf``, and the input's ``Input.fyf`` slot is that
force's rate, bounded by :func:`~mufusion.vehicle.planner_model.front_force_rate_limit_n_per_s`.
The backends take and return the planner's ``(N+1, 6)`` states and ``(N, 3)`` tire forces:
:func:`augmented_problem` and :func:`plan_from_augmented` translate at the boundary, so nothing
outside the backends sees the augmented layout.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mufusion.planner.ocp import Param, PlannerConfig, polygon_directions
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import N_STATES, Input, front_force_rate_limit_n_per_s

FRONT_FORCE = N_STATES
"""Index of ``F_yf`` in the augmented OCP state (after the planner's six states)."""

INITIAL_FORCE_SHARE = 0.999
"""Share of the first stage's inscribed front radius the initial force state is clipped to."""


def ocp_state_count(config: PlannerConfig) -> int:
    """Length of the OCP's state: 6, or 7 with the steering's rate limit."""
    return N_STATES + 1 if config.steering_rate_limit else N_STATES


def front_force_rate_bound_n_per_s(params: VehicleParams, config: PlannerConfig) -> float:
    """Bound on ``|dF_yf/dt|`` in the plans [N/s] (the secant stiffness at the utilisation)."""
    return front_force_rate_limit_n_per_s(params, config.utilization_factor)


def tire_forces(x: Any, u: Any) -> Any:
    """``(F_yf, F_xf, F_xr)`` of an augmented OCP state and input (CasADi symbols)."""
    import casadi as ca

    return ca.vertcat(x[FRONT_FORCE], u[Input.fxf], u[Input.fxr])


def augmented_problem(
    x0: np.ndarray, guess_x: np.ndarray, guess_u: np.ndarray, p: np.ndarray, n_sides: int,
    dt_s: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The augmented initial state ``(7,)``, state guess ``(N+1, 7)`` and input guess ``(N, 3)``.

    The force state starts at the guess's first front force (the caller puts there the force the
    tires deliver, or the previous plan's command now: the force cannot jump), clipped into the
    first stage's inscribed front radius. That row is hard and a force state fixed outside it,
    e.g. after μ̂ dropped, would leave the QP without a solution; inside it, ``F_xf = 0``
    satisfies it. Stage k's force is the guess's (the last one held for the terminal stage) and
    the rate input is the difference quotient, so a guess that respects the bound stays consistent.
    """
    n = guess_u.shape[0]
    _, ratio = polygon_directions(n_sides)
    limit = INITIAL_FORCE_SHARE * ratio * float(p[0, Param.radius_front])
    force = np.empty(n + 1)
    force[:n] = guess_u[:, Input.fyf]
    force[n] = guess_u[n - 1, Input.fyf]
    force[0] = min(max(force[0], -limit), limit)
    xa = np.empty((n + 1, N_STATES + 1))
    xa[:, :N_STATES] = guess_x
    xa[:, FRONT_FORCE] = force
    ua = np.array(guess_u, dtype=float, copy=True)
    ua[:, Input.fyf] = np.diff(force) / dt_s
    x0a = np.empty(N_STATES + 1)
    x0a[:N_STATES] = x0
    x0a[FRONT_FORCE] = force[0]
    return x0a, xa, ua


def plan_from_augmented(xa: np.ndarray, ua: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The planner's states ``(N+1, 6)`` and tire forces ``(N, 3)`` of an augmented solution.

    Stage k's front force is the force state at its start: the value stage k's polygon bounds.
    """
    us = np.array(ua, dtype=float, copy=True)
    us[:, Input.fyf] = xa[:-1, FRONT_FORCE]
    return np.array(xa[:, :N_STATES]), us
