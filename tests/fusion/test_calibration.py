"""Fusion calibration (no closed loop): determinism, safe mode's zero over-estimates, paper mode's
over-estimates on a known layout, the camera emulation, bad input, the figure and the command."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from mufusion.cli import app
from mufusion.estimators import LOCAL_MAX_ERROR, PAPER_CLASSES, predictive_estimate
from mufusion.fusion import DEFAULT_GRID_M, GPPrior
from mufusion.fusion.calibration import (
    NOMINAL_COVERAGE,
    CalibrationHorizons,
    CalibrationResult,
    calibrate_fusion,
    calibrate_horizons,
    camera_random,
    draw_horizons,
)
from mufusion.plots.calibration import build_calibration_figure, calibration_figure

GRID = DEFAULT_GRID_M


@pytest.fixture(scope="module")
def small() -> CalibrationResult:
    return calibrate_fusion(np.random.default_rng(7), n_horizons=400)


def test_small_calibration_is_deterministic_for_a_seed(small):
    again = calibrate_fusion(np.random.default_rng(7), n_horizons=400)
    assert json.dumps(again.to_dict()) == json.dumps(small.to_dict())
    other = calibrate_fusion(np.random.default_rng(8), n_horizons=400)
    assert other.paper.mean_shortfall != small.paper.mean_shortfall


def test_safe_mode_never_over_estimates(small):
    assert small.safe.over_estimate_rate == 0.0
    assert (small.safe.over_estimate_rate_by_s == 0.0).all()
    assert small.safe.max_over_estimate <= 0.0
    assert (small.safe.mean_shortfall_by_s >= 0.0).all()


def test_paper_mode_over_estimates_on_random_horizons(small):
    assert 0.0 < small.paper.over_estimate_rate < 1.0
    assert small.paper.max_over_estimate > 0.0
    assert small.paper.p05_shortfall < 0.0  # the worst 5 % over-estimate


def test_result_shapes_and_ranges(small):
    m = GRID.size
    assert small.n_horizons == 400 and small.s_ahead_m.shape == (m,)
    assert small.nominal_coverage == NOMINAL_COVERAGE == 0.975
    for cal in (small.paper, small.safe):
        for name in ("over_estimate_rate_by_s", "mean_shortfall_by_s", "p05_shortfall_by_s",
                     "lower_coverage_by_s"):
            assert getattr(cal, name).shape == (m,)
        assert 0.0 <= cal.lower_coverage <= 1.0
        # The rate overall is the mean of the rates per distance (same horizons everywhere).
        assert cal.over_estimate_rate == pytest.approx(cal.over_estimate_rate_by_s.mean())
    assert 0.35 < small.local_present_share < 0.65
    assert 1.0 < small.class_changes_mean < 2.0


def _worst_wet_horizons(n: int) -> CalibrationHorizons:
    # The paper's adversarial turn: μ_gt = 0.4 on wet, the camera reports 0.5 (error +0.1, at its
    # margin) and the local estimate 0.425 (+0.025): every error within its declared margin.
    mu_gt = np.full((n, GRID.size), 0.4)
    return CalibrationHorizons(
        GRID, mu_gt, mu_gt + 0.1, np.full(mu_gt.shape, 0.1),
        np.where(np.arange(n) % 2 == 0, 0.4 + LOCAL_MAX_ERROR, np.nan), np.zeros(n, dtype=int),
    )


def test_paper_mode_over_estimates_on_the_worst_wet_layout():
    res = calibrate_horizons(_worst_wet_horizons(4))
    assert res.paper.over_estimate_rate == 1.0  # μ̂ > 0.4 everywhere, with or without local
    assert res.paper.max_over_estimate > 0.05
    assert res.safe.over_estimate_rate == 0.0
    assert res.safe.max_over_estimate == pytest.approx(0.0, abs=1e-12)  # tight: μ̂ = 0.4


def test_camera_emulation_equals_predictive_estimate_row_by_row():
    h = draw_horizons(np.random.default_rng(3), 30)
    for b in range(30):
        cam = predictive_estimate(
            GRID, h.mu_gt[b], error="random", rng=np.random.default_rng(100 + b)
        )
        n_segments = int(np.count_nonzero(np.diff(cam.class_index))) + 1
        unit = np.zeros((1, 4))
        unit[0, :n_segments] = np.random.default_rng(100 + b).uniform(-1.0, 1.0, n_segments)
        mu, margin = camera_random(h.mu_gt[b : b + 1], unit, PAPER_CLASSES)
        np.testing.assert_array_equal(mu[0], cam.mu)
        np.testing.assert_array_equal(margin[0], cam.margin)


def test_drawn_errors_lie_within_the_declared_margins():
    h = draw_horizons(np.random.default_rng(5), 2000)
    assert (np.abs(h.camera_mu - h.mu_gt) <= h.camera_margin + 1e-12).all()
    local = ~np.isnan(h.local_mu)
    assert (np.abs(h.local_mu[local] - h.mu_gt[local, 0]) <= LOCAL_MAX_ERROR).all()
    changes = (np.diff(h.camera_margin, axis=1) != 0).sum(axis=1)
    assert (changes <= h.n_changes).all() and set(np.unique(h.n_changes)) == {0, 1, 2, 3}


@pytest.mark.parametrize(
    ("match", "kwargs"),
    [
        ("rng", {"rng": 0}),
        ("rng", {"rng": np.random.RandomState(0)}),
        ("n_horizons", {"n_horizons": 0}),
        ("n_horizons", {"n_horizons": 10.0}),
        ("n_horizons", {"n_horizons": True}),
        ("prior", {"prior": "paper"}),
        ("classes", {"classes": []}),
    ],
)
def test_bad_inputs_raise(match, kwargs):
    args = {"rng": np.random.default_rng(0), "n_horizons": 5, **kwargs}
    rng = args.pop("rng")
    with pytest.raises(ValueError, match=match):
        calibrate_fusion(rng, **args)


def test_bad_horizons_raise():
    h = _worst_wet_horizons(2)
    with pytest.raises(ValueError, match="mu_gt"):
        CalibrationHorizons(GRID, np.zeros((2, GRID.size)), h.camera_mu, h.camera_margin,
                            h.local_mu, h.n_changes)
    with pytest.raises(ValueError, match="camera_mu"):
        CalibrationHorizons(GRID, h.mu_gt, h.camera_mu[:, :3], h.camera_margin, h.local_mu,
                            h.n_changes)
    with pytest.raises(ValueError, match="horizons"):
        calibrate_horizons("horizons")
    with pytest.raises(ValueError, match="mu must lie"):
        bad = CalibrationHorizons(GRID, h.mu_gt, h.camera_mu + 5.0, h.camera_margin,
                                  h.local_mu, h.n_changes)
        calibrate_horizons(bad, GPPrior(0.55, 0.2, 15.0))


def test_figure(small, tmp_path):
    fig = build_calibration_figure(small)
    assert len(fig.axes) == 2
    # The nominal level is drawn on the coverage panel.
    assert any(np.allclose(line.get_ydata(), 97.5) for line in fig.axes[1].get_lines())
    out = calibration_figure(small, tmp_path / "sub" / "cal.png")
    assert out.exists() and out.stat().st_size > 10_000
    with pytest.raises(ValueError, match="CalibrationResult"):
        build_calibration_figure({"paper": None})


def test_calibrate_command_writes_json_and_figure(tmp_path):
    result = CliRunner().invoke(
        app, ["calibrate", "--horizons", "300", "--seed", "2", "--out", str(tmp_path / "c")]
    )
    assert result.exit_code == 0, result.output
    payload = json.loads((tmp_path / "c" / "calibration.json").read_text())
    assert payload["command"] == {"horizons": 300, "seed": 2}
    assert payload["n_horizons"] == 300 and payload["safe"]["over_estimate_rate"] == 0.0
    assert (tmp_path / "c" / "calibration.png").exists()
    assert "over % paper" in result.output


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["--horizons", "0"], "--horizons"),
        (["--horizons", "many"], "--horizons"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_calibrate_command_rejects_bad_options(args, option, tmp_path):
    result = CliRunner().invoke(app, ["calibrate", *args, "--out", str(tmp_path / "c")])
    assert result.exit_code == 2
    assert option in result.output


def test_calibrate_command_rejects_a_file_as_out(tmp_path):
    target = tmp_path / "file.txt"
    target.write_text("x")
    result = CliRunner().invoke(app, ["calibrate", "--horizons", "5", "--out", str(target)])
    assert result.exit_code == 2
    assert "--out" in result.output
