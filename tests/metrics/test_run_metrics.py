"""Metrics from crafted logs: each metric reacts to exactly the rows that should move it."""

from __future__ import annotations

import numpy as np
import pytest

from factories import plan_stages, planning_step, run_meta, ticks
from mufusion.metrics import attach_gt_comparison, compute_metrics
from mufusion.sim.log import RunLog, load_run


def _log(n: int = 50, **overrides) -> RunLog:
    t = np.arange(n) * 0.02
    cols = {"speed_mps": np.linspace(20.0, 15.0, n), "s_m": 20.0 * t, **overrides}
    log = RunLog(run_meta(comparison_time_s=0.5))
    log.extend(ticks(n, **cols))
    return log


def _plan(log: RunLog, step: int, t: float, fyf: float, fzf: float = 50e3, mu_true: float = 1.0):
    log.append(plan_stages(step, t, fyf_n=fyf, fzf_n=fzf, fzr_n=30e3, mu_true=mu_true))


def test_quiet_run_has_no_events() -> None:
    m = compute_metrics(_log())
    assert not m.collision and m.impact_speed_mps is None
    assert m.min_clearance_m is None
    assert not m.left_lane and not m.entered_opposing_lane
    assert m.max_abs_lateral_offset_m == 0.0


def test_collision_reports_speed_at_first_contact() -> None:
    hit = np.zeros(50, bool)
    hit[30:] = True
    m = compute_metrics(_log(in_collision=hit))
    assert m.collision
    assert m.impact_speed_mps == pytest.approx(np.linspace(20.0, 15.0, 50)[30])
    assert m.min_clearance_m is None


def test_clearance_only_counts_once_passed() -> None:
    clearance = np.linspace(3.0, 0.4, 50)
    not_passed = compute_metrics(_log(clearance_m=clearance))
    assert not_passed.min_clearance_m is None
    passed = np.zeros(50, bool)
    passed[-5:] = True
    m = compute_metrics(_log(clearance_m=clearance, passed_obstacle=passed))
    assert m.min_clearance_m == pytest.approx(0.4)


def test_lane_flags_and_offset() -> None:
    d = np.zeros(50)
    d[20] = -2.5
    margin = np.full(50, 0.45)
    margin[20:23] = [-0.2, -0.05, 0.1]
    opposing = np.zeros(50)
    opposing[21] = 0.03
    m = compute_metrics(_log(d_m=d, lane_margin_m=margin, opposing_depth_m=opposing))
    assert m.max_abs_lateral_offset_m == 2.5
    assert m.left_lane and m.entered_opposing_lane
    # Graded: 20 cm deepest, two ticks (0.04 s) outside, 3 cm into the opposing lane.
    assert m.max_lane_excursion_m == pytest.approx(0.2)
    assert m.min_lane_margin_m == pytest.approx(-0.2)
    assert m.time_outside_lane_s == pytest.approx(2 * 0.02)
    assert m.max_opposing_lane_depth_m == pytest.approx(0.03)
    inside = compute_metrics(_log(lane_margin_m=np.linspace(0.4, 0.01, 50)))
    assert not inside.left_lane and inside.max_lane_excursion_m == 0.0
    assert inside.min_lane_margin_m == pytest.approx(0.01)


def test_spin_and_body_slip() -> None:
    slip = np.zeros(50)
    slip[30] = 0.3
    calm = compute_metrics(_log(body_slip_rad=slip))
    assert calm.max_body_slip_rad == pytest.approx(0.3) and not calm.spun
    slip[31] = -0.5
    assert compute_metrics(_log(body_slip_rad=slip)).spun
    # Near standstill a large angle means nothing.
    slow = compute_metrics(_log(body_slip_rad=slip, speed_mps=np.full(50, 1.0)))
    assert slow.max_body_slip_rad == 0.0 and not slow.spun


def test_utilization_vs_gt_and_force_excess() -> None:
    gt, p = _log(), _log()
    _plan(gt, 0, 0.0, fyf=10e3)
    _plan(gt, 5, 0.5, fyf=45e3)
    _plan(p, 5, 0.5, fyf=27e3, mu_true=0.5)
    m_gt, m_p = compute_metrics(gt), compute_metrics(p)
    assert m_gt.planned_utilization_at_comparison == pytest.approx(0.9)
    assert attach_gt_comparison(m_p, m_gt).utilization_vs_gt == pytest.approx(27 / 45 - 1)
    assert m_gt.max_force_excess == 0.0
    assert m_p.max_force_excess == pytest.approx(27e3 / 25e3 - 1)


def test_empty_log_is_an_error() -> None:
    with pytest.raises(ValueError, match="timeseries"):
        compute_metrics(RunLog(run_meta()))


def test_log_round_trip(tmp_path) -> None:
    log = _log()
    _plan(log, 0, 0.0, fyf=1e3)
    log.append(planning_step(step=0, t_s=0.0, sampled_reinit=True))
    back = load_run(log.save(tmp_path / "run"))
    assert back.meta == log.meta
    np.testing.assert_allclose(back.timeseries["speed_mps"], log.timeseries["speed_mps"])
    assert len(back.plans) == 4
    assert compute_metrics(back).to_dict() == compute_metrics(log).to_dict()


def test_load_run_rejects_foreign_directory(tmp_path) -> None:
    with pytest.raises(ValueError, match=r"meta\.json"):
        load_run(tmp_path)
