"""The CommonRoad importer on the shipped scenario files: geometry checked against the lanelets.

Runs where the ``commonroad`` extra is installed (CI installs it); every reference value comes
from the file's own lanelets and obstacle states, never from the importer's output.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

pytest.importorskip("commonroad")
pytest.importorskip("commonroad_clcs")
pytest.importorskip("commonroad_route_planner")

from mufusion.road.commonroad import (  # after the skips
    ImportedRoad,
    RunChoice,
    import_road,
    polyline_curvature_1pm,
    read_commonroad,
    road_scenario_toml,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "commonroad"
GUETERSLOH = DATA / "DEU_Guetersloh-36_1_T-1.xml"
LOOP = [84591, 85155, 84600, 85215, 84603, 85225, 84606, 85230]


@pytest.fixture(scope="module")
def guetersloh():
    return read_commonroad(GUETERSLOH)


@pytest.fixture(scope="module")
def loop(guetersloh) -> ImportedRoad:
    return import_road(guetersloh, lanelet_ids=LOOP, length_m=257.0)


@pytest.fixture(scope="module")
def problem_route(guetersloh) -> ImportedRoad:
    return import_road(guetersloh, problem_id=1)


def _raw_centre(file, ids) -> np.ndarray:
    network = file.scenario.lanelet_network
    centre = np.vstack([network.find_lanelet_by_id(i).center_vertices for i in ids])
    return centre[np.r_[True, np.hypot(*np.diff(centre, axis=0).T) > 1e-6]]  # seams repeat


def test_bend_radius_is_the_lanelets_radius(guetersloh, loop: ImportedRoad) -> None:
    kappa = np.abs(polyline_curvature_1pm(loop.points_m))
    bend = loop.points_m[int(np.argmax(kappa)) + 1] + np.asarray(loop.origin_m)
    centre = _raw_centre(guetersloh, LOOP)
    # The file's own centre line over the bend: the tightest circle through three consecutive
    # vertices within 10 m of it (vertices 1.3–2.6 m apart there).
    near = centre[np.hypot(*(centre - bend).T) < 10.0]
    assert len(near) >= 5
    raw_radius = 1.0 / float(np.max(np.abs(polyline_curvature_1pm(near))))
    assert loop.smallest_radius_m == pytest.approx(raw_radius, rel=0.1)
    # One-vertex kinks of the subdivision are sharper, but not by much.
    assert 0.8 * raw_radius < loop.smallest_vertex_radius_m <= loop.smallest_radius_m


def _lanelet_widths(file, ids) -> np.ndarray:
    network = file.scenario.lanelet_network
    return np.concatenate([
        np.hypot(*(la.left_vertices - la.right_vertices).T)
        for la in (network.find_lanelet_by_id(i) for i in ids)
    ])


@pytest.mark.parametrize("which", ["loop", "problem_route"])
def test_lane_widths_positive_and_within_the_lanelets(which, request, guetersloh) -> None:
    road: ImportedRoad = request.getfixturevalue(which)
    widths = _lanelet_widths(guetersloh, road.lanelet_ids)
    lanes = road.lanes
    assert 0.0 < lanes.ego_width_m <= widths.min() + 0.02
    # The path stays near the lane's middle: the symmetric lane keeps most of the real one.
    assert lanes.ego_width_m > 0.8 * widths.min()
    # At every s the two distances add up to the lanelet's width there (a few cm of slant).
    total = lanes.left_m + lanes.right_m
    assert total.min() > widths.min() - 0.1 and total.max() < widths.max() + 0.1
    network = guetersloh.scenario.lanelet_network
    opposite = [network.find_lanelet_by_id(network.find_lanelet_by_id(i).adj_left)
                for i in road.lanelet_ids
                if network.find_lanelet_by_id(i).adj_left_same_direction is False]
    assert opposite, "Guetersloh's route has oncoming lanelets beside it"
    widest = max(np.hypot(*(la.left_vertices - la.right_vertices).T).max() for la in opposite)
    assert 0.0 < lanes.opposing_width_m <= widest + 0.02


def test_obstacles_sit_where_the_file_puts_them(guetersloh, problem_route: ImportedRoad) -> None:
    assert problem_route.obstacles, "the planning problem's route has oncoming cars"
    points = problem_route.points_m + np.asarray(problem_route.origin_m)
    s = problem_route.s_m
    tangent = np.gradient(points, s, axis=0)
    tangent /= np.hypot(*tangent.T)[:, None]
    for o in problem_route.obstacles:
        state = guetersloh.scenario.obstacle_by_id(o.obstacle_id).state_at_time(0)
        on_path = np.array([np.interp(o.s_m, s, points[:, 0]), np.interp(o.s_m, s, points[:, 1])])
        t = np.array([np.interp(o.s_m, s, tangent[:, 0]), np.interp(o.s_m, s, tangent[:, 1])])
        normal = np.array([-t[1], t[0]]) / np.hypot(*t)
        # (s, d) mapped back through the written path lands on the file's position.
        assert np.hypot(*(on_path + o.d_m * normal - state.position)) < 0.15
        heading = math.atan2(t[1], t[0])
        assert o.speed_mps == pytest.approx(
            state.velocity * math.cos(state.orientation - heading), abs=0.05)
        assert o.speed_mps < 0.0 and o.d_m > 0.5 * problem_route.lanes.ego_width_m  # oncoming


@pytest.mark.parametrize(
    ("name", "chain", "length_m"),
    [("DEU_A9-3_1_T-1.xml", [3990], 300.0), ("DEU_Starnberg-1_1_T-1.xml", [50, 120, 24, 92, 2],
                                              289.0)],
)
def test_a9_ramp_and_starnberg_bends_under_60_m(name: str, chain: list[int],
                                                length_m: float) -> None:
    file = read_commonroad(DATA / name)
    road = import_road(file, lanelet_ids=chain, length_m=length_m)
    assert 20.0 < road.smallest_radius_m < 60.0
    assert road.length_m == pytest.approx(length_m, abs=1.0)
    assert np.allclose(np.diff(road.s_m)[:-1], 1.0)
    # The bend as the lanelets draw it (their centre line, consecutive vertices), within 10 %.
    centre = _raw_centre(file, road.lanelet_ids)
    raw = 1.0 / float(np.max(np.abs(polyline_curvature_1pm(centre))))
    assert road.smallest_radius_m == pytest.approx(raw, rel=0.1)
    if name.startswith("DEU_A9"):
        assert road.lanes.opposing_width_m == 0.0  # a one-way ramp


SCHEMA_TOP = {"name", "description", "vehicle", "initial_speed_mps", "duration_s", "seed",
              "start_s_m", "path", "lanes", "friction"}
OBSTACLE_KEYS = {"s_m", "d_m", "length_m", "width_m", "speed_mps"}


def _written(road: ImportedRoad, tmp_path: Path) -> Path:
    run = RunChoice(start_s_m=10.0, initial_speed_mps=8.0, duration_s=5.0)
    out = tmp_path / "road.toml"
    out.write_text(road_scenario_toml(road, run, vehicle="car", mu=0.5, mu_source="test"))
    return out


def test_written_toml_has_the_road_schema_keys(problem_route: ImportedRoad,
                                               tmp_path: Path) -> None:
    data = tomllib.loads(_written(problem_route, tmp_path).read_text())
    assert set(data) - {"obstacles"} == SCHEMA_TOP
    assert data["name"] == "road"
    points = np.asarray(data["path"]["points_m"])
    assert points.shape == problem_route.points_m.shape and set(data["path"]) == {"points_m"}
    assert np.allclose(points, problem_route.points_m, atol=1e-4)
    assert set(data["lanes"]) == {"ego_width_m", "opposing_width_m", "drivable"}
    assert data["lanes"]["ego_width_m"] == pytest.approx(problem_route.lanes.ego_width_m,
                                                         abs=1e-3)
    assert data["friction"] == {"mu": 0.5}
    assert len(data["obstacles"]) == len(problem_route.obstacles)
    assert all(set(o) == OBSTACLE_KEYS for o in data["obstacles"])


def test_imported_toml_loads_as_road_scenario(problem_route: ImportedRoad,
                                              tmp_path: Path) -> None:
    """Fails until the `road` scenario kind (branch roads-kind) is merged."""
    from mufusion.scenarios import load_scenario
    from mufusion.vehicle.params import vehicle_preset

    cfg = load_scenario(str(_written(problem_route, tmp_path)))
    assert cfg.name == "road"
    assert cfg.start_s_m == pytest.approx(10.0)
    road = cfg.build_road(vehicle_preset(cfg.vehicle))
    assert road.path.length_m == pytest.approx(problem_route.length_m, rel=0.02)
    assert road.lane_width_m == pytest.approx(problem_route.lanes.ego_width_m, abs=1e-3)
    assert len(road.obstacles) == len(problem_route.obstacles)
