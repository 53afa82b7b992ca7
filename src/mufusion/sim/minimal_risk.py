"""The minimal-risk manoeuvre when no plan can be trusted: brake in lane, steer along it.

Used by the loop once the planner has failed too often, or a component raised, and the planner
cannot plan the stop itself. Deliberately simple (no model, no optimisation): curvature
feed-forward plus lateral and heading feedback for steering; braking with what the friction
circle at a declared share of μ̂ g leaves after the lateral acceleration that following the lane
takes (``v² κ``), split over the axles by their static loads. The vehicle's slip control (ABS)
keeps the wheels rolling if μ̂ over-estimates the road.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import State


@dataclass(frozen=True)
class LaneKeepingGains:
    """Steering feedback of the manoeuvre (left positive, like the Frenet offset)."""

    lateral_rad_per_m: float = 0.05
    heading_rad_per_rad: float = 0.8


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
    steer = (
        params.wheelbase_m * curvature_1pm
        - g.lateral_rad_per_m * d
        - g.heading_rad_per_rad * dpsi
    )
    available = utilization * mu * GRAVITY_MPS2
    lateral = float(x[State.vx]) ** 2 * abs(curvature_1pm) if np.isfinite(x[State.vx]) else 0.0
    force = params.mass_kg * math.sqrt(max(available * available - lateral * lateral, 0.0))
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    r = params.wheel_radius_m
    return ActuatorCommand(
        float(steer), -share_front * force * r, -(1.0 - share_front) * force * r
    ).clipped(params)
