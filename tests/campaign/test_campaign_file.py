"""Campaign files: validation, the grid, shards that partition a campaign and keep GT with it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from mufusion.campaign import (
    RunSpec,
    campaign_specs,
    check_distinct,
    load_campaign,
    with_indices,
)
from mufusion.cli import app
from mufusion.scenarios import load_scenario

SWEEP = """
name = "test sweep"
scenarios = ["popup", "turn"]
configs = ["GT", "P"]
overrides = ["duration_s=0.6"]
[grid]
"initial_speed_mps" = [10.0, 12.0, 14.0]
"""


def _write(tmp_path, text: str):
    path = tmp_path / "c.toml"
    path.write_text(text)
    return path


def test_grid_times_scenarios_times_configs(tmp_path):
    specs = campaign_specs(load_campaign(_write(tmp_path, SWEEP)))
    assert len(specs) == 2 * 3 * 2
    assert {s.variant for s in specs} == {f"initial_speed_mps={v}" for v in (10.0, 12.0, 14.0)}
    assert all("duration_s=0.6" in s.overrides for s in specs)


@pytest.mark.parametrize("shards", [1, 2, 4, 7])
def test_shards_partition_the_campaign_and_keep_each_variant_whole(tmp_path, shards):
    campaign = load_campaign(_write(tmp_path, SWEEP))
    parts = [campaign_specs(campaign, shard=k, shards=shards) for k in range(shards)]
    flat = [s for part in parts for s in part]
    assert sorted(flat, key=repr) == sorted(campaign_specs(campaign), key=repr)
    for part in parts:
        variants = {(s.scenario, s.variant) for s in part}
        for scenario, variant in variants:
            configs = {s.config for s in part if (s.scenario, s.variant) == (scenario, variant)}
            assert configs == {"GT", "P"}


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('scenarios = ["popup"]\nconfigs = ["Q"]', "configs: 'Q' is neither a built-in"),
        ('scenarios = ["popup"]\nconfigs = ["no_such_mod:S"]',
         "configs: plug-in 'no_such_mod:S': module 'no_such_mod' failed to import"),
        ('scenarios = ["popup"]\nplanner = "no_such_mod:P"',
         "planner.*plug-in 'no_such_mod:P': module 'no_such_mod' failed to import"),
        ('scenarios = ["popup"]\ncontroller = "json:JSONDecoder"',
         "controller.*is not a controller"),
        ('scenarios = []', "scenarios"),
        ('scenarios = ["popup"]\n[grid]\n"friction.mu" = []', "no values"),
        ('scenarios = ["popup"]\ncolour = "red"', "colour"),
        ('scenarios = ["popup"]\n[grid]\n"friction.muu" = [0.5]', "friction.muu"),
        ('scenarios = ["popup"]\n[grid]\n"friction.mu" = [7.0]', "friction.mu"),
        ("scenarios = [", "not valid TOML"),
    ],
)
def test_bad_campaign_files_name_the_problem(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        campaign_specs(load_campaign(_write(tmp_path, text)))


def test_bad_shard_is_rejected(tmp_path):
    with pytest.raises(ValueError, match="shard"):
        campaign_specs(load_campaign(_write(tmp_path, SWEEP)), shard=2, shards=2)
    result = CliRunner().invoke(app, ["campaign", str(_write(tmp_path, SWEEP)), "--shard", "x"])
    assert result.exit_code == 2 and "--shard must be K/N" in result.output


def test_cli_campaign_shard_runs_and_compares_with_its_gt(tmp_path):
    text = SWEEP.replace('["popup", "turn"]', '["popup"]').replace("10.0, 12.0, 14.0", "12.0")
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["campaign", str(_write(tmp_path, text)), "--out", str(out),
                                      "--jobs", "1"])
    assert result.exit_code == 0, result.output
    runs = json.loads((out / "summary.json").read_text())["runs"]
    assert [r["config"] for r in runs] == ["GT", "P"]
    assert runs[0]["utilization_vs_gt"] == 0.0
    assert runs[1]["utilization_vs_gt"] is not None and runs[1]["utilization_vs_gt"] < 0.0


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('scenarios = ["popup"]\n[grid]\n"obstacle.lateral_offset_m" = [1.0, -1.0, 1.0]',
         r"obstacle.lateral_offset_m.*1\.0 is listed more than once"),
        ('scenarios = ["popup"]\n[grid]\n"friction.mu" = [0.8, 0.80]', "0.8 is listed more"),
        ('scenarios = ["popup"]\n[grid]\n"initial_speed_mps" = [10, 10.0]', "10"),
        ('scenarios = ["popup"]\nconfigs = ["GT", "F", "GT"]', "configs: 'GT' is listed more"),
        ('scenarios = ["popup", "popup"]', "scenarios: 'popup' is listed more"),
        ('scenarios = ["popup"]\noverrides = ["friction.mu=0.8", "friction.mu = 0.9"]',
         "'friction.mu' is listed more"),
        ('scenarios = ["popup"]\noverrides = ["friction.mu=0.8"]\n[grid]\n"friction.mu" = [0.9]',
         "grid key 'friction.mu' is also set in overrides"),
        ('scenarios = ["popup"]\nseeds = 3\n[grid]\n"seed" = [1, 2]', "seeds = N"),
        ('scenarios = ["popup"]\nseeds = 0', "seeds"),
    ],
)
def test_repeated_runs_are_rejected_up_front_naming_key_and_value(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        load_campaign(_write(tmp_path, text))


def test_a_true_and_a_one_are_different_grid_values(tmp_path):
    campaign = load_campaign(_write(tmp_path, 'scenarios = ["popup"]\n[grid]\n"x" = [true, 1]'))
    assert campaign.grid["x"] == [True, 1]


def test_hand_made_duplicate_specs_are_rejected():
    spec = RunSpec("popup", "GT", overrides=("friction.mu=0.8",))
    with pytest.raises(ValueError, match="popup / default / seed None / GT is listed more"):
        check_distinct(with_indices([spec, spec]))
    with pytest.raises(ValueError, match="share the directory name"):
        check_distinct([RunSpec("popup", "GT", index=1),
                        RunSpec("popup", "GT", overrides=("seed=2",), index=1)])


def test_seeds_repeat_every_variant_from_the_scenarios_own_seed(tmp_path):
    text = ('scenarios = ["popup"]\nconfigs = ["GT", "F"]\nseeds = 3\n'
            'overrides = ["seed=10", "duration_s=1"]\n[grid]\n"friction.mu" = [0.8, 1.0]')
    specs = campaign_specs(load_campaign(_write(tmp_path, text)))
    assert len(specs) == 2 * 3 * 2
    assert [s.seed for s in specs[:6]] == [10, 10, 11, 11, 12, 12]
    assert [s.index for s in specs] == list(range(12))
    # The seed reaches the scenario: it replaces the file's own seed=10 override.
    assert load_scenario(specs[2].scenario, specs[2].all_overrides).seed == 11
    assert len({s.name for s in specs}) == 12
    assert specs[2].name == "0002-popup-friction.mu=0.8-s11-GT"


def test_shards_keep_global_indices_so_run_names_never_collide(tmp_path):
    campaign = load_campaign(_write(tmp_path, SWEEP))
    names = [s.name for k in range(3) for s in campaign_specs(campaign, shard=k, shards=3)]
    assert sorted(names) == sorted(s.name for s in campaign_specs(campaign))


def test_run_names_are_one_readable_path_component(tmp_path):
    scenario = tmp_path / "my dir" / "custom popup.toml"
    spec = RunSpec(str(scenario.resolve()), "F-safe", "friction.mu=0.8, road/x=ü", index=12)
    assert spec.name == "0012-custom_popup-friction.mu=0.8_road_x=-F-safe"
    assert "/" not in spec.name and str(tmp_path) not in spec.name
    assert RunSpec("popup", "GT", "x" * 500, index=0).name.endswith("x-GT")
    assert len(RunSpec("popup", "GT", "x" * 500, index=0).name) < 120


EXAMPLES = sorted((Path(__file__).parents[2] / "examples").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_published_campaign_files_validate(path):
    """Every campaign file the docs tell users to run is valid: it loads, and its variants'
    scenarios validate (``campaign_specs`` checks each before anything runs, so a typo in a grid
    key, e.g. ``friction.mu_trun``, fails here and not mid-campaign)."""
    assert campaign_specs(load_campaign(path))


def test_a_controller_plugin_reaches_every_run_and_its_stored_spec(tmp_path):
    from mufusion.campaign.runs import spec_record

    text = 'scenarios = ["popup"]\nconfigs = ["GT", "F"]\n'
    plain = campaign_specs(load_campaign(_write(tmp_path, text)))
    assert all(s.controller is None for s in plain)
    assert "controller" not in spec_record(plain[0])  # records of earlier campaigns still match
    spec = "mufusion.planner:TrackingController"
    specs = campaign_specs(load_campaign(_write(tmp_path, f'{text}controller = "{spec}"\n')))
    assert [s.controller for s in specs] == [spec, spec] and specs[0].planner is None
    assert spec_record(specs[0])["controller"] == spec


def test_a_zipped_axis_takes_its_values_together(tmp_path):
    text = ('scenarios = ["turn"]\nconfigs = ["GT"]\n[grid]\nvehicle = ["truck", "car"]\n'
            '"friction.mu_before, friction.mu_turn" = [[0.9, 0.3], [0.3, 0.9]]')
    specs = campaign_specs(load_campaign(_write(tmp_path, text)))
    assert len(specs) == 2 * 2  # the product over axes, not over keys (that would be 8)
    pairs = {(dict(s.grid)["friction.mu_before"], dict(s.grid)["friction.mu_turn"])
             for s in specs}
    assert pairs == {(0.9, 0.3), (0.3, 0.9)}
    # Every key is its own grid column and override, so each run has the pair it was given.
    for spec in specs:
        cfg = load_scenario(spec.scenario, list(spec.overrides))
        assert (cfg.friction.mu_before, cfg.friction.mu_turn) in pairs
        assert [k for k, _ in spec.grid] == ["vehicle", "friction.mu_before", "friction.mu_turn"]


@pytest.mark.parametrize(
    ("grid", "match"),
    [
        ('"friction.mu, initial_speed_mps" = [[0.5]]', r"must be a list of 2 values"),
        ('"friction.mu, initial_speed_mps" = [0.5]', r"must be a list of 2 values"),
        ('"friction.mu" = [[0.5, 10.0]]', "only a zipped axis"),
        ('"friction.mu, initial_speed_mps" = [[[0.5], 10.0]]',
         r"grid\.friction\.mu, initial_speed_mps\.0"),  # pydantic: a value is no list
        ('"friction.mu, friction.mu" = [[0.5, 0.6]]', "'friction.mu' is listed more"),
        ('"friction.mu," = [[0.5, 0.6]]', "empty key"),
        ('"friction.mu" = [0.5]\n"initial_speed_mps, friction.mu" = [[10.0, 0.6]]',
         "'friction.mu' is listed more"),
        ('"friction.mu, initial_speed_mps" = [[0.5, 10.0], [0.5, 10]]', "listed more than once"),
    ],
)
def test_bad_zipped_axes_name_the_axis(tmp_path, grid, match):
    with pytest.raises(ValueError, match=match):
        load_campaign(_write(tmp_path, f'scenarios = ["popup"]\n[grid]\n{grid}'))


def test_a_zipped_key_fixed_in_overrides_is_rejected(tmp_path):
    text = ('scenarios = ["popup"]\noverrides = ["initial_speed_mps=12"]\n[grid]\n'
            '"friction.mu, initial_speed_mps" = [[0.5, 10.0]]')
    with pytest.raises(ValueError, match="grid key 'initial_speed_mps' is also set in overrides"):
        load_campaign(_write(tmp_path, text))
