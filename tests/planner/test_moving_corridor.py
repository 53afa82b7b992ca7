"""The corridor and the sampling's violation place a moving obstacle at each stage's time."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.footprint import stage_violations_m
from mufusion.planner.ocp import PlannerObstacle, lateral_corridor
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_STATES, State

ROAD = (-0.35, 3.85)
MARGIN_M = 0.5
DT_S = 0.1
OB_LENGTH_M = 4.5
# Centres closer than this along s overlap (half the truck, half the obstacle, the margin).
REACH_M = 0.5 * TRUCK.length_m + 0.5 * OB_LENGTH_M + MARGIN_M


def _guess() -> np.ndarray:
    """Ten stages at 10 m/s from s = 0 on the lane centre: stage k at s = k m."""
    guess = np.zeros((11, N_STATES))
    guess[:, State.s] = np.arange(11, dtype=float)
    guess[:, State.vx] = 10.0
    return guess


def _closed(ob: PlannerObstacle, dt_s: float = DT_S) -> list[int]:
    """The stages (1-based) whose corridor the obstacle changes."""
    lo, hi = lateral_corridor(_guess(), [ob], *ROAD, TRUCK, MARGIN_M, dt_s=dt_s)
    free_lo, free_hi = lateral_corridor(_guess(), [], *ROAD, TRUCK, MARGIN_M)
    return [k + 1 for k in np.flatnonzero((lo != free_lo) | (hi != free_hi))]


def test_a_lead_at_the_vehicles_speed_never_closes_the_corridor() -> None:
    # 2 m beyond the reach and moving at the guess's 10 m/s: it stays 2 m beyond.
    lead = PlannerObstacle(REACH_M + 2.0, 0.0, OB_LENGTH_M, 1.8, speed_mps=10.0)
    assert _closed(lead) == []
    # The same obstacle at rest: stage k is at k m, within the reach beyond stage 2.
    assert _closed(PlannerObstacle(lead.s_m, 0.0, OB_LENGTH_M, 1.8)) == list(range(3, 11))


def test_an_oncoming_obstacle_closes_the_stages_where_it_will_be() -> None:
    # Closing at 20 m/s from reach + 10 m: within the reach after stage 5 (2 m per stage).
    oncoming = PlannerObstacle(REACH_M + 10.0, 0.0, OB_LENGTH_M, 1.8, speed_mps=-10.0)
    assert _closed(oncoming) == [6, 7, 8, 9, 10]
    # Placed where it is now (no stage time), the guess (1 m per stage) never reaches it.
    assert _closed(oncoming, dt_s=0.0) == []


def test_a_static_obstacle_gives_the_same_corridor_with_and_without_stage_times() -> None:
    static = PlannerObstacle(8.0, 0.3, OB_LENGTH_M, 1.8)
    with_dt = lateral_corridor(_guess(), [static], *ROAD, TRUCK, MARGIN_M, dt_s=DT_S)
    without = lateral_corridor(_guess(), [static], *ROAD, TRUCK, MARGIN_M)
    assert all(np.array_equal(a, b) for a, b in zip(with_dt, without, strict=True))


def test_sampling_scores_a_moving_obstacle_at_the_stage_times() -> None:
    states = _guess()[:, :, None]
    oncoming = PlannerObstacle(REACH_M + 10.0, 0.0, OB_LENGTH_M, 1.8, speed_mps=-10.0)
    clear = 0.5 * (1.8 + TRUCK.width_m) + MARGIN_M
    # Five overlapping stages on the obstacle's centre line, each short by the full clearance.
    road, overlap = stage_violations_m(states, [oncoming], *ROAD, TRUCK, MARGIN_M, DT_S)
    assert road.sum() == 0.0
    assert overlap.sum(axis=0).tolist() == pytest.approx([5 * clear])
    assert stage_violations_m(states, [oncoming], *ROAD, TRUCK, MARGIN_M)[1].sum() == 0.0
