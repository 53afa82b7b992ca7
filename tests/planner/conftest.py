"""Planner fixtures: the acados solver is generated/compiled once (disk cache keyed by hash)."""

from __future__ import annotations

import pytest

from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.vehicle.params import TRUCK

# Lane plus opposing lane: room to pass an obstacle in the lane centre.
TWO_LANES = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=3.95)


@pytest.fixture(scope="session")
def two_lane_planner() -> TractionAdaptivePlanner:
    return TractionAdaptivePlanner(TRUCK, TWO_LANES)


@pytest.fixture(scope="session")
def two_lane_planner_no_sampling() -> TractionAdaptivePlanner:
    return TractionAdaptivePlanner(
        TRUCK, PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=3.95, use_sampling=False)
    )
