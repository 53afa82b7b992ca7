"""The paper's turn and pop-up written as roads (examples/roads/paper/) are the same closed
loop as the built-in kinds: the same logs, array for array, and the same oracle verdict."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import classify_scenario, summary_fields
from mufusion.scenarios.runner import run_scenario
from mufusion.vehicle.params import vehicle_preset

PAPER = Path(__file__).resolve().parents[2] / "examples" / "roads" / "paper"
TABLES = ("timeseries", "planning_steps", "plans", "estimates")


@pytest.mark.parametrize("kind", ["turn", "popup"])
def test_the_road_file_runs_as_the_built_in_kind(kind: str) -> None:
    short = ["duration_s=3"]
    built_in = run_scenario(load_scenario(kind, short), "F")
    as_road = run_scenario(load_scenario(PAPER / f"{kind}.toml", short), "F")
    assert as_road.meta.scenario_name == "road"
    for table in TABLES:
        expected, actual = built_in.frame(table), as_road.frame(table)
        assert len(expected) > 0
        pd.testing.assert_frame_equal(actual, expected, check_exact=True, obj=table)
    assert as_road.meta.road == built_in.meta.road
    assert as_road.meta.obstacles == built_in.meta.obstacles
    assert as_road.meta.planner == built_in.meta.planner


@pytest.mark.parametrize("kind", ["turn", "popup"])
def test_the_oracle_gives_the_road_file_the_built_in_verdict(kind: str) -> None:
    built_in, as_road = load_scenario(kind), load_scenario(PAPER / f"{kind}.toml")
    params = vehicle_preset(built_in.vehicle)
    assert summary_fields(classify_scenario(as_road, params)) == summary_fields(
        classify_scenario(built_in, params))
