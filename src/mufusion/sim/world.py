"""The world as the closed loop sees it: the road, its true friction and obstacles, and the
vehicle's footprint in it.

The footprint is the vehicle's ``length × width`` rectangle centred midway between the axles
(cab-over trucks and cars have similar front and rear overhangs), aligned with its heading.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mufusion.road import Obstacle, Road, footprint_clearance_m, obstacle_active
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import N_STATES, State
from mufusion.vehicle.plant import PlantState, axle_positions


@dataclass(frozen=True)
class FootprintStatus:
    """Where the vehicle's footprint is, at one instant."""

    mu_front: float
    mu_rear: float
    obstacle_active: bool
    clearance_m: float
    in_collision: bool
    passed_obstacle: bool
    left_lane: bool
    in_opposing_lane: bool


@dataclass(frozen=True)
class World:
    """A road and the conversion of plant states into what the planner and metrics need.

    Parameters
    ----------
    road
        Reference path, lanes, true friction, obstacles.
    to_planner_obstacle
        Converts an active road obstacle into the planner's obstacle description.
    """

    road: Road
    to_planner_obstacle: Callable[[Obstacle], Any]

    @property
    def road_length_m(self) -> float:
        return self.road.length_m

    def curvature(self, s_m: np.ndarray) -> np.ndarray:
        """Reference-path curvature [1/m] at progress ``s_m``."""
        return self.road.curvature(s_m)

    def friction(self, s_m: np.ndarray) -> np.ndarray:
        """True friction along the ego-lane centre at progress ``s_m``."""
        return np.asarray(self.road.mu_at(s_m), dtype=float)

    def to_cartesian(self, s_m: np.ndarray, d_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, y, _ = self.road.to_cartesian(s_m, d_m)
        return x, y

    @staticmethod
    def pose(x_plant: np.ndarray) -> tuple[float, float, float]:
        """``(X, Y, ψ)`` of the centre of gravity."""
        return (
            float(x_plant[PlantState.X]),
            float(x_plant[PlantState.Y]),
            float(x_plant[PlantState.PSI]),
        )

    def frenet_state(self, x_plant: np.ndarray) -> np.ndarray:
        """The planner's state ``(s, d, Δψ, ψ̇, v_x, v_y)`` of a plant state."""
        s, d, dpsi = self.road.to_frenet(
            x_plant[PlantState.X], x_plant[PlantState.Y], x_plant[PlantState.PSI]
        )
        xf = np.empty(N_STATES)
        xf[State.s], xf[State.d], xf[State.dpsi] = float(s), float(d), float(dpsi)
        xf[State.psidot] = x_plant[PlantState.YAW_RATE]
        xf[State.vx] = x_plant[PlantState.VX]
        xf[State.vy] = x_plant[PlantState.VY]
        return xf

    def friction_under_axles(
        self, x_plant: np.ndarray, params: VehicleParams
    ) -> tuple[float, float]:
        """True friction under the front and the rear axle."""
        front, rear = axle_positions(x_plant, params)
        mu = self.road.mu_at_xy(
            np.array([front[0], rear[0]]), np.array([front[1], rear[1]])
        )
        return float(mu[0]), float(mu[1])

    def active_obstacles(self, t_s: float, s_ego_m: float) -> list[Obstacle]:
        return [o for o in self.road.obstacles if bool(obstacle_active(o, s_ego_m, t_s))]

    def planner_obstacles(
        self, t_s: float, s_ego_m: float, behind_m: float = float("inf")
    ) -> Sequence[Any]:
        """The active obstacles in the planner's description.

        Obstacles whose far end lies more than ``behind_m`` [m] behind ``s_ego_m`` are left out:
        once passed they no longer shape the plan (nor keep it in its evasive mode).
        """
        return [
            self.to_planner_obstacle(o)
            for o in self.active_obstacles(t_s, s_ego_m)
            if o.s_m + 0.5 * o.length_m >= s_ego_m - behind_m
        ]

    def footprint_status(
        self,
        pose: tuple[float, float, float],
        t_s: float,
        s_ego_m: float,
        params: VehicleParams,
    ) -> FootprintStatus:
        """Lane, opposing-lane and obstacle status of the footprint at ``pose``."""
        x, y, psi = pose
        shift = 0.5 * (params.cog_to_front_axle_m - params.cog_to_rear_axle_m)
        cx, cy = x + shift * np.cos(psi), y + shift * np.sin(psi)
        s_c, d_c, dpsi_c = self.road.to_frenet(cx, cy, psi)
        length, width = params.length_m, params.width_m
        active = self.active_obstacles(t_s, s_ego_m)
        clearance = np.inf
        passed = False
        for obstacle in active:
            c = float(footprint_clearance_m(obstacle, self.road.path, cx, cy, psi, length, width))
            clearance = min(clearance, c)
            passed |= float(s_c) - 0.5 * length > obstacle.s_m + 0.5 * obstacle.length_m
        mu_f, mu_r = self.friction_under_axles(
            np.array([x, y, psi] + [0.0] * (len(PlantState) - 3)), params
        )
        return FootprintStatus(
            mu_front=mu_f,
            mu_rear=mu_r,
            obstacle_active=bool(active),
            clearance_m=float(clearance) if np.isfinite(clearance) else float("nan"),
            in_collision=bool(clearance <= 0.0),
            passed_obstacle=bool(passed),
            left_lane=bool(self.road.left_ego_lane(s_c, d_c, dpsi_c, length, width)),
            in_opposing_lane=bool(
                self.road.entered_opposing_lane(s_c, d_c, dpsi_c, length, width)
            ),
        )
