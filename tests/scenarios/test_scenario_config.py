"""Scenario files: shipped, validated, overridable from the command line."""

from __future__ import annotations

import pytest

from mufusion.scenarios import BUILTIN_SCENARIOS, load_scenario


@pytest.mark.parametrize("name", BUILTIN_SCENARIOS)
def test_builtin_scenarios_load(name: str) -> None:
    cfg = load_scenario(name)
    assert cfg.name == name
    assert cfg.vehicle == "truck"


def test_paper_settings() -> None:
    turn = load_scenario("turn")
    assert (turn.initial_speed_mps, turn.turn.radius_m) == (12.0, 28.0)
    assert (turn.friction.mu_before, turn.friction.mu_turn) == (0.8, 0.4)
    assert turn.estimation.local_error == "worst_over"
    popup = load_scenario("popup")
    assert (popup.initial_speed_mps, popup.friction.mu) == (20.0, 1.0)
    assert popup.obstacle is not None and popup.obstacle.distance_m == 20.0
    assert popup.estimation.local_error == "worst_under"


@pytest.mark.parametrize(
    ("key", "value", "getter"),
    [
        ("initial_speed_mps", "15", lambda c: c.initial_speed_mps == 15.0),
        ("vehicle", "car", lambda c: c.vehicle == "car"),
        ("duration_s", "3.5", lambda c: c.duration_s == 3.5),
        ("seed", "7", lambda c: c.seed == 7),
        ("obstacle.distance_m", "25", lambda c: c.obstacle.distance_m == 25.0),
        ("obstacle.lateral_offset_m", "-0.5", lambda c: c.obstacle.lateral_offset_m == -0.5),
        ("friction.mu", "0.89", lambda c: c.friction.mu == 0.89),
        ("estimation.local_error", "random", lambda c: c.estimation.local_error == "random"),
        ("estimation.predictive_error", "none", lambda c: c.estimation.predictive_error == "none"),
    ],
)
def test_popup_overrides(key: str, value: str, getter) -> None:
    assert getter(load_scenario("popup", [f"{key}={value}"]))


@pytest.mark.parametrize(
    ("key", "value"),
    [("friction.mu_before", "0.7"), ("friction.mu_turn", "0.3"), ("turn.radius_m", "40")],
)
def test_turn_overrides(key: str, value: str) -> None:
    cfg = load_scenario("turn", [f"{key}={value}"])
    section, field = key.split(".")
    assert getattr(getattr(cfg, section), field) == float(value)


@pytest.mark.parametrize(
    ("override", "fragment"),
    [
        ("friction.mu=-0.2", "friction.mu"),
        ("friction.mu=nan", "friction.mu"),
        ("initial_speed_mps=100", "initial_speed_mps"),
        ("vehicle=bus", "vehicle"),
        ("estimation.local_error=sometimes", "estimation.local_error"),
        ("obstacle.colour=red", "obstacle.colour"),
        ("nonsense", "dotted.key=value"),
        ("turn.radius_m=abc", "turn.radius_m"),
    ],
)
def test_bad_overrides_name_the_field(override: str, fragment: str) -> None:
    with pytest.raises(ValueError, match=fragment.replace(".", r"\.")):
        load_scenario("popup" if not override.startswith("turn") else "turn", [override])


def test_unknown_scenario_and_missing_file(tmp_path) -> None:
    with pytest.raises(ValueError, match="scenario must be one of"):
        load_scenario("highway")
    with pytest.raises(ValueError, match="does not exist"):
        load_scenario(tmp_path / "nope.toml")


def test_scenario_file_round_trip(tmp_path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text('name = "popup"\ninitial_speed_mps = 18.0\n[obstacle]\ndistance_m = 30.0\n')
    cfg = load_scenario(path, ["friction.mu=0.7"])
    assert (cfg.initial_speed_mps, cfg.obstacle.distance_m, cfg.friction.mu) == (18.0, 30.0, 0.7)


def test_popup_without_obstacle_is_rejected(tmp_path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('name = "popup"\n')
    with pytest.raises(ValueError, match="obstacle"):
        load_scenario(path)
