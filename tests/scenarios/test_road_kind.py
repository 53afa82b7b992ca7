"""The road kind: what it builds from its sections, and every bad description refused with the
key and the allowed range named (the CLI's exit 2 before any work)."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from mufusion.cli import app
from mufusion.road import PathSegment, ReferencePath
from mufusion.scenarios import RoadScenario, load_scenario, scenario_from_dict
from mufusion.scenarios.config import planner_lane_bounds_m
from mufusion.scenarios.road_kind import min_radius_m
from mufusion.vehicle.params import vehicle_preset

CAR = vehicle_preset("car")
TRUCK = vehicle_preset("truck")
ROAD: dict[str, Any] = {
    "name": "road", "vehicle": "car", "initial_speed_mps": 15.0, "duration_s": 5.0,
    "start_s_m": 30.0,
    "path": {"segments": [
        {"kind": "straight", "length_m": 60.0},
        {"kind": "arc", "radius_m": 50.0, "angle_rad": 1.0},
        {"kind": "straight", "length_m": 80.0},
    ]},
    "lanes": {"ego_width_m": 3.5, "opposing_width_m": 3.0, "drivable": "road"},
    "friction": {"mu": 0.9, "zones": [
        {"start_m": 70.0, "end_m": 90.0, "mu": 0.3, "mu_opposing": 0.6},
        {"start_m": 100.0, "mu": 0.5},
    ]},
    "obstacles": [{"s_m": 150.0, "d_m": 0.0, "appear_ahead_m": 25.0}],
}


def _loop_points() -> list[list[float]]:
    """Points every 2 m along a straight, three quarters of a 30 m circle and a straight that
    crosses the first one."""
    path = ReferencePath([PathSegment.straight(100.0), PathSegment.arc(30.0, 1.5 * math.pi),
                          PathSegment.straight(200.0)])
    x, y = path.position(np.arange(0.0, path.length_m, 2.0))
    return np.column_stack([x, y]).tolist()


LOOP_POINTS = _loop_points()


def _with(**changes: Any) -> dict[str, Any]:
    data = copy.deepcopy(ROAD)
    for dotted, value in changes.items():
        node = data
        *parents, last = dotted.split("__")
        for p in parents:
            node = node[int(p)] if isinstance(node, list) else node[p]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return data


def test_the_road_is_built_from_its_sections() -> None:
    cfg = scenario_from_dict(ROAD)
    assert isinstance(cfg, RoadScenario) and cfg.start_s_m == 30.0
    road = cfg.build_road(CAR)
    assert road.length_m == pytest.approx(140.0 + 50.0)
    assert road.lane_width_m == 3.5 and road.opposing_width_m == 3.0
    assert [float(road.mu_at(s)) for s in (50.0, 80.0, 95.0, 120.0, 500.0)] == [
        0.9, 0.3, 0.9, 0.5, 0.5]
    # Split μ: the opposing lane (left of d = 1.75) keeps 0.6 in the first zone only.
    assert float(road.mu_at(80.0, 2.0)) == 0.6 and float(road.mu_at(80.0, 1.7)) == 0.3
    assert float(road.mu_at(120.0, 2.0)) == 0.5
    assert cfg.drivable_d_m() == (-1.75, 4.75)
    lo, hi = planner_lane_bounds_m(cfg.model_copy(update={"lanes": cfg.lanes.model_copy(
        update={"drivable": "ego_lane"})}), CAR)
    assert lo == pytest.approx(-1.75 + 0.5 * CAR.width_m + 0.1) and hi == pytest.approx(-lo)


def test_appear_ahead_is_measured_from_the_front_as_the_popup_kind() -> None:
    """The obstacle pops up when the front is ``appear_ahead_m`` before its centre."""
    (obstacle,) = scenario_from_dict(ROAD).build_road(CAR).obstacles
    assert obstacle.appear_at_ego_s_m == pytest.approx(150.0 - 25.0 - CAR.cog_to_body_front_m)
    moving = _with(obstacles=[{"s_m": 150.0, "d_m": 3.0, "speed_mps": -12.0}])
    (oncoming,) = scenario_from_dict(moving).build_road(CAR).obstacles
    assert oncoming.speed_mps == -12.0 and oncoming.s_at_time(2.0) == 126.0


def test_a_polyline_path_is_smoothed_into_clothoids() -> None:
    points = [[float(x), 0.02 * x] for x in range(0, 200, 5)]
    cfg = scenario_from_dict(_with(path={"points_m": points, "smoothing_length_m": 5.0}))
    path = cfg.build_road(CAR).path
    assert path.length_m == pytest.approx(195.0 * math.hypot(1.0, 0.02), abs=0.05)
    assert path.start_heading_rad == pytest.approx(math.atan(0.02), abs=1e-3)


@pytest.mark.parametrize(
    ("changes", "fragment"),
    [
        ({"path__segments__0": {"kind": "straight", "length_m": 0.0}},
         "path.segments.0.straight.length_m: Input should be greater than 0"),
        ({"path__segments__1": {"kind": "arc", "radius_m": 50.0, "angle_rad": 0.0}},
         "angle_rad must not be 0"),
        ({"path__segments__1": {"kind": "arc", "radius_m": 1.0, "angle_rad": 1.0}},
         "path.segments.1: radius 1.00 m is below the smallest allowed"),
        # Three quarters of a circle to the left: the straight after it crosses the first one.
        ({"path": {"segments": [{"kind": "straight", "length_m": 100.0},
                                {"kind": "arc", "radius_m": 30.0, "angle_rad": 1.5 * math.pi},
                                {"kind": "straight", "length_m": 200.0}]}},
         "path crosses itself: s = 70.0 m and s = 271.4 m meet"),
        ({"path": {"points_m": LOOP_POINTS}}, "path crosses itself"),
        ({"path": {"points_m": [[0, 0], [10, 0], [10, 0], [30, 0]]}}, "coincide"),
        ({"path": {"segments": [{"kind": "straight", "length_m": 100.0}],
                   "points_m": [[0, 0], [1, 0], [2, 0], [3, 0]]}},
         "give exactly one of segments or points_m"),
        ({"vehicle": "truck", "lanes__ego_width_m": 2.7},
         "lanes.ego_width_m must be at least the truck's width plus the planner's footprint "
         "margin each side = 2.80 m, got 2.7"),
        ({"lanes__opposing_width_m": 1.0}, "opposing_width_m must be 0 (no opposing lane)"),
        ({"obstacles__0": {"s_m": 150.0, "d_m": 4.5}}, "obstacles.0: off the road"),
        ({"obstacles__0": {"s_m": 150.0, "d_m": -1.5}}, "obstacles.0: off the road"),
        ({"obstacles__0": {"s_m": 500.0}}, "obstacles.0.s_m must be on the path"),
        ({"friction__zones__1": {"start_m": 85.0, "end_m": 95.0, "mu": 0.5}},
         "zones.1.start_m must be at or after zones.0.end_m = 90.0"),
        ({"friction__zones__1": {"start_m": 100.0, "end_m": 400.0, "mu": 0.5}},
         "friction.zones.1.end_m must be within the path"),
        ({"friction__zones__0": {"start_m": 70.0, "end_m": 60.0, "mu": 0.5}},
         "end_m must exceed start_m"),
        ({"duration_s": 20.0}, "the run needs at least"),
        ({"start_s_m": 5.0}, "start_s_m: Input should be greater than or equal to 10"),
        ({"road": {"lane_width_m": 3.5}}, "road: Extra inputs are not permitted"),
    ],
)
def test_bad_road_descriptions_name_the_problem(changes, fragment) -> None:
    with pytest.raises(ValueError, match=None) as err:
        scenario_from_dict(_with(**changes), "test")
    assert fragment in str(err.value), str(err.value)


def test_a_one_way_road_has_no_split_friction() -> None:
    data = _with(lanes={"ego_width_m": 3.5, "opposing_width_m": 0.0})
    with pytest.raises(ValueError, match="mu_opposing needs an opposing lane"):
        scenario_from_dict(data)
    data["friction"]["zones"][0].pop("mu_opposing")
    data["obstacles"] = []
    road = scenario_from_dict(data).build_road(CAR)
    assert road.opposing_width_m == 0.0 and road.friction.mu_opposing is None


def test_the_smallest_radius_is_the_steering_or_the_inner_edge() -> None:
    steering = TRUCK.wheelbase_m / math.tan(TRUCK.max_steer_rad)
    assert min_radius_m(TRUCK, 1.75) == pytest.approx(steering)
    assert min_radius_m(TRUCK, 6.0) == 7.0 > steering
    # A left curve's inside is the opposing lane: 1.75 + 3 + 1 m.
    tight = _with(path__segments__1={"kind": "arc", "radius_m": 5.5, "angle_rad": 1.0})
    with pytest.raises(ValueError, match=r"below the smallest allowed 5\.75 m"):
        scenario_from_dict(tight)
    right = _with(path__segments__1={"kind": "arc", "radius_m": 5.5, "angle_rad": -1.0},
                  obstacles=[])
    assert scenario_from_dict(right).path.segments is not None


def test_the_cli_refuses_a_bad_road_with_exit_2(tmp_path: Path) -> None:
    file = tmp_path / "bad.toml"
    file.write_text(
        'name = "road"\nvehicle = "car"\nduration_s = 3.0\n'
        '[path]\nsegments = [{ kind = "straight", length_m = 200.0 }]\n'
        '[lanes]\nego_width_m = 1.5\n'
    )
    result = CliRunner().invoke(app, ["run", str(file), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    assert "lanes.ego_width_m" in " ".join(result.output.split())
    assert not (tmp_path / "out").exists()


def test_the_library_files_load() -> None:
    library = Path(__file__).resolve().parents[2] / "examples" / "roads"
    files = sorted(library.rglob("*.toml"))
    scenarios = [f for f in files if f.name != "library.toml"]
    assert len(scenarios) >= 7
    for file in scenarios:
        assert isinstance(load_scenario(file), RoadScenario), file
