"""A planning step's result and why it may be a fallback."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np


class FallbackReason(str, Enum):
    """Why a planning step did not use a fresh solution (``NONE``: it did)."""

    NONE = "none"
    SOLVER_STATUS = "solver_status"  # the backend returned a status other than 0 or 2
    NON_FINITE = "non_finite"  # a "successful" solution with NaN or inf in it
    IMPLAUSIBLE = "implausible"  # finite, but outside the force, corridor or state limits
    EXCEPTION = "exception"  # the backend raised


@dataclass(frozen=True)
class Plan:
    """One planning step's result (stage k at time ``t0_s + k·dt``).

    ``states (N+1, 6)`` and ``inputs (N, 3)`` follow
    :class:`~mufusion.vehicle.planner_model.State` / :class:`~mufusion.vehicle.planner_model.Input`;
    the per-stage arrays ``(N,)`` are what the solve used: the (sanitised) friction estimate, the
    normal loads and the friction-polygon radii [N].

    ``ok`` is True when the solution passed the checks and is the plan; otherwise ``fallback`` is
    True, ``fallback_reason`` says why, and the plan is the previous one shifted (in mode
    ``minimal_risk``: the braking roll-out). ``consecutive_fallbacks`` counts this and the
    directly preceding fallback steps (0 after a good step). ``mu_sanitized_stages`` is the number
    of stages whose μ̂ was replaced or clipped (see :mod:`mufusion.planner.safeguards`).
    """

    t0_s: float
    states: np.ndarray
    inputs: np.ndarray
    rear_lateral_force_n: np.ndarray
    mu_hat: np.ndarray
    normal_load_front_n: np.ndarray
    normal_load_rear_n: np.ndarray
    force_limit_front_n: np.ndarray
    force_limit_rear_n: np.ndarray
    status: int
    ok: bool
    fallback: bool
    solve_time_s: float
    sampled_reinit: bool = False
    robust_qp_retry: bool = False
    """The fast QP failed and the solve was repeated in the robust mode (acados backend)."""
    dt_s: float = 0.1
    fallback_reason: FallbackReason = FallbackReason.NONE
    consecutive_fallbacks: int = 0
    mu_sanitized_stages: int = 0
    mode: str = "cruise"
    held: bool = False
    """A stop at rest held with the brakes on, not solved
    (:func:`~mufusion.planner.rti.held_plan`)."""


@dataclass(frozen=True)
class StageParameters:
    """One solve's per-stage parameters (arrays of length N) from the guess's ``s_k`` and forces:
    the OCP's ``p (N, N_PARAMS)`` and what the checks and the plan read. Loads and radii [N]
    (radii ``λ μ̂ F_z`` at the guess's loads), stiffness [N/rad], curvature [1/m]."""

    mu_hat: np.ndarray
    fzf_n: np.ndarray
    fzr_n: np.ndarray
    radius_front_n: np.ndarray
    radius_rear_n: np.ndarray
    utilized_friction: np.ndarray
    rear_stiffness_n_per_rad: np.ndarray
    curvature_1pm: np.ndarray
    p: np.ndarray
    # μ̂ where the front brake torque commanded at the stage's start lands (the front braking's
    # bound; the CoG's ``mu_hat`` without ``PlannerConfig.axle_friction``).
    mu_hat_front_brake: np.ndarray
    # The front braking's bound per stage [N] at that μ̂ (``inf`` where it is the stage's own).
    front_brake_limit_n: np.ndarray
    # The front polygon's μ̂: the lower of ``mu_hat`` (the CoG's) and the front axle's.
    mu_hat_front: np.ndarray
