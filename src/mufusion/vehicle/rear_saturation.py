"""The planner's linear rear tire, saturated at the axle's friction (``PlannerConfig.
rear_saturation``, docs/decisions/0109).

The planner's rear lateral force follows the rear slip angle linearly
(:func:`~mufusion.vehicle.planner_model.rear_lateral_force_n`). A tire's force cannot pass its
friction ``μ F_z`` however far it slips; the linear tire's can, and a plan from a state whose
rear slides predicts it snapping back on many times what the road holds. These functions clip
it, for the plan's dynamics (:func:`saturated_rear_force_n`) and for the rear friction polygon
(:func:`rear_row_force_n`). Both work on numpy arrays and CasADi symbols.
"""

from __future__ import annotations

from typing import Any

import numpy as np

REAR_SATURATION_MIN_SPEED_MPS = 1.5
"""Below this speed the saturated rear tire stays linear [m/s] (:func:`saturated_rear_force_n`)."""
REAR_ROW_EXCESS_SHARE = 0.1
"""Share of the linear rear force's excess over the saturated one that the rear friction
polygon still prices (:func:`rear_row_force_n`)."""


def _symbolic(*values: Any) -> bool:
    return any(type(v).__module__.startswith("casadi") for v in values)


def rear_row_force_n(force_n: Any, vx_mps: Any, limit_n: Any) -> Any:
    """The rear lateral force the rear friction polygon prices with the saturated tire
    (``PlannerConfig.rear_saturation``): the saturated force (:func:`saturated_rear_force_n`)
    plus :data:`REAR_ROW_EXCESS_SHARE` of the linear force's excess over it, so that a plan still
    pays for slip beyond the tire's peak (it would otherwise drift at a bounded price) while
    the rear's braking or drive in a slide is weighed against the force the tire has.

    Examples
    --------
    >>> float(rear_row_force_n(13.0, 10.0, 3.0)) == 3.0 + REAR_ROW_EXCESS_SHARE * 10.0
    True
    """
    saturated = saturated_rear_force_n(force_n, vx_mps, limit_n)
    return saturated + REAR_ROW_EXCESS_SHARE * (force_n - saturated)


def saturated_rear_force_n(force_n: Any, vx_mps: Any, limit_n: Any) -> Any:
    """The linear rear tire's force ``force_n`` clipped to ``[−limit_n, limit_n]`` while the
    speed ``vx_mps`` exceeds :data:`REAR_SATURATION_MIN_SPEED_MPS` (numpy or CasADi).

    A tire's force cannot pass its friction ``μ F_z`` however far it slips; the linear tire's
    can, and a plan from a state whose rear slides predicts it snapping back on many times what
    the road holds. Within the limit the value is the linear one exactly (a min and a max, no
    smoothing). Below the speed the force stays linear: there the slip angle's floored speed
    makes it the strong damping that keeps the lateral motion of a plan's crawling last stages
    determined, and no slide worth predicting happens (docs/decisions/0109).

    Examples
    --------
    >>> [float(saturated_rear_force_n(f, 10.0, 3.0)) for f in (5.0, -5.0, 1.5)]
    [3.0, -3.0, 1.5]
    >>> float(saturated_rear_force_n(5.0, 1.0, 3.0))
    5.0
    """
    if _symbolic(force_n, vx_mps, limit_n):
        import casadi as ca

        clipped = ca.fmin(ca.fmax(force_n, -limit_n), limit_n)
        return ca.if_else(vx_mps > REAR_SATURATION_MIN_SPEED_MPS, clipped, force_n)
    clipped = np.minimum(np.maximum(force_n, -limit_n), limit_n)
    return np.where(np.asarray(vx_mps) > REAR_SATURATION_MIN_SPEED_MPS, clipped, force_n)
