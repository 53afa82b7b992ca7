from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.ocp import PlannerObstacle, lateral_corridor
from mufusion.planner.passing import (
    blocks_road,
    passing_left,
    stopping_distance_m,
    stopping_possible,
)
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_STATES, State

# The pop-up's road for the truck: reference point within −0.35 … 3.85 m; clearance 2.3 m.
ROAD = (-0.35, 3.85)
CLEAR = 0.5 * (1.0 + TRUCK.width_m) + 0.5


def test_the_guess_decides_when_both_sides_have_room() -> None:
    guess = np.array([-0.2, 0.0, 0.2])
    assert passing_left(guess, 0.1, 0.3, -5.0, 5.0).tolist() == [False, False, True]


def test_a_side_without_room_is_never_opened() -> None:
    # 1.5 m left of centre: right needs d ≤ −0.8 (road: −0.35), left d ≥ 3.8 (road: 3.85).
    assert passing_left(np.zeros(3), 1.5, CLEAR, *ROAD).all()
    # 1.5 m right of centre: left needs d ≥ 0.8, right d ≤ −3.8, off the road: left.
    assert passing_left(np.full(3, 2.0), -1.5, CLEAR, *ROAD).all()
    assert not blocks_road(1.5, CLEAR, *ROAD)
    assert blocks_road(1.6, CLEAR, *ROAD)  # left would need 3.9 m


def test_corridor_opens_the_side_with_room() -> None:
    guess = np.zeros((41, N_STATES))
    guess[:, State.s] = np.linspace(60.0, 100.0, 41)
    ob = PlannerObstacle(s_m=80.0, d_m=1.5, length_m=1.0, width_m=1.0)
    lo, hi = lateral_corridor(guess, [ob], *ROAD, TRUCK, 0.5)
    near = np.abs(guess[1:, State.s] - 80.0) < 0.5 * TRUCK.length_m + 1.0
    # Before the fix the guess (d = 0, right of the obstacle's centre) closed the left side and
    # left the corridor −0.35 … −0.8, empty.
    assert np.all(lo[near] == pytest.approx(1.5 + CLEAR))
    assert np.all(hi[near] == pytest.approx(ROAD[1]))


def test_a_heading_swing_does_not_close_the_side_the_road_leaves_room_on() -> None:
    # Obstacle 1.0 m left of centre: right needs d ≤ 1.0 − 2.3 = −1.3; a road to −1.4 leaves
    # 0.1 m. A guess yawed right (Δψ −0.05 rad) swings the front corners right by a_f sin Δψ,
    # about 0.13 m: the swung bounds left no room on the right, and the corridor opened the left,
    # 3.3 m across (docs/decisions/0073).
    road = (-1.4, 3.85)
    guess = np.zeros((41, N_STATES))
    guess[:, State.s] = np.linspace(60.0, 100.0, 41)
    guess[:, State.dpsi] = -0.05
    swing = TRUCK.cog_to_body_front_m * np.sin(0.05)
    assert road[0] + swing > 1.0 - CLEAR  # the swung bound would leave no room on the right
    ob = PlannerObstacle(s_m=80.0, d_m=1.0, length_m=1.0, width_m=1.0)
    lo, hi = lateral_corridor(guess, [ob], *road, TRUCK, 0.5)
    near = np.abs(guess[1:, State.s] - 80.0) < 0.5 * TRUCK.length_m + 1.0
    # Passing right, with less than the margin where the swung lower bound lies above the
    # obstacle's (both bounds are soft); the left side is never opened.
    assert np.all(hi[near] == pytest.approx(1.0 - CLEAR))
    assert np.all(lo[near] == pytest.approx(road[0] + swing))


def test_stopping_distance_and_decision() -> None:
    assert stopping_distance_m(10.0, 5.0, 0.2) == pytest.approx(2.0 + 10.0)
    kw = dict(utilization_factor=0.9, polygon_sides=12, dead_time_s=0.25)
    decel = 0.9 * np.cos(np.pi / 12) * 0.75 * 9.81
    need = 14.0 * 0.25 + 14.0**2 / (2.0 * decel)
    assert stopping_possible(speed_mps=14.0, gap_m=need + 0.01, mu_hat=0.75, **kw)
    assert not stopping_possible(speed_mps=14.0, gap_m=need - 0.01, mu_hat=0.75, **kw)
    assert not stopping_possible(speed_mps=14.0, gap_m=need, mu_hat=float("nan"), **kw)
    with pytest.raises(ValueError, match="decel_mps2"):
        stopping_distance_m(10.0, 0.0, 0.1)
