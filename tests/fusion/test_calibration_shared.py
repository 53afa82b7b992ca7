"""Calibration with shared reports: safe mode never over-estimates with honest fresh reports,
which raise its μ̂ on average; the command writes its cells."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from mufusion.cli import app
from mufusion.fusion.calibration_shared import calibrate_shared


def test_fresh_honest_reports_keep_safe_mode_safe_and_raise_its_estimate():
    cells = calibrate_shared(np.random.default_rng(1), 12, ages_s=[0.0, 1e5],
                             wrong_shares=[0.0])
    fresh_safe = next(c for c in cells if c.mode == "safe" and c.age_s == 0.0)
    old_safe = next(c for c in cells if c.mode == "safe" and c.age_s == 1e5)
    assert fresh_safe.over_estimate_rate == 0.0
    assert fresh_safe.mean_mu_hat > fresh_safe.mean_mu_hat_without + 0.02
    # Reports far older than τ have aged to the prior (or expired): nothing changes.
    assert old_safe.mean_mu_hat == pytest.approx(old_safe.mean_mu_hat_without, abs=1e-9)


def test_calibrate_shared_command_writes_cells(tmp_path):
    result = CliRunner().invoke(app, ["calibrate", "--shared", "--horizons", "2", "-o",
                                      str(tmp_path)])
    assert result.exit_code == 0, result.output
    cells = json.loads((tmp_path / "calibration_shared.json").read_text())["cells"]
    assert {c["mode"] for c in cells} == {"paper", "safe"}
    assert len(cells) == 2 * 6 * 2
