"""F+shared and F-safe+shared: without reports they are F and F-safe; with reports the source
places them by the vehicle's position and fuses them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mufusion.configurations import make_estimator, step_source
from mufusion.estimators import make_sensor_model
from mufusion.estimators.comm import CommModel, Delivery, ReportInbox
from mufusion.estimators.shared import FrictionReport
from mufusion.scenarios import load_scenario
from mufusion.scenarios.shared_section import load_reports, scenario_inbox

GRID = np.arange(0.0, 51.0)
TRUE_MU = np.full(51, 0.5)


def _estimate(name, inbox=None, s_ego_m=100.0, t_s=5.0):
    source = make_estimator(name, inbox=inbox) if inbox is not None else make_estimator(name)
    sensors = make_sensor_model(local_error="worst_under")
    return step_source(source, sensors, GRID, TRUE_MU, 0.0, t_s=t_s, s_ego_m=s_ego_m)


@pytest.mark.parametrize(("shared", "base"), [("F+shared", "F"), ("F-safe+shared", "F-safe")])
def test_without_reports_a_shared_configuration_is_its_base(shared, base):
    a, b = _estimate(shared), _estimate(base)
    assert np.array_equal(a.mu_hat, b.mu_hat)
    empty = ReportInbox((), CommModel())
    assert np.array_equal(_estimate(shared, empty).mu_hat, b.mu_hat)


def test_reports_are_placed_by_the_vehicle_position():
    reports = tuple(
        Delivery(FrictionReport.numeric(100.0 + s, 0.5, 0.025, t_created_s=0.0,
                                        sender=f"v{int(s) % 2}"), 1.0)
        for s in np.arange(0.0, 51.0, 1.0)
    )
    inbox = ReportInbox(reports, CommModel())
    here = _estimate("F-safe+shared", inbox, s_ego_m=100.0).mu_hat
    elsewhere = _estimate("F-safe+shared", inbox, s_ego_m=1000.0).mu_hat
    base = _estimate("F-safe").mu_hat
    assert np.array_equal(elsewhere, base)
    assert (here > base + 0.02).sum() > 20
    assert (here <= 0.5 + 1e-12).all()
    # Without a position (a frame whose localisation is missing) no report is placed.
    sensors = make_sensor_model(local_error="worst_under")
    unplaced = step_source(make_estimator("F-safe+shared", inbox=inbox), sensors, GRID, TRUE_MU,
                           0.0, t_s=5.0).mu_hat
    assert np.array_equal(unplaced, base)


def test_inbox_rejected_by_a_configuration_without_reports():
    with pytest.raises(ValueError, match="reads no shared reports"):
        make_estimator("F-safe", inbox=ReportInbox((), CommModel()))


def test_reports_file_is_read_and_bad_entries_named(tmp_path):
    good = tmp_path / "r.json"
    good.write_text(json.dumps([{"s_m": 70.0, "mu": 0.5, "lower_mu": 0.47, "upper_mu": 0.53}]))
    assert load_reports(good)[0].lower_mu == 0.47
    cfg = load_scenario("turn", [f"shared.reports_file={good}", "shared.loss=0.0"])
    inbox = scenario_inbox(cfg.shared, cfg.seed)
    assert inbox is not None and len(inbox.at(10.0)) == 1
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps([{"s_m": 70.0, "mu": 0.5, "lower_mu": 0.6, "upper_mu": 0.53}]))
    with pytest.raises(ValueError, match="report 0"):
        load_reports(bad)
