"""Per-kind scenario schemas: every key does something, every error names its field."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mufusion.scenarios import load_scenario
from mufusion.scenarios.sections import VehicleName
from mufusion.vehicle.params import PRESETS, vehicle_preset


@pytest.mark.parametrize(
    ("scenario", "override", "fragment"),
    [
        # The turn has mu_before / mu_turn; `friction.mu` used to be accepted and ignored.
        ("turn", "friction.mu=0.1", "unknown key 'friction.mu' for the 'turn' scenario"),
        ("turn", "obstacle.distance_m=20", "unknown key 'obstacle'"),
        ("turn", "emergency_on_obstacle=true", "unknown key 'emergency_on_obstacle'"),
        ("popup", "turn.radius_m=30", "unknown key 'turn' for the 'popup' scenario"),
        ("popup", "friction.mu_turn=0.3", "keys at friction: mu"),
    ],
)
def test_keys_a_kind_does_not_use_are_rejected(scenario, override, fragment) -> None:
    with pytest.raises(ValueError, match=fragment):
        load_scenario(scenario, [override])


def test_a_boolean_is_not_a_number() -> None:
    with pytest.raises(ValueError, match="initial_speed_mps: expected a number, got the boolean"):
        load_scenario("turn", ["initial_speed_mps=true"])
    with pytest.raises(ValueError, match="radius_m: expected a number"):
        load_scenario("turn", ["turn.radius_m=false"])
    assert load_scenario("popup", ["planner.use_sampling=false"]).planner.use_sampling is False


def test_the_same_key_twice_is_an_error() -> None:
    with pytest.raises(ValueError, match="'seed' is given more than once"):
        load_scenario("turn", ["seed=1", "seed=2"])


def test_turn_angle_shapes_the_road() -> None:
    for angle in (math.pi / 4, math.pi / 2, 2.0):
        cfg = load_scenario("turn", [f"turn.angle_rad={angle}"])
        road = cfg.build_road(vehicle_preset(cfg.vehicle))
        # A right turn by `angle`: the road ends heading −angle.
        assert float(road.path.end_heading_rad) == pytest.approx(-angle, abs=1e-9)


def test_a_later_popup_appears_its_distance_ahead_of_the_vehicle_front() -> None:
    # distance_m is the gap when it appears; a later appearance moves the obstacle down the
    # road by the initial speed's cruise and triggers it on the vehicle's progress, so that
    # the gap holds whatever the vehicle did meanwhile (it was fixed from the start before:
    # 1.5 s at 22 m/s put a 32 m pop-up 1 m ahead of the front).
    at_once, later = (load_scenario("popup", ["initial_speed_mps=22", "obstacle.distance_m=32",
                                              f"obstacle.appear_at_s={t}"]) for t in (0.0, 1.5))
    params = vehicle_preset(at_once.vehicle)
    (first,), (second,) = (c.build_road(params).obstacles for c in (at_once, later))
    assert first.appear_at_time_s == 0.0 and first.appear_at_ego_s_m is None
    assert second.s_m - first.s_m == pytest.approx(22.0 * 1.5)
    assert second.appear_at_time_s is None
    # It appears when the front (CoG + cog_to_body_front_m) is distance_m before its centre.
    gap = second.s_m - (second.appear_at_ego_s_m + params.cog_to_body_front_m)
    assert gap == pytest.approx(32.0)
    with pytest.raises(ValueError, match=r"obstacle\.appear_at_s must leave the obstacle"):
        load_scenario("popup", ["initial_speed_mps=22", "obstacle.appear_at_s=20"])


def test_clothoids_longer_than_the_turn_are_rejected() -> None:
    with pytest.raises(ValueError, match="clothoid_m must be <= radius_m"):
        load_scenario("turn", ["turn.angle_rad=0.1", "turn.clothoid_m=5"])


@pytest.mark.parametrize(
    ("overrides", "fragment"),
    [
        (["duration_s=0.4"], "duration_s must exceed comparison_time_s = 0.5"),
        (["sim.controller_rate_hz=60"], "sim.controller_rate_hz must divide sim.plant_rate_hz"),
        (["planner.rate_hz=20"], "planner.rate_hz must divide sim.controller_rate_hz"),
    ],
)
def test_checks_that_used_to_fail_inside_the_simulation_run_up_front(overrides, fragment) -> None:
    with pytest.raises(ValueError, match=fragment):
        load_scenario("popup", overrides)


def test_a_binary_scenario_file_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "scenario.toml"
    path.write_bytes(bytes(range(256)))
    with pytest.raises(ValueError, match=r"scenario\.toml"):
        load_scenario(str(path))


def test_invalid_obstacle_field_names_the_table(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('name = "popup"\n[obstacle]\ndistance_m = -3\n')
    with pytest.raises(ValueError, match=r"obstacle\.distance_m"):
        load_scenario(str(path))


def test_vehicle_names_are_the_presets() -> None:
    assert set(VehicleName.__args__) == set(PRESETS)  # type: ignore[attr-defined]


def test_drivable_band_per_kind() -> None:
    turn, popup = load_scenario("turn"), load_scenario("popup")
    assert turn.drivable_d_m() == (-1.75, 1.75)
    assert popup.drivable_d_m() == (-1.75, 5.25)
    assert np.isclose(popup.comparison_time_s, 0.5) and turn.comparison_time_s == 0.0
