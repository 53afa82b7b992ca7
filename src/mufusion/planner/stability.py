"""The stability envelope: per-stage bounds on the planned yaw rate and body slip from μ̂.

Issue 38, mechanism B (``PlannerConfig.stability_envelope``, both backends). A yaw rate above
what the lateral friction sustains at the speed, ``|ψ̇| ≤ μ g / v`` (a steady turn at the
friction limit), or a body slip above ``tan β_max = 0.02 μ g`` runs the rear axle at its limit;
production yaw-stability control bounds its references by the same two expressions (Rajamani,
*Vehicle Dynamics and Control*, 2nd ed., §8.5). The planner states them as soft boxes on the
ψ̇ and v_y states at the guess's speed (docs/decisions/0065).
"""

from __future__ import annotations

import numpy as np

from mufusion.planner.config import PlannerConfig
from mufusion.planner.ocp import MAX_SPEED_MPS, Param
from mufusion.vehicle.params import GRAVITY_MPS2
from mufusion.vehicle.planner_model import State

YAW_RATE_MARGIN = 1.1
"""Headroom above ``μ̂ g / v``: the bound keeps the plans off the rear's limit, not off a turn
the polygons allow."""
BODY_SLIP_GAIN_PER_MPS2 = 0.02
"""``tan β_max`` per m/s² of the friction's acceleration ``μ̂ g`` (Rajamani §8.5)."""
MIN_ENVELOPE_SPEED_MPS = 1.0
"""Speeds below this take this one: the yaw-rate bound grows without limit towards rest."""


def _floored_speed_mps(speed_mps: np.ndarray) -> np.ndarray:
    return np.maximum(np.asarray(speed_mps, dtype=float), MIN_ENVELOPE_SPEED_MPS)


def _friction_accel_mps2(mu_hat: np.ndarray) -> np.ndarray:
    return np.asarray(mu_hat, dtype=float) * GRAVITY_MPS2


def yaw_rate_bound_rps(mu_hat: np.ndarray, speed_mps: np.ndarray) -> np.ndarray:
    """``YAW_RATE_MARGIN μ̂ g / max(v, MIN_ENVELOPE_SPEED_MPS)`` per stage [rad/s, > 0].

    Examples
    --------
    >>> round(float(yaw_rate_bound_rps(np.array([0.3]), np.array([19.0]))[0]), 4)
    0.1704
    """
    return YAW_RATE_MARGIN * _friction_accel_mps2(mu_hat) / _floored_speed_mps(speed_mps)


def body_slip_speed_bound_mps(mu_hat: np.ndarray, speed_mps: np.ndarray) -> np.ndarray:
    """``|v_y| ≤ tan(β_max) max(v, MIN_ENVELOPE_SPEED_MPS)``, ``tan β_max = 0.02 μ̂ g`` [m/s].

    Examples
    --------
    >>> round(float(body_slip_speed_bound_mps(np.array([0.9]), np.array([16.0]))[0]), 3)
    2.825
    """
    return BODY_SLIP_GAIN_PER_MPS2 * _friction_accel_mps2(mu_hat) * _floored_speed_mps(speed_mps)


def state_bounds(
    d_lo: np.ndarray,
    d_hi: np.ndarray,
    min_speed_mps: float,
    guess_x: np.ndarray,
    p: np.ndarray,
    config: PlannerConfig,
    max_speed_mps: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The state boxes of stages 1 … N, ``(lower, upper)`` each ``(N, m)``: ``d`` within the
    corridor ``[d_lo, d_hi]``, ``v_x`` within ``[min_speed_mps, MAX_SPEED_MPS]`` (the upper
    bound lowered to ``max_speed_mps`` ``(N,)``, the speed ceiling, where given), and with
    ``config.stability_envelope`` (``m = 4``) ``|ψ̇|`` and ``|v_y|`` within the bounds above at
    each stage's μ̂ (``p``'s λ μ̂ over λ; the terminal stage takes the last stage's parameters)
    and the guess's speed ``guess_x[1:]``."""
    n = config.horizon_steps
    lower, upper = np.empty((n, 4)), np.empty((n, 4))
    lower[:, 0], lower[:, 1], upper[:, 0], upper[:, 1] = d_lo, min_speed_mps, d_hi, MAX_SPEED_MPS
    if max_speed_mps is not None:
        upper[:, 1] = np.minimum(MAX_SPEED_MPS, max_speed_mps)
    if not config.stability_envelope:
        return lower[:, :2], upper[:, :2]
    mu_hat = p[np.minimum(np.arange(1, n + 1), n - 1), Param.utilized_friction]
    mu_hat = mu_hat / config.utilization_factor
    speed = guess_x[1:, State.vx]
    upper[:, 2] = yaw_rate_bound_rps(mu_hat, speed)
    upper[:, 3] = body_slip_speed_bound_mps(mu_hat, speed)
    lower[:, 2:] = -upper[:, 2:]
    return lower, upper
