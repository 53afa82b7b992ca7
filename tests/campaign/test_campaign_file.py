"""Campaign files: validation, the grid, shards that partition a campaign and keep GT with it."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from mufusion.campaign import campaign_specs, load_campaign
from mufusion.cli import app

SWEEP = """
name = "test sweep"
scenarios = ["popup", "turn"]
configs = ["GT", "P"]
overrides = ["duration_s=0.5"]
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
    assert all("duration_s=0.5" in s.overrides for s in specs)


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
        ('scenarios = ["popup"]\nconfigs = ["Q"]', "unknown configs"),
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
