"""The oracle along any road: the curve limit √(λμgR) where the path and its friction zones
set it, the pop-up envelopes for a static obstacle in the own lane, the worst verdict wins."""

from __future__ import annotations

import math
from typing import Any

import pytest

from mufusion.scenarios import scenario_from_dict
from mufusion.scenarios.feasibility import (
    FeasibilityClass,
    RoadFeasibility,
    classify_scenario,
    summary_fields,
)
from mufusion.scenarios.feasibility.common import GRAVITY_MPS2
from mufusion.vehicle.params import vehicle_preset

CAR = vehicle_preset("car")


def _road(speed_mps: float, mu: float = 0.9, zone_mu: float | None = None,
          angle_rad: float = 1.2, obstacles: list[dict[str, Any]] | None = None,
          radius_m: float = 60.0) -> RoadFeasibility:
    """A car on 300 m of straight, a long arc (R = 60 m) and a straight; optionally μ =
    ``zone_mu`` on the whole arc."""
    arc_start = 300.0
    zones = [] if zone_mu is None else [
        {"start_m": arc_start, "end_m": arc_start + radius_m * abs(angle_rad), "mu": zone_mu}]
    cfg = scenario_from_dict({
        "name": "road", "vehicle": "car", "initial_speed_mps": speed_mps, "duration_s": 5.0,
        "start_s_m": 50.0,
        "path": {"segments": [{"kind": "straight", "length_m": arc_start},
                              {"kind": "arc", "radius_m": radius_m, "angle_rad": angle_rad},
                              {"kind": "straight", "length_m": 200.0}]},
        "lanes": {"drivable": "road"},
        "friction": {"mu": mu, "zones": zones},
        "obstacles": obstacles or [],
    })
    verdict = classify_scenario(cfg, CAR)
    assert isinstance(verdict, RoadFeasibility)
    return verdict


def test_a_long_arc_limits_at_its_steady_state_speed() -> None:
    # 250 m of straight before the arc: any speed brakes down in time; the limit is the arc's.
    limit = math.sqrt(0.9 * 0.9 * GRAVITY_MPS2 * 60.0)
    verdict = _road(20.0)
    assert verdict.path.limit_speed_mps == pytest.approx(limit, rel=1e-9)
    assert verdict.feasibility_class is FeasibilityClass.FEASIBLE
    assert verdict.deciding == "path"
    # A right curve limits as a left one.
    assert _road(20.0, angle_rad=-1.2).path.limit_speed_mps == pytest.approx(limit, rel=1e-9)


def test_a_friction_zone_on_the_arc_lowers_the_limit_and_the_margin() -> None:
    dry, wet = _road(25.0), _road(25.0, zone_mu=0.3)
    assert wet.path.limit_speed_mps == pytest.approx(
        math.sqrt(0.9 * 0.3 * GRAVITY_MPS2 * 60.0), rel=1e-9)
    assert wet.margin_mps < dry.margin_mps


# A 10 m radius 20 m after the start at 25 m/s: no braking makes it.
TOO_FAST = {
    "name": "road", "vehicle": "car", "initial_speed_mps": 25.0, "duration_s": 3.0,
    "start_s_m": 20.0,
    "path": {"segments": [{"kind": "straight", "length_m": 40.0},
                          {"kind": "arc", "radius_m": 10.0, "angle_rad": -1.5},
                          {"kind": "straight", "length_m": 100.0}]},
}


def test_too_fast_into_a_close_curve_is_infeasible() -> None:
    result = classify_scenario(scenario_from_dict(TOO_FAST), CAR)
    assert result.feasibility_class is FeasibilityClass.INFEASIBLE and result.margin_mps < 0.0


def test_a_straight_road_without_obstacles_has_no_limit() -> None:
    cfg = scenario_from_dict({"name": "road", "path": {"segments": [
        {"kind": "straight", "length_m": 500.0}]}})
    verdict = classify_scenario(cfg, vehicle_preset("truck"))
    assert verdict.feasibility_class is FeasibilityClass.FEASIBLE
    assert summary_fields(verdict) == {"feasibility": "feasible", "feasibility_margin_mps": None}


def test_a_static_obstacle_in_the_lane_is_judged_as_a_pop_up() -> None:
    near = [{"s_m": 90.0, "d_m": 0.0, "appear_ahead_m": 12.0}]
    far = [{"s_m": 250.0, "d_m": 0.0}]  # there from the start, 200 m ahead
    beside = [{"s_m": 90.0, "d_m": 3.5, "appear_ahead_m": 12.0}]  # in the opposing lane
    oncoming = [{"s_m": 250.0, "d_m": 0.0, "speed_mps": -10.0}]
    close = _road(25.0, obstacles=near)
    assert [i for i, _ in close.obstacles] == [0]
    assert close.deciding == "obstacles.0"
    assert close.margin_mps == close.obstacles[0][1].margin_mps < _road(25.0).margin_mps
    assert _road(25.0, obstacles=far).obstacles[0][1].feasibility_class is (
        FeasibilityClass.FEASIBLE)
    assert _road(25.0, obstacles=beside).obstacles == ()
    assert _road(25.0, obstacles=oncoming).obstacles == ()  # moving: not judged


def test_the_verdict_lands_in_the_run_metadata() -> None:
    from mufusion.scenarios.runner import planner_config, run_meta

    cfg = scenario_from_dict(TOO_FAST)
    meta = run_meta(cfg, "GT", CAR, cfg.build_road(CAR), planner_config(cfg, CAR))
    verdict = summary_fields(classify_scenario(cfg, CAR))
    assert meta.feasibility == verdict["feasibility"] == "infeasible"
    assert meta.feasibility_margin_mps == pytest.approx(verdict["feasibility_margin_mps"],
                                                        abs=1e-3)
