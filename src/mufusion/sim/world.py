"""The world as the closed loop sees it: the road, its true friction and obstacles, and the
vehicle's footprint in it.

The footprint is the vehicle's ``length × width`` rectangle centred midway between the axles
(cab-over trucks and cars have similar front and rear overhangs), aligned with its heading.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mufusion.road import (
    FrictionTracker,
    Obstacle,
    PointTracker,
    ReferencePath,
    Road,
    footprint_lane_margins,
    obstacle_active_at,
    obstacle_corners,
    rectangle_corner_points,
    signed_clearance_points,
)
from mufusion.road.geometry import Point
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import N_STATES, State
from mufusion.vehicle.plant import PlantState
from mufusion.vehicle.plant_state import PlantStateVector


@dataclass(frozen=True)
class FootprintStatus:
    """Where the vehicle's footprint is, at one instant.

    Attributes
    ----------
    mu_front, mu_rear
        True friction under the front and the rear axle [-].
    obstacle_active
        Whether any obstacle is present.
    clearance_m
        Smallest signed clearance to an active obstacle [m] (NaN without one).
    in_collision
        Clearance ≤ 0.
    passed_obstacle
        The footprint's rear is past an active obstacle's far end.
    lane_margin_m
        Smallest signed distance of the footprint's corners to the ego lane's edges [m]:
        positive inside, negative by how far the deepest corner is outside
        (:func:`~mufusion.road.lanes.lane_margin_m`).
    lane_excursion_m
        ``max(0, −lane_margin_m)`` [m].
    opposing_depth_m
        How far the deepest corner lies left of the centre line [m], 0 if none.
    road_margin_m
        As ``lane_margin_m`` against the road's outer edges [m].
    left_lane, in_opposing_lane, off_road
        ``lane_margin_m < 0``, ``opposing_depth_m > 0``, ``road_margin_m < 0``.
    """

    mu_front: float
    mu_rear: float
    obstacle_active: bool
    clearance_m: float
    in_collision: bool
    passed_obstacle: bool
    left_lane: bool
    in_opposing_lane: bool
    lane_margin_m: float
    lane_excursion_m: float
    opposing_depth_m: float
    road_margin_m: float
    off_road: bool


@dataclass(frozen=True)
class _Trackers:
    """Warm starts of the projections of the vehicle's points that move with it (the axles'
    only for the friction under them)."""

    cog: PointTracker
    centre: PointTracker
    front_axle: FrictionTracker
    rear_axle: FrictionTracker
    corners: tuple[PointTracker, ...]


@dataclass(frozen=True)
class World:
    """A road and the conversion of plant states into what the planner and metrics need.

    The projections of the vehicle's points (centre of gravity, footprint centre and corners)
    start from where each point was projected last (one :class:`PointTracker` each); the axles
    are projected only when the friction under them could have changed
    (:class:`~mufusion.road.tracking.FrictionTracker`). That is the only state a world holds,
    and it does not change any result beyond rounding.

    Parameters
    ----------
    road
        Reference path, lanes, true friction, obstacles.
    to_planner_obstacle
        Converts an active road obstacle into the planner's obstacle description. It is given
        the obstacle as it is at the planning step's time (:func:`obstacle_now`: ``s_m`` where
        its centre is then, ``speed_mps`` its speed along the path).
    """

    road: Road
    to_planner_obstacle: Callable[[Obstacle], Any]
    _trackers: _Trackers = field(init=False, repr=False, compare=False)
    _obstacle_points: tuple[tuple[Point, ...], ...] = field(
        init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        path = self.road.path
        object.__setattr__(self, "_trackers", _Trackers(
            PointTracker(path), PointTracker(path),
            FrictionTracker(path, self.road.friction), FrictionTracker(path, self.road.friction),
            tuple(PointTracker(path) for _ in range(4)),
        ))
        # Static obstacles' corners once, as plain floats for the per-tick clearance (a moving
        # one's are placed at each tick: _points_at).
        object.__setattr__(self, "_obstacle_points", tuple(
            _corner_points(o, path, 0.0) for o in self.road.obstacles
        ))

    @property
    def road_length_m(self) -> float:
        return self.road.length_m

    def curvature(self, s_m: np.ndarray) -> np.ndarray:
        """Reference-path curvature [1/m] at progress ``s_m``."""
        return self.road.curvature(s_m)

    def curvature_at(self, s_m: float) -> float:
        """Reference-path curvature [1/m] at one progress [m] (plain float; once per tick)."""
        return self.road.path.curvature_at(s_m)

    def friction(self, s_m: np.ndarray) -> np.ndarray:
        """True friction along the ego-lane centre at progress ``s_m``."""
        return np.asarray(self.road.mu_at(s_m), dtype=float)

    def to_cartesian(self, s_m: np.ndarray, d_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, y, _ = self.road.to_cartesian(s_m, d_m)
        return x, y

    @staticmethod
    def pose(x_plant: np.ndarray | PlantStateVector) -> tuple[float, float, float]:
        """``(X, Y, ψ)`` of the centre of gravity (plant state as an array or named floats)."""
        return (
            float(x_plant[PlantState.X]),
            float(x_plant[PlantState.Y]),
            float(x_plant[PlantState.PSI]),
        )

    def frenet_state(self, x_plant: np.ndarray) -> np.ndarray:
        """The planner's state ``(s, d, Δψ, ψ̇, v_x, v_y)`` of a plant state."""
        s, d, dpsi = self._trackers.cog.to_frenet(*self.pose(x_plant))
        xf = np.empty(N_STATES)
        xf[State.s], xf[State.d], xf[State.dpsi] = s, d, dpsi
        xf[State.psidot] = x_plant[PlantState.YAW_RATE]
        xf[State.vx] = x_plant[PlantState.VX]
        xf[State.vy] = x_plant[PlantState.VY]
        return xf

    def friction_under_axles(
        self, x_plant: np.ndarray | PlantStateVector, params: VehicleParams
    ) -> tuple[float, float]:
        """True friction under the front and the rear axle (state as an array or named floats)."""
        return self._mu_under_axles(self.pose(x_plant), params)

    def _mu_under_axles(
        self, pose: tuple[float, float, float], params: VehicleParams
    ) -> tuple[float, float]:
        # The axle centres as in vehicle.plant.axle_positions, in plain floats.
        x, y, psi = pose
        c, s = math.cos(psi), math.sin(psi)
        front_x, front_y = x + params.cog_to_front_axle_m * c, y + params.cog_to_front_axle_m * s
        rear_x, rear_y = x - params.cog_to_rear_axle_m * c, y - params.cog_to_rear_axle_m * s
        return (self._trackers.front_axle.mu_at(front_x, front_y),
                self._trackers.rear_axle.mu_at(rear_x, rear_y))

    def active_obstacles(self, t_s: float, s_ego_m: float) -> list[Obstacle]:
        """The obstacles present at ``t_s`` [s] for ego progress ``s_ego_m`` [m] (as given: a
        moving one's ``s_m`` is its progress at time 0)."""
        return [o for o in self.road.obstacles if obstacle_active_at(o, s_ego_m, t_s)]

    def planner_obstacles(
        self, t_s: float, s_ego_m: float, behind_m: float = float("inf")
    ) -> Sequence[Any]:
        """The active obstacles in the planner's description, where they are at ``t_s`` [s].

        Obstacles whose far end lies more than ``behind_m`` [m] behind ``s_ego_m`` are left out:
        once passed they no longer shape the plan (nor keep it in its evasive mode).
        """
        now = (obstacle_now(o, t_s) for o in self.active_obstacles(t_s, s_ego_m))
        return [
            self.to_planner_obstacle(o) for o in now
            if o.s_m + 0.5 * o.length_m >= s_ego_m - behind_m
        ]

    def _points_at(self, index: int, obstacle: Obstacle, t_s: float) -> tuple[Point, ...]:
        """The corners of obstacle ``index`` at ``t_s`` [s] as plain floats."""
        if not obstacle.moving:
            return self._obstacle_points[index]
        return _corner_points(obstacle, self.road.path, t_s)

    def footprint_status(
        self,
        pose: tuple[float, float, float],
        t_s: float,
        s_ego_m: float,
        params: VehicleParams,
    ) -> FootprintStatus:
        """Lane, road, opposing-lane and obstacle status of the footprint at ``pose``.

        The footprint is the ``length × width`` rectangle centred midway between the axles; the
        lane quantities come from the Frenet offsets of its four corners.
        """
        x, y, psi = pose
        shift = params.body_centre_ahead_of_cog_m
        cx, cy = x + shift * math.cos(psi), y + shift * math.sin(psi)
        length, width, lane_width = params.length_m, params.width_m, self.road.lane_width_m
        corners = rectangle_corner_points(cx, cy, psi, length, width)
        corner_d = [
            tracker.to_frenet(px, py)[1]
            for tracker, (px, py) in zip(self._trackers.corners, corners, strict=True)
        ]
        clearance = math.inf
        passed = False
        any_active = False
        s_c: float | None = None
        for index, obstacle in enumerate(self.road.obstacles):
            if not obstacle_active_at(obstacle, s_ego_m, t_s):
                continue
            any_active = True
            points = self._points_at(index, obstacle, t_s)
            clearance = min(clearance, signed_clearance_points(corners, points))
            if s_c is None:  # the footprint's progress matters only next to an obstacle
                s_c = self._trackers.centre.to_frenet(cx, cy, psi)[0]
            passed |= s_c - 0.5 * length > obstacle.s_at_time(t_s) + 0.5 * obstacle.length_m
        mu_f, mu_r = self._mu_under_axles(pose, params)
        lanes = footprint_lane_margins(corner_d, lane_width, self.road.opposing_lane_width_m)
        return FootprintStatus(
            mu_front=mu_f,
            mu_rear=mu_r,
            obstacle_active=any_active,
            clearance_m=clearance if math.isfinite(clearance) else float("nan"),
            in_collision=clearance <= 0.0,
            passed_obstacle=passed,
            left_lane=lanes.left_lane,
            in_opposing_lane=lanes.in_opposing_lane,
            lane_margin_m=lanes.lane_margin_m,
            lane_excursion_m=lanes.lane_excursion_m,
            opposing_depth_m=lanes.opposing_depth_m,
            road_margin_m=lanes.road_margin_m,
            off_road=lanes.off_road,
        )


def obstacle_now(obstacle: Obstacle, time_s: float) -> Obstacle:
    """``obstacle`` as it is at ``time_s`` [s]: its ``s_m`` the centre's progress then.

    A static obstacle comes back unchanged (the same object).

    Examples
    --------
    >>> obstacle_now(Obstacle(100.0, 3.5, speed_mps=-10.0), 2.0).s_m
    80.0
    """
    if not obstacle.moving:
        return obstacle
    return dataclasses.replace(obstacle, s_m=obstacle.s_at_time(time_s))


def _corner_points(obstacle: Obstacle, path: ReferencePath, time_s: float) -> tuple[Point, ...]:
    return tuple((float(x), float(y)) for x, y in obstacle_corners(obstacle, path, time_s).tolist())
