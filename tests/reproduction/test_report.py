"""The reproduction report: verdicts computed from metrics, explanations, figures, HTML."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from mufusion.reproduction import compare_with_paper, markdown_to_html, write_report
from mufusion.reproduction.verdicts import Outcome

AGREES, DIFFERS, NO_DATA = Outcome.AGREES, Outcome.DIFFERS, Outcome.NO_DATA

_BASE = {
    "collision": False, "impact_speed_mps": None, "min_clearance_m": None,
    "max_abs_lateral_offset_m": 0.5, "left_lane": False, "entered_opposing_lane": False,
    "planned_utilization_at_comparison": 0.5, "utilization_vs_gt": None,
    "max_force_excess": 0.0, "planner_median_ms": 12.0, "planner_p99_ms": 30.0,
    "fallbacks": 0, "sampling_reinits": 0, "final_speed_mps": 10.0, "duration_s": 5.0,
}


_KEYS = {("turn", "paper"): "turn-paper", ("popup", "paper mu=1.0"): "popup-paper",
         ("popup", "authors mu=0.89"): "popup-authors", ("popup", "car"): "popup-car"}


def _run(scenario: str, variant: str, config: str, **metrics) -> dict:
    key = _KEYS[(scenario, variant)]
    return {"scenario": scenario, "variant": key, "config": config, **_BASE, **metrics}


def _verdicts(run: dict) -> dict[str, str]:
    return {v.criterion: v.outcome for v in compare_with_paper(run)}


def test_popup_verdicts_follow_the_paper() -> None:
    variant = "authors mu=0.89"
    p_as_paper = _run("popup", variant, "P", collision=True, impact_speed_mps=17.0,
                      utilization_vs_gt=-0.30)
    assert _verdicts(p_as_paper) == {
        "collision": AGREES, "impact speed": AGREES, "utilisation vs GT": AGREES,
    }
    p_no_hit = _run("popup", variant, "P", collision=False, utilization_vs_gt=-0.10)
    assert _verdicts(p_no_hit) == {
        "collision": DIFFERS, "impact speed": NO_DATA, "utilisation vs GT": DIFFERS,
    }
    f_ok = _run("popup", variant, "F", min_clearance_m=0.6, utilization_vs_gt=-0.06)
    assert _verdicts(f_ok) == {"collision": AGREES, "clearance": AGREES,
                               "utilisation vs GT": AGREES}
    f_close = _run("popup", variant, "F", min_clearance_m=0.1, utilization_vs_gt=-0.06)
    assert _verdicts(f_close)["clearance"] == DIFFERS
    gt_hit = _run("popup", variant, "GT", collision=True)
    assert _verdicts(gt_hit)["collision"] == DIFFERS
    assert "utilisation vs GT" not in _verdicts(gt_hit)


def test_utilization_reference_depends_on_the_variant() -> None:
    # -40 % agrees at the paper's μ = 1.0 but not with the authors' -32.6 % ± 5 pp at μ = 0.89.
    assert _verdicts(_run("popup", "paper mu=1.0", "P", collision=True,
                          utilization_vs_gt=-0.40))["utilisation vs GT"] == AGREES
    assert _verdicts(_run("popup", "authors mu=0.89", "P", collision=True,
                          utilization_vs_gt=-0.40))["utilisation vs GT"] == DIFFERS


def test_turn_verdicts_and_car_variant() -> None:
    assert _verdicts(_run("turn", "paper", "L", entered_opposing_lane=True, left_lane=True)) == {
        "opposing lane": AGREES}
    assert _verdicts(_run("turn", "paper", "L")) == {"opposing lane": DIFFERS}
    assert _verdicts(_run("turn", "paper", "F", left_lane=True)) == {"stays in lane": DIFFERS}
    # The car variant only checks the qualitative outcome; F-safe is not in the paper.
    assert set(_verdicts(_run("popup", "car", "F", min_clearance_m=3.0))) == {"collision"}
    assert compare_with_paper(_run("popup", "paper mu=1.0", "F-safe")) == []
    with pytest.raises(ValueError, match="'config'"):
        compare_with_paper({"scenario": "turn", "variant": "turn-paper"})


def _figure(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100))
    return path


def test_report_lists_every_run_and_explains_differences(tmp_path: Path) -> None:
    runs = [
        _run("turn", "paper", "GT"),
        _run("turn", "paper", "L", entered_opposing_lane=True, left_lane=True),
        _run("popup", "paper mu=1.0", "P", collision=False, utilization_vs_gt=-0.40),
        _run("popup", "paper mu=1.0", "F", min_clearance_m=0.55, utilization_vs_gt=-0.05),
        _run("popup", "paper mu=1.0", "F-safe", min_clearance_m=0.9, planner_median_ms=15.5),
    ]
    figures = {
        "turn-paper/snapshots": _figure(tmp_path / "figures" / "turn-paper-snapshots.png"),
        "popup-paper/forces": _figure(tmp_path / "figures" / "popup-forces.png"),
        "extra": _figure(tmp_path / "figures" / "extra.png"),
    }
    key = "popup-paper/P/collision"
    md_path, html_path = write_report(
        {"runs": runs, "elapsed_s": 42.0}, tmp_path, figures,
        explanations={key: "Our P plan finds a narrow gap the paper's solver missed."},
    )
    md = md_path.read_text()
    for run in runs:
        assert f"| {run['config']} |" in md
    assert "| P | collision | collides | collision = no | differs |" in md
    assert "Our P plan finds a narrow gap" in md
    assert "| P | impact speed | ≈ 17.5 m/s | — | no data |" in md
    assert "no value for impact_speed_mps" in md
    assert "| GT | stays in lane | stays in its lane | left_lane = no | agrees |" in md
    assert "## Safe fusion mode (F-safe)" in md and "15.5" in md
    assert "(figures/turn-paper-snapshots.png)" in md
    assert "(figures/popup-forces.png)" in md and "(figures/extra.png)" in md
    html = html_path.read_text()
    assert html.startswith("<!DOCTYPE html>")
    assert 'src="figures/turn-paper-snapshots.png"' in html
    assert html.count("<table>") == md.count("\n|---|")
    assert "<td>differs</td>" in html


def test_unexplained_difference_states_the_metric_and_amount(tmp_path: Path) -> None:
    runs = [_run("popup", "authors mu=0.89", "F", min_clearance_m=1.5, utilization_vs_gt=-0.2)]
    md = write_report({"runs": runs, "elapsed_s": 1.0}, tmp_path, {})[0].read_text()
    assert "min_clearance_m is 1.50 m vs the paper's 0.50 m: +1.00 m" in md
    assert "utilization_vs_gt is -20.0 % vs the paper's -5.6 %: -14.4 percentage points" in md
    assert md.count("No explanation recorded") == 2


def test_report_rejects_bad_input(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="summary\\['runs'\\]"):
        write_report({"runs": [], "elapsed_s": 0.0}, tmp_path, {})
    with pytest.raises(ValueError, match="does not exist"):
        write_report({"runs": [_run("turn", "paper", "F")]}, tmp_path,
                     {"x": tmp_path / "missing.png"})
    with pytest.raises(ValueError, match="'variant'"):
        write_report({"runs": [{"scenario": "turn", "config": "F"}]}, tmp_path, {})
    with pytest.raises(ValueError, match="unknown variants"):
        write_report({"runs": [{"variant": "paper mu=1.0", "config": "F"}]}, tmp_path, {})


def test_markdown_converter_formats_tables_and_spans() -> None:
    html = markdown_to_html("# A & B\n\nx **y** `z`\n\n| a | b |\n|---|---|\n| 1 \\| 2 | 3 |\n")
    assert "<h1>A &amp; B</h1>" in html
    assert "<p>x <strong>y</strong> <code>z</code></p>" in html
    assert re.search(r"<td>1 \| 2</td>\s*<td>3</td>", html)
