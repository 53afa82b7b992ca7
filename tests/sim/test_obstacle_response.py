from __future__ import annotations

import numpy as np

from mufusion.planner.ocp import PlannerObstacle
from mufusion.sim.obstacle_response import ObstacleResponse, obstacle_mode
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_STATES, State

GRID = np.arange(0.0, 51.0)
ROAD = (-0.35, 3.85)


def state(speed: float, d: float = 0.0) -> np.ndarray:
    x = np.zeros(N_STATES)
    x[State.s], x[State.d], x[State.vx] = 60.0, d, speed
    return x


def mode(speed, ahead_m, mu, offset=0.0, brake_first=True, braking=False, d=0.0):
    front = 0.5 * TRUCK.length_m + 0.5 * (TRUCK.cog_to_front_axle_m - TRUCK.cog_to_rear_axle_m)
    ob = PlannerObstacle(s_m=60.0 + front + ahead_m, d_m=offset, length_m=1.0, width_m=1.0)
    return obstacle_mode([ob], state(speed, d), GRID, np.full(GRID.shape, mu), ROAD, TRUCK,
                         ObstacleResponse(brake_first=brake_first), braking=braking)


def test_stop_where_possible_else_evade() -> None:
    # 14 m/s, μ̂ 0.75: stop in 0.25·14 + 14²/(2·6.40) = 18.8 m of 35 − 0.5 − 0.5 = 34 m.
    assert mode(14.0, 35.0, 0.75) == "emergency"
    # 24 m/s: 6 + 45 m, more than there is: evade.
    assert mode(24.0, 35.0, 0.75) == "evade"
    # The paper's choice: evade whenever there is an obstacle.
    assert mode(14.0, 35.0, 0.75, brake_first=False) == "evade"
    assert obstacle_mode([], state(14.0), GRID, np.full(51, 0.75), ROAD, TRUCK,
                         ObstacleResponse(brake_first=True)) == "cruise"


def test_a_stop_under_way_is_not_charged_the_brake_lag_again() -> None:
    # A gap between the stop with the lag (0.25 s of dead time) and without it (0.1 s).
    decel = 0.9 * np.cos(np.pi / 12) * 0.5 * 9.81
    speed = 12.0
    gap = speed * 0.18 + speed**2 / (2 * decel)  # between the two dead times
    ahead = gap + 1.0
    assert mode(speed, ahead, 0.5) == "evade"
    assert mode(speed, ahead, 0.5, braking=True) == "emergency"


def test_obstacles_beside_the_path_or_blocking_the_road() -> None:
    # 3 m left of the vehicle: not in its path (clearance 2.3 m), nothing to stop for.
    assert mode(24.0, 20.0, 0.75, offset=3.0) == "evade"
    # Straddling so that neither side has room: stop, whatever the speed.
    assert mode(24.0, 20.0, 0.75, offset=1.6) == "emergency"
