"""`mufusion campaign-report`: rates with Wilson intervals, distributions, heat maps, Markdown and
HTML, from a campaign directory (a synthetic results table here; no simulation needed)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from PIL import Image
from typer.testing import CliRunner

from mufusion.campaign.report import load_campaign_results, rates_by_class_markdown
from mufusion.cli import app


def _campaign_dir(tmp_path, partial: bool = False):
    rng = np.random.default_rng(1)
    rows = []
    for mu in (0.8, 1.0):
        for distance in (18.0, 22.0):
            for config in ("GT", "P", "F"):
                for seed in range(10):
                    crash = config == "P" and distance == 18.0 and seed < (6 if mu < 1 else 3)
                    rows.append({
                        "run": f"{len(rows):04d}", "index": len(rows), "scenario": "popup",
                        "variant": f"friction.mu={mu}, obstacle.distance_m={distance}",
                        "config": config, "seed": seed, "friction.mu": mu,
                        "obstacle.distance_m": distance, "error": None, "log": "runs/x",
                        "collision": crash, "left_lane": True,
                        "entered_opposing_lane": bool(seed % 2),
                        "min_clearance_m": None if crash else float(rng.uniform(0.1, 1.0)),
                        "planner_median_ms": 3.0,
                    })
    out = tmp_path / "campaign"
    out.mkdir()
    pd.DataFrame(rows).to_parquet(out / "results.parquet")
    summary = {"campaign": "mc.toml", "name": "mc test", "shard": "0/1", "engine": "pool",
               "elapsed_s": 12.0, "partial": partial, "pending": 5 if partial else 0,
               "grid_columns": ["friction.mu", "obstacle.distance_m"], "runs": rows}
    (out / "summary.json").write_text(json.dumps(summary))
    return out


@pytest.fixture(scope="module")
def complete_campaign(tmp_path_factory):
    """The complete synthetic campaign and the output of its report, made once for the module
    (the tests below only read them)."""
    directory = _campaign_dir(tmp_path_factory.mktemp("report"))
    result = CliRunner().invoke(app, ["campaign-report", str(directory)])
    return directory, result


def test_campaign_report_writes_rates_intervals_heat_maps_and_html(complete_campaign):
    directory, result = complete_campaign
    assert result.exit_code == 0, result.output
    report = directory / "report"
    md = (report / "report.md").read_text()
    # P collides in 9 of its 40 runs: 22 % with the Wilson interval [12, 38] %.
    assert "| P | 22 % [12, 38] (9/40) |" in md
    assert "| GT | 0 % [0, 9] (0/40) |" in md
    assert "min_clearance_m" in md and "planner_median_ms" not in md
    html = (report / "report.html").read_text()
    assert "<table>" in html and "<img" in html and "Outcome rates" in html
    figures = sorted(p.name for p in (report / "figures").iterdir())
    assert "heatmap-collision.png" in figures and "heatmap-min_clearance_m.png" in figures
    assert "rates.png" in figures and "distributions.png" in figures
    for name in figures:
        with Image.open(report / "figures" / name) as image:
            assert image.width > 200 and image.height > 100
    assert "![heatmap/collision](figures/heatmap-collision.png)" in md
    # P against GT on the same starts: it collides in 9 runs whose GT run does not, never the
    # other way round (sign test p = 2 / 2⁹); the 9 runs are listed, each with GT's clearance.
    assert "## Against GT, run by run" in md
    assert "| P | collision | 40 | 9 | 0 | 0 | 0.0039 |" in md
    assert "| F | collision | 40 | 0 | 0 | 0 | – |" in md
    assert "Runs that fail where GT does not (9)" in md
    assert md.count("| popup | P | `friction.mu=") == 9


def test_partial_campaign_is_flagged_and_a_missing_directory_exits_2(tmp_path):
    directory = _campaign_dir(tmp_path, partial=True)
    assert load_campaign_results(directory).partial
    out = tmp_path / "elsewhere"
    result = CliRunner().invoke(app, ["campaign-report", str(directory), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "Partial campaign" in (out / "report.md").read_text()
    result = CliRunner().invoke(app, ["campaign-report", str(tmp_path / "nothing")])
    assert result.exit_code == 2 and "no campaign results" in " ".join(result.output.split())


def test_rates_are_split_by_the_oracles_class():
    rows = []
    for cls, exits in (("feasible", 1), ("infeasible", 4)):
        for config in ("GT", "F-safe"):
            for seed in range(5):
                rows.append({"scenario": "turn", "config": config, "seed": seed,
                             "feasibility": cls, "error": None, "collision": False,
                             "left_lane": seed < exits + (config == "F-safe")})
    table = pd.DataFrame(rows)
    md = "\n".join(rates_by_class_markdown(table))
    # Feasible: GT 1 of 5 (20 %, Wilson [4, 62] %), F-safe 2 of 5; infeasible 4 and 5 of 5.
    assert "| feasible | GT | 0 % [0, 43] (0/5) | 20 % [4, 62] (1/5) |" in md
    assert "| feasible | F-safe | 0 % [0, 43] (0/5) | 40 % [12, 77] (2/5) |" in md
    assert "| infeasible | F-safe | 0 % [0, 43] (0/5) | 100 % [57, 100] (5/5) |" in md
    assert md.index("| feasible | GT") < md.index("| infeasible | GT")
    # One class only, or no oracle column: nothing to split.
    assert rates_by_class_markdown(table[table["feasibility"] == "feasible"]) == []
    assert rates_by_class_markdown(table.drop(columns="feasibility")) == []


def test_campaign_report_opens_in_a_browser_with_every_image_loaded(complete_campaign):
    from browser import load_in_browser

    directory, result = complete_campaign
    assert result.exit_code == 0, result.output
    seen = load_in_browser(directory / "report" / "report.html")
    assert len(seen.images) >= 4, seen.images
    assert seen.broken_images == [] and seen.failed_requests == []
    assert seen.console_errors == []
