"""The fleet: each vehicle's local estimates reach those behind it as reports; without a shared
configuration the vehicles ignore them; the command refuses bad input before any work."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from mufusion.campaign.fleet_study import report_markdown, summarise
from mufusion.cli import app
from mufusion.plots.fleet import build_band_figure, build_first_last_figure
from mufusion.scenarios import load_scenario
from mufusion.scenarios.fleet import reports_from_log, run_fleet
from mufusion.scenarios.runner import run_scenario

OVERRIDES = ["vehicle=car", "duration_s=4", "friction.mu_turn=0.5", "shared.loss=0.0"]


@pytest.fixture(scope="module")
def fleet():
    cfg = load_scenario("turn", OVERRIDES)
    seen = []
    logs = run_fleet(cfg, "F-safe+shared", 3, on_vehicle=lambda k, log, inbox: seen.append(inbox))
    return cfg, logs, seen


def test_the_first_vehicle_gets_nothing_and_the_second_its_estimates(fleet):
    cfg, logs, inboxes = fleet
    assert inboxes[0] is None or not inboxes[0].deliveries
    own = reports_from_log(logs[0], sender="vehicle-1", position_std_m=0.5)
    assert own, "vehicle 1 measured somewhere (its probe)"
    got = inboxes[1].at(cfg.duration_s)
    assert got and {r.sender for r in got} == {"vehicle-1"}
    # Vehicle 1's times on vehicle 2's clock: one fleet delay earlier.
    assert max(r.t_created_s for r in got) <= cfg.duration_s - cfg.shared.fleet_delay_s + 1e-9


def test_no_vehicle_plans_above_the_true_friction_and_the_third_gains(fleet):
    """Vehicle 3 has two senders ahead to vouch for a bound (decision 0063's corroboration)."""
    _, logs, _ = fleet
    for log in logs:
        assert not (log.estimates["mu_hat"] > log.estimates["mu_true"] + 1e-9).any()
    assert logs[2].estimates["mu_hat"].mean() > logs[0].estimates["mu_hat"].mean() + 0.005


def test_a_baseline_fleet_is_the_plain_run(fleet):
    cfg = load_scenario("turn", OVERRIDES)
    (log,) = run_fleet(cfg, "F-safe", 1)
    plain = run_scenario(cfg, "F-safe")
    assert np.array_equal(log.estimates["mu_hat"], plain.estimates["mu_hat"])


def test_fleet_figures_build(fleet):
    _, logs, inboxes = fleet
    assert build_band_figure(logs[1], 0.0, inboxes[1].at(0.0)).axes
    assert len(build_first_last_figure(logs[0], logs[1], 0.0).axes) == 3


@pytest.mark.parametrize(("args", "message"), [
    (["fleet", "turn", "--vehicles", "0"], "--vehicles must lie in [1, 50]"),
    (["fleet", "turn", "--config", "F_safe"], "--config must be one of"),
    (["fleet", "turn", "--set", "shared.tau_s=0"], "tau_s"),
])
def test_fleet_command_refuses_bad_input(args, message, tmp_path):
    result = CliRunner().invoke(app, [*args, "-o", str(tmp_path / "f")])
    assert result.exit_code == 2
    assert message in result.output


def test_study_summary_counts_and_closes_gaps():
    def facts(util, over=False):
        return {"kept_lane": True, "planned_above_mu": over, "horizon_over_share": 0.0,
                "util": util, "probed": True, "mean_mu_hat": 0.4}
    row = {"vehicle": "car", "seed": 0, "GT": facts(0.4), "F": facts(0.35), "F-safe": facts(0.3)}
    for fam in ("F+shared", "F-safe+shared"):
        for cond, u in (("fresh", 0.36), ("old", 0.3), ("wrong", 0.34)):
            row[f"{fam} {cond}"] = facts(u)
    s = summarise([row])
    assert s["car F-safe+shared fresh"]["closure_median"] == pytest.approx(0.6)
    assert s["car F-safe+shared fresh"]["closure_at_least_half"]["successes"] == 1
    assert s["car F-safe+shared wrong"]["closure_at_least_half"]["successes"] == 0
    assert s["car F-safe+shared old"]["not_worse_than_baseline"]["rate"] == 1.0
    table = report_markdown(s).splitlines()
    assert len(table) == 2 + len(s)
    fresh = next(line for line in table if line.startswith("| car F-safe+shared fresh |"))
    assert "| 0.60 | 1/1 [" in fresh
    wrong = next(line for line in table if line.startswith("| car F-safe+shared wrong |"))
    assert "| 0.40 | 0/1 [0.00, " in wrong


def test_fleet_command_writes_logs_summary_and_figures(tmp_path):
    sets = [a for o in OVERRIDES for a in ("--set", o)]
    result = CliRunner().invoke(app, ["fleet", "turn", "--vehicles", "2", *sets, "-o",
                                      str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "vehicle-2" / "log").is_dir()
    assert (tmp_path / "band_last.png").stat().st_size > 0
    assert (tmp_path / "first_vs_last.png").stat().st_size > 0
    rows = json.loads((tmp_path / "summary.json").read_text())
    assert rows[0]["reports_received"] == 0
    assert rows[1]["reports_received"] > 0
