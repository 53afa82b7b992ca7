"""How the loop responds to an obstacle ahead: stop in lane where it can, else steer around it.

With ``brake_first`` (the product's default, off in the paper's method) the planner brakes to a
stop in front of an obstacle in the vehicle's path whenever the friction it may use allows it
(:func:`~mufusion.planner.passing.stopping_possible`) or when no side of the obstacle has room
(:func:`~mufusion.planner.passing.blocks_road`); it evades only when a stop is out of reach. A
swerve at the handling limit into the opposing lane carries risks the stop does not (oncoming
traffic, a corridor a few centimetres wide between the obstacle and the road's edge), and
braking also lowers the speed of any impact. Without ``brake_first`` the paper's behaviour: evade
whenever an obstacle is active.

Moving obstacles (``speed_mps ≠ 0``, docs/decisions/0058) are traffic, judged by
:func:`traffic_role`: one outside the vehicle's path (an oncoming vehicle in the opposing lane) or
behind it does not count for the mode; one ahead in the path moving the same way is a lead
vehicle, followed (cruise, the speed capped by :func:`follow_speed_mps`) while its speed can
still be matched short of it, else a conflict like an oncoming vehicle in the path: evade where a
side has room, else brake (``emergency``), in both settings of ``brake_first`` (under constant
velocities a stop does not avoid a vehicle that keeps coming). Static obstacles are judged as
before, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from mufusion.planner import PlannerConfig, PlannerObstacle
from mufusion.planner.passing import blocks_road, in_path, stopping_possible
from mufusion.sim.components import PlanningMode
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
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
    follow_time_gap_s
        Time gap kept behind a lead vehicle [s], on top of the margin (the two-second rule's
        lower end; ACC systems offer 1–2.5 s).
    follow_braking_fraction
        Share of the planner's braking (``λ cos(π/n) μ̂ g``) the follow speed assumes, in
        (0, 1]: the rest is the reserve for a lead that brakes.
    """

    # Defaults are the planner's (one home: PlannerConfig); the runner passes the run's own.
    brake_first: bool = False
    utilization_factor: float = PlannerConfig.utilization_factor
    polygon_sides: int = PlannerConfig.polygon_sides
    margin_m: float = PlannerConfig.obstacle_margin_m
    planning_period_s: float = PlannerConfig.dt_s
    follow_time_gap_s: float = 1.5
    follow_braking_fraction: float = 0.5

    def __post_init__(self) -> None:
        if not (math.isfinite(self.follow_time_gap_s) and self.follow_time_gap_s >= 0.0):
            raise ValueError(
                f"follow_time_gap_s must be finite and >= 0 s, got {self.follow_time_gap_s!r}")
        if not 0.0 < self.follow_braking_fraction <= 1.0:
            raise ValueError("follow_braking_fraction must be in (0, 1], "
                             f"got {self.follow_braking_fraction!r}")


TrafficRole = Literal["clear", "lead", "conflict"]
"""What a moving obstacle is to the vehicle (:func:`traffic_role`)."""


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
    if any(ob.speed_mps != 0.0 for ob in obstacles):
        roles = [traffic_role(ob, xf, estimate_s_m, mu_hat, params, response, braking)
                 if ob.speed_mps != 0.0 else "static" for ob in obstacles]
        if "conflict" in roles:
            conflicts = [ob for ob, role in zip(obstacles, roles, strict=True)
                         if role == "conflict"]
            return "evade" if not any(
                blocks_road(ob.d_m, _clearance_m(ob, params, response), *lane_bounds_m)
                for ob in conflicts) else "emergency"
        obstacles = [ob for ob, role in zip(obstacles, roles, strict=True) if role == "static"]
    if not obstacles:
        return "cruise"
    if not response.brake_first:
        return "evade"
    s_ego, d_ego, speed = float(xf[State.s]), float(xf[State.d]), float(xf[State.vx])
    for ob in obstacles:
        clear = _clearance_m(ob, params, response)
        if not in_path(ob.s_m, ob.d_m, clear, s_ego, d_ego):
            continue  # beside or behind the vehicle, or not in its path
        if blocks_road(ob.d_m, clear, *lane_bounds_m):
            return "emergency"
        if _can_stop(speed, ob, s_ego, estimate_s_m, mu_hat, params, response, braking):
            return "emergency"
    return "evade"


def stop_within_reach(
    obstacles: Sequence[PlannerObstacle],
    xf: np.ndarray,
    estimate_s_m: np.ndarray,
    mu_hat: np.ndarray,
    params: VehicleParams,
    response: ObstacleResponse,
    braking: bool = False,
) -> bool:
    """Whether braking at what ``mu_hat`` grants stops short of every static obstacle in the
    vehicle's path (:func:`stopping_possible`, as :func:`obstacle_mode` judges a stop).

    :func:`obstacle_mode` also chooses the stop where no side of an obstacle has room, whatever
    ``mu_hat`` grants: this says whether that stop is within the estimate's reach. Moving
    obstacles are not judged here (true without a static one in the path).
    """
    s_ego, d_ego, speed = float(xf[State.s]), float(xf[State.d]), float(xf[State.vx])
    return all(
        _can_stop(speed, ob, s_ego, estimate_s_m, mu_hat, params, response, braking)
        for ob in obstacles
        if ob.speed_mps == 0.0 and in_path(ob.s_m, ob.d_m, _clearance_m(ob, params, response),
                                           s_ego, d_ego)
    )


def _clearance_m(ob: PlannerObstacle, params: VehicleParams, response: ObstacleResponse) -> float:
    """Lateral distance the reference point must keep from the obstacle's centre line [m]."""
    return 0.5 * (ob.width_m + params.width_m) + response.margin_m


def _lowest_mu(estimate_s_m: np.ndarray, mu_hat: np.ndarray, ahead_m: float) -> float:
    """The lowest estimate between the vehicle and ``ahead_m`` (held beyond the grid)."""
    mu = np.asarray(mu_hat, dtype=float)
    return float(np.min(mu[np.asarray(estimate_s_m) <= max(ahead_m, 0.0)], initial=float(mu[0])))


def _can_stop(
    speed_mps: float, ob: PlannerObstacle, s_ego_m: float, estimate_s_m: np.ndarray,
    mu_hat: np.ndarray, params: VehicleParams, response: ObstacleResponse, braking: bool,
) -> bool:
    """Whether ``speed_mps`` (the vehicle's, or its speed relative to a lead) is braked away
    short of the obstacle with the lowest estimate up to it (:func:`stopping_possible`)."""
    return stopping_possible(
        speed_mps=speed_mps, gap_m=_gap_m(ob, s_ego_m, params, response),
        mu_hat=_lowest_mu(estimate_s_m, mu_hat, ob.s_m - s_ego_m),
        utilization_factor=response.utilization_factor, polygon_sides=response.polygon_sides,
        dead_time_s=response.planning_period_s
        + (0.0 if braking else params.torque_time_constant_s),
    )


def _gap_m(ob: PlannerObstacle, s_ego_m: float, params: VehicleParams,
           response: ObstacleResponse) -> float:
    """From the vehicle's front to the obstacle's near face, less the margin [m]."""
    return (ob.s_m - s_ego_m - params.cog_to_body_front_m - 0.5 * ob.length_m
            - response.margin_m)


def traffic_role(
    ob: PlannerObstacle,
    xf: np.ndarray,
    estimate_s_m: np.ndarray,
    mu_hat: np.ndarray,
    params: VehicleParams,
    response: ObstacleResponse,
    braking: bool = False,
) -> TrafficRole:
    """What a moving obstacle is to the vehicle at state ``xf`` (docs/decisions/0058).

    ``clear``: outside the vehicle's path (:func:`~mufusion.planner.passing.in_path`: an oncoming
    vehicle in the opposing lane) or behind it; ``lead``: ahead in the path, moving the same way,
    and its speed can still be matched short of it braking at what the planner may use
    (:func:`~mufusion.planner.passing.stopping_possible` on the relative speed and the gap);
    ``conflict``: ahead in the path and oncoming, or a lead whose speed can no longer be matched.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> xf = np.array([0.0, 0.0, 0.0, 0.0, 20.0, 0.0]); grid = np.array([0.0]); mu = np.array([0.9])
    >>> oncoming = PlannerObstacle(60.0, 3.5, 4.5, 1.8, speed_mps=-15.0)
    >>> lead = PlannerObstacle(60.0, 0.0, 4.5, 1.8, speed_mps=10.0)
    >>> [traffic_role(o, xf, grid, mu, CAR, ObstacleResponse()) for o in (oncoming, lead)]
    ['clear', 'lead']
    >>> traffic_role(PlannerObstacle(60.0, 0.0, 4.5, 1.8, speed_mps=-15.0), xf, grid, mu, CAR,
    ...              ObstacleResponse())
    'conflict'
    """
    s_ego, d_ego = float(xf[State.s]), float(xf[State.d])
    if not in_path(ob.s_m, ob.d_m, _clearance_m(ob, params, response), s_ego, d_ego):
        return "clear"
    if ob.speed_mps < 0.0:
        return "conflict"
    relative = float(xf[State.vx]) - ob.speed_mps
    if relative <= 0.0 and _gap_m(ob, s_ego, params, response) > 0.0:
        return "lead"  # not closing in
    matched = _can_stop(relative, ob, s_ego, estimate_s_m, mu_hat, params, response, braking)
    return "lead" if matched else "conflict"


def follow_speed_mps(
    obstacles: Sequence[PlannerObstacle],
    xf: np.ndarray,
    estimate_s_m: np.ndarray,
    mu_hat: np.ndarray,
    params: VehicleParams,
    response: ObstacleResponse,
) -> float:
    """The highest speed [m/s] from which the vehicle matches every lead vehicle's speed in time.

    For a lead (moving the same way, ahead in the path) at speed ``v_o`` and gap ``g`` (front
    to its near face, less the margin and the time gap ``T v_o``), the speed from which braking
    at ``a = f λ cos(π/n) μ̂ g₀`` reaches ``v_o`` just as the gap closes:
    ``v = v_o + √(2 a g)``; closer than the time gap, ``max(0, v_o + g / T)`` (the gap opens
    again). ``inf`` without a lead (static and oncoming obstacles, traffic outside the path).

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> xf = np.array([0.0, 0.0, 0.0, 0.0, 20.0, 0.0])
    >>> lead = PlannerObstacle(100.0, 0.0, 4.5, 1.8, speed_mps=10.0)
    >>> # g = 100 − 2.12 − 2.25 − 0.5 − 1.5·10 = 80.13 m, a = 0.5·0.9·cos 15°·0.9·9.81 = 3.84:
    >>> v = follow_speed_mps([lead], xf, np.array([0.0]), np.array([0.9]), CAR, ObstacleResponse())
    >>> round(v, 1)  # 10 + √(2·3.84·80.13)
    34.8
    >>> follow_speed_mps([], xf, np.array([0.0]), np.array([0.9]), CAR, ObstacleResponse())
    inf
    """
    s_ego, d_ego = float(xf[State.s]), float(xf[State.d])
    cap = math.inf
    for ob in obstacles:
        if ob.speed_mps <= 0.0 or not in_path(
                ob.s_m, ob.d_m, _clearance_m(ob, params, response), s_ego, d_ego):
            continue
        gap = _gap_m(ob, s_ego, params, response) - response.follow_time_gap_s * ob.speed_mps
        mu = _lowest_mu(estimate_s_m, mu_hat, ob.s_m - s_ego)
        decel = (response.follow_braking_fraction * response.utilization_factor
                 * math.cos(math.pi / response.polygon_sides) * max(mu, 0.0) * GRAVITY_MPS2)
        if gap >= 0.0:
            speed = ob.speed_mps + math.sqrt(2.0 * decel * gap)
        else:
            speed = max(0.0, ob.speed_mps + gap / max(response.follow_time_gap_s, 1e-3))
        cap = min(cap, speed)
    return cap
