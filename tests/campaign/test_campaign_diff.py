"""`mufusion campaign-diff`: two campaigns of the same grid compared run by run (synthetic
results tables; no simulation needed)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from mufusion.campaign.diff import GRADED, OUTCOMES, RUN_KEY, campaign_diff, diff_markdown
from mufusion.cli import app
from mufusion.metrics import RunMetrics


def _rows(change: bool) -> list[dict]:
    """Two configurations × three variants; with ``change`` F-safe hits in the second variant
    (it cleared by 0.1 m), passes 5 cm wider in the first, and GT's third run failed."""
    rows = []
    for config in ("GT", "F-safe"):
        for i, mu in enumerate((0.4, 0.6, 0.8)):
            hit = change and config == "F-safe" and i == 1
            clearance = None if hit else 0.1 + (0.05 if change and config == "F-safe"
                                                and i == 0 else 0.0)
            rows.append({"run": f"{len(rows):04d}", "index": len(rows), "scenario": "popup",
                         "variant": f"friction.mu={mu}", "config": config, "seed": 0,
                         "friction.mu": mu, "error": "boom" if change and config == "GT"
                         and i == 2 else None, "log": "runs/x", "collision": hit,
                         "left_lane": True, "off_road": False, "spun": False,
                         "min_clearance_m": clearance, "impact_speed_mps": 20.0 if hit else None,
                         "feasibility": "feasible" if i else "marginal"})
    return rows


def test_flips_counts_and_graded_moves_are_read_run_by_run() -> None:
    diff = campaign_diff(pd.DataFrame(_rows(False)), pd.DataFrame(_rows(True)))
    assert (diff.matched, diff.only_before, diff.only_after) == (5, 1, 0)
    assert diff.worse == 1
    flip = diff.flips.iloc[0]
    assert (flip["config"], flip["variant"], flip["outcome"], flip["before"], flip["after"]) == (
        "F-safe", "friction.mu=0.6", "collision", False, True)
    assert flip["min_clearance_m before"] == pytest.approx(0.1)
    assert np.isnan(flip["min_clearance_m after"])
    counts = diff.counts.set_index(["config", "class", "outcome"])
    assert counts.loc[("F-safe", "feasible", "collision"), ["before", "after"]].tolist() == [0, 1]
    assert counts.loc[("GT", "feasible", "collision"), "runs"] == 1  # its failed run left out
    clearance = diff.moved.set_index("graded").loc["min_clearance_m"]
    # The flipped run is not a move; the one 5 cm wider is.
    assert (clearance["runs"], clearance["up"], clearance["down"]) == (4, 1, 0)
    assert clearance["largest_rise"] == pytest.approx(0.05)
    md = diff_markdown(diff, "before", "after")
    assert "| F-safe | feasible | collision | 2 | 0 | 1 |" in md
    assert "friction.mu=0.6" in md and "Outcomes that got worse: 1" in md


def test_the_same_campaign_compares_equal() -> None:
    table = pd.DataFrame(_rows(False))
    diff = campaign_diff(table, table.copy())
    assert diff.flips.empty and diff.worse == 0
    assert (diff.counts["before"] == diff.counts["after"]).all()
    assert (diff.moved[["up", "down"]].to_numpy() == 0).all()


def test_a_run_named_twice_or_no_shared_run_is_refused() -> None:
    table = pd.DataFrame(_rows(False))
    with pytest.raises(ValueError, match="names a run twice"):
        campaign_diff(pd.concat([table, table.iloc[:1]]), table)
    other = table.assign(variant=table["variant"] + " (another grid)")
    with pytest.raises(ValueError, match="share no run"):
        campaign_diff(table, other)


def _campaign(path, change: bool):
    path.mkdir()
    rows = _rows(change)
    pd.DataFrame(rows).to_parquet(path / "results.parquet")
    (path / "summary.json").write_text(json.dumps({"name": path.name, "grid_columns":
                                                   ["friction.mu"], "runs": rows}))
    return path


def test_the_command_prints_writes_markdown_and_gates_on_worse(tmp_path) -> None:
    before, after = _campaign(tmp_path / "a", False), _campaign(tmp_path / "b", True)
    out = tmp_path / "diff.md"
    result = CliRunner().invoke(app, ["campaign-diff", str(before), str(after), "--out",
                                      str(out)])
    assert result.exit_code == 0, result.output
    assert "collision False → True" in result.output
    assert "friction.mu=0.6" in out.read_text()
    gated = CliRunner().invoke(app, ["campaign-diff", str(before), str(after),
                                     "--fail-on-worse"])
    assert gated.exit_code == 1
    assert CliRunner().invoke(app, ["campaign-diff", str(after), str(before),
                                    "--fail-on-worse"]).exit_code == 0


def test_a_directory_without_a_campaign_exits_2_naming_it(tmp_path) -> None:
    before = _campaign(tmp_path / "a", False)
    result = CliRunner().invoke(app, ["campaign-diff", str(before), str(tmp_path / "none")])
    assert result.exit_code == 2
    assert "none" in result.output and "no campaign results" in result.output


def test_the_outcomes_compared_are_metrics_and_the_key_the_runs_parameters() -> None:
    fields = {f.name for f in dataclasses.fields(RunMetrics)}
    assert set(OUTCOMES) <= fields and set(GRADED) <= fields
    assert RUN_KEY == ("scenario", "variant", "config", "seed")
