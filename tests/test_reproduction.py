"""The product's main claim, end to end: `mufusion reproduce` and the paper's outcomes.

This runs the whole reproduction once (30 closed-loop runs, figures, report; about a minute on
two cores) and asserts the outcome table. Where our outcome differs from the paper's, the test
asserts what we report instead, and that the report explains it.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from mufusion.cli import app

# Closed-loop runs of several seconds each: outside the fast subset (pytest -m 'not slow').
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def reproduction(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    result = CliRunner().invoke(app, ["reproduce", "--out", str(out), "--no-gif"])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    runs = {(r["variant"], r["config"]): r for r in summary["runs"]}
    return out, runs


def test_turn_local_only_slides_into_the_opposing_lane_and_the_others_keep_their_lane(
    reproduction,
):
    _, runs = reproduction
    assert runs[("turn-paper", "L")]["entered_opposing_lane"]
    for config in ("GT", "P", "F-safe"):
        assert not runs[("turn-paper", config)]["left_lane"], config
    # L planned with the 0.8 it last measured: far more force than μ = 0.4 gives.
    assert runs[("turn-paper", "L")]["max_force_excess"] > 0.5
    assert runs[("turn-paper", "GT")]["max_force_excess"] == 0.0


@pytest.mark.parametrize("variant", ["popup-paper", "popup-authors"])
def test_popup_predictive_only_collides_and_the_others_pass(reproduction, variant):
    _, runs = reproduction
    p = runs[(variant, "P")]
    assert p["collision"] and 15.0 <= p["impact_speed_mps"] <= 20.0
    # With all of the authors' settings the obstacle is 2.65 m closer (20 m from the CoG, not
    # the front) and GT passes by centimetres: the fused configurations, planning with 7-9 %
    # less force, hit it (the report explains it from the logs).
    passing = ("GT", "L", "F", "F-safe") if variant == "popup-paper" else ("GT", "L")
    for config in passing:
        run = runs[(variant, config)]
        assert not run["collision"], config
        assert run["min_clearance_m"] is not None and run["min_clearance_m"] > 0.0, config
        assert run["max_abs_lateral_offset_m"] < 3 * 3.5 / 2, config  # stayed on the road


def test_authors_turn_local_only_saturates_and_slides_into_the_opposing_lane(reproduction):
    out, runs = reproduction
    l_run = runs[("turn-authors", "L")]
    assert l_run["entered_opposing_lane"] and l_run["max_force_excess"] > 0.5
    # P, planning on the camera's 0.3 where μ is 0.4, takes the arc inside its tires' limit.
    # Whether a corner then crosses the line by a few centimetres in the weave that follows is
    # decided by the QP's rounding, not by the physics: over ten numerically equivalent solver
    # settings P's farthest corner ended 0.00-0.13 m beyond the line (docs/decisions/0102).
    p_run = runs[("turn-authors", "P")]
    assert p_run["max_force_excess"] == 0.0 and not p_run["spun"]
    assert p_run["max_lane_excursion_m"] < 0.15
    assert l_run["max_lane_excursion_m"] > 10 * 0.15  # L: metres into the opposing lane
    report = (out / "report.md").read_text()
    # The slide mechanism is read from L's log: its front tires saturated.
    section = report.split("### Why L leaves its lane in the turn, or why not")[1]
    authors = section.split("**turn, the authors' settings.**")[1].split("\n\n")[0]
    assert "The tires saturated (utilisation ≥ 0.98): the front at" in authors
    assert "slid and spun into the opposing lane" in authors or "slid into the opposing" in authors
    paper = section.split("**turn, paper settings.**")[1].split("\n\n")[0]
    assert "never exceeded the true limit" in paper


def test_popup_planned_force_utilisation_against_ground_truth(reproduction):
    _, runs = reproduction
    # Paper: P −32.6 % (authors' μ = 0.89) / −40 % (μ = 1.0); F within −10 % (paper −5.6 %).
    assert runs[("popup-authors", "P")]["utilization_vs_gt"] == pytest.approx(
        -0.326, abs=0.01)
    assert runs[("popup-paper", "P")]["utilization_vs_gt"] == pytest.approx(
        -0.40, abs=0.01)
    for variant in ("popup-paper", "popup-authors"):
        assert -0.10 <= runs[(variant, "F")]["utilization_vs_gt"] < 0.0


def test_report_puts_every_difference_next_to_an_explanation(reproduction):
    out, runs = reproduction
    report = (out / "report.md").read_text()
    assert (out / "report.html").is_file()
    assert "No explanation recorded" not in report
    assert report.count("| agrees |") >= 24
    assert "## The authors' settings" in report and "Not represented:" in report
    assert any((out / "figures").glob("turn-*-slide.png"))
    assert any((out / "figures").glob("*.png"))
    assert {r["config"] for r in runs.values()} == {"GT", "L", "P", "F", "F-safe"}


def test_report_opens_in_a_browser_with_every_figure_loaded(reproduction):
    from browser import load_in_browser

    out, _ = reproduction
    seen = load_in_browser(out / "report.html")
    assert len(seen.images) >= 5, seen.images
    assert seen.broken_images == [] and seen.failed_requests == []
    assert seen.console_errors == []
