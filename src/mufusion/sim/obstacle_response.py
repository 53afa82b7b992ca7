"""How the loop responds to an obstacle ahead: stop in lane where it can, else steer around it.

With ``brake_first`` (the product's default, off in the paper's method) the planner brakes to a
stop in front of an obstacle in the vehicle's path whenever the friction it may use allows it
(:func:`~mufusion.planner.passing.stopping_possible`) or when no side of the obstacle has room
(:func:`~mufusion.planner.passing.blocks_road`); it evades only when a stop is out of reach. A
swerve at the handling limit into the opposing lane carries risks the stop does not (oncoming
traffic, a corridor a few centimetres wide between the obstacle and the road's edge), and
braking also lowers the speed of any impact. Without ``brake_first`` the paper's behaviour: evade
whenever an obstacle is active.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.planner import PlannerConfig, PlannerObstacle
from mufusion.planner.passing import blocks_road, in_path, stopping_possible
from mufusion.sim.components import PlanningMode
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State


@dataclass(frozen=True)
class ObstacleResponse:
    """Settings of the stop-or-evade decision.

    Attributes
    ----------
    brake_first
        Stop in front of an obstacle in the path when possible (else the paper's evade).
    utilization_factor, polygon_sides
        The planner's λ and friction polygon (what it may brake with).
    margin_m
        Gap to keep to the obstacle [m] (the planner's obstacle margin).
    planning_period_s
        Time until a new plan acts [s]; added to the brakes' lag.
    """

    # Defaults are the planner's (one home: PlannerConfig); the runner passes the run's own.
    brake_first: bool = False
    utilization_factor: float = PlannerConfig.utilization_factor
    polygon_sides: int = PlannerConfig.polygon_sides
    margin_m: float = PlannerConfig.obstacle_margin_m
    planning_period_s: float = PlannerConfig.dt_s


def obstacle_mode(
    obstacles: Sequence[PlannerObstacle],
    xf: np.ndarray,
    estimate_s_m: np.ndarray,
    mu_hat: np.ndarray,
    lane_bounds_m: tuple[float, float],
    params: VehicleParams,
    response: ObstacleResponse,
    braking: bool = False,
) -> PlanningMode:
    """The planning mode for the obstacles ahead: ``cruise``, ``evade`` or ``emergency``.

    Parameters
    ----------
    obstacles
        Active obstacles (road coordinates).
    xf
        Frenet state of the vehicle (6,).
    estimate_s_m, mu_hat
        Distances ahead [m] and the friction estimate there [-].
    lane_bounds_m
        Bounds on the reference point's offset [m] (road or lane, already shrunk).
    params
        Vehicle parameters (footprint, brake lag).
    response
        Settings.
    braking
        The previous step chose the stop: the brakes are on already, so their lag no longer
        counts (without this, each step would add the lag again and a stop under way could flip
        to a swerve).

    Returns
    -------
    str
        ``cruise`` without obstacles, ``emergency`` if ``brake_first`` and an obstacle in the
        path can be stopped for or blocks the road, else ``evade``.
    """
    if not obstacles:
        return "cruise"
    if not response.brake_first:
        return "evade"
    s_ego, d_ego, speed = float(xf[State.s]), float(xf[State.d]), float(xf[State.vx])
    front = params.cog_to_body_front_m
    for ob in obstacles:
        clear = 0.5 * (ob.width_m + params.width_m) + response.margin_m
        ahead = ob.s_m - s_ego
        if not in_path(ob.s_m, ob.d_m, clear, s_ego, d_ego):
            continue  # beside or behind the vehicle, or not in its path
        if blocks_road(ob.d_m, clear, *lane_bounds_m):
            return "emergency"
        gap = ahead - front - 0.5 * ob.length_m - response.margin_m
        # The lowest estimate between the vehicle and the obstacle (held beyond the grid).
        mu = float(np.min(np.asarray(mu_hat)[np.asarray(estimate_s_m) <= max(ahead, 0.0)],
                          initial=float(np.asarray(mu_hat)[0])))
        if stopping_possible(
            speed_mps=speed, gap_m=gap, mu_hat=mu,
            utilization_factor=response.utilization_factor,
            polygon_sides=response.polygon_sides,
            dead_time_s=response.planning_period_s
            + (0.0 if braking else params.torque_time_constant_s),
        ):
            return "emergency"
    return "evade"
