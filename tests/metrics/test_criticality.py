"""Criticality measures from crafted logs against hand numbers (docs/metrics.md)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from factories import estimate_grid, run_meta, ticks
from mufusion.metrics import compute_metrics
from mufusion.metrics.criticality import (
    criticality,
    criticality_summary,
    required_deceleration_mps2,
    time_to_collision_s,
)
from mufusion.sim.log import RunLog
from mufusion.sim.records import ObstacleTrace

G = 9.81
N = 50  # ticks of 0.02 s: the last at 0.98 s
SPEED = 20.0
MU = 0.5
# The factory's truck: footprint front 6.28/2 + (1.2 − 2.2)/2 = 2.64 m ahead of the CoG.
FRONT_M = 2.64


def _obstacle(s_m: float, d_m: float = 0.0, speed_mps: float = 0.0, **kw) -> ObstacleTrace:
    return ObstacleTrace(s_m=s_m, d_m=d_m, length_m=2.0, width_m=2.0, appear_time_s=None,
                         corners_x_m=[0.0] * 4, corners_y_m=[0.0] * 4, speed_mps=speed_mps, **kw)


def _log(*obstacles: ObstacleTrace, mu_hat: float | None = None) -> RunLog:
    t = np.arange(N) * 0.02
    log = RunLog(run_meta(obstacles=list(obstacles)))
    log.extend(ticks(N, s_m=SPEED * t, vx_mps=SPEED, speed_mps=SPEED, mu_front=MU, mu_rear=0.8))
    if mu_hat is not None:
        log.append(estimate_grid(0, 0.0, mu_hat, MU))
    return log


def test_a_static_obstacle_ahead() -> None:
    summary = criticality_summary(_log(_obstacle(100.0), mu_hat=0.4))
    gap = 100.0 - 1.0 - FRONT_M - SPEED * 0.98  # at the last tick: 76.76 m
    assert summary["min_time_to_collision_s"] == pytest.approx(gap / SPEED)
    # Braking at λ μ g with the lower axle's μ (0.5): TTC − v / (2 · 0.9 · 0.5 · 9.81).
    assert summary["min_time_to_brake_s"] == pytest.approx(gap / SPEED - SPEED / (2 * 0.9 * MU * G))
    need = SPEED**2 / (2 * gap)
    assert summary["max_required_decel_mps2"] == pytest.approx(need)
    assert summary["max_required_decel_over_mu_g"] == pytest.approx(need / (MU * G))
    assert summary["max_required_decel_over_mu_hat_g"] == pytest.approx(need / (0.4 * G))


def test_a_lead_counts_its_speed_and_an_oncoming_one_has_no_time_to_brake() -> None:
    lead = criticality_summary(_log(_obstacle(100.0, speed_mps=15.0)))
    # Closing at 5 m/s; the lead moves 15 · 0.98 m while the vehicle moves 20 · 0.98 m.
    gap = 100.0 - 1.0 - FRONT_M - 5.0 * 0.98
    assert lead["min_time_to_collision_s"] == pytest.approx(gap / 5.0)
    assert lead["max_required_decel_mps2"] == pytest.approx(25.0 / (2 * gap))
    oncoming = criticality_summary(_log(_obstacle(200.0, speed_mps=-10.0)))
    gap = 200.0 - 1.0 - FRONT_M - 30.0 * 0.98
    assert oncoming["min_time_to_collision_s"] == pytest.approx(gap / 30.0)
    assert oncoming["min_time_to_brake_s"] is None  # braking does not avoid what keeps coming
    assert lead["max_required_decel_over_mu_hat_g"] is None  # no estimate logged


def test_obstacles_outside_the_path_behind_or_not_yet_there_do_not_count() -> None:
    beside = _obstacle(100.0, d_m=3.5, speed_mps=-15.0)  # opposing lane: 3.5 > (2.6 + 2) / 2
    behind = _obstacle(-20.0)
    later = _obstacle(100.0, appear_ego_s_m=50.0)  # the vehicle reaches 19.6 m only
    for ob in (beside, behind, later):
        assert criticality_summary(_log(ob))["min_time_to_collision_s"] is None
    assert criticality_summary(_log())["min_time_to_collision_s"] is None
    assert criticality(_log()) is None


def test_the_worst_obstacle_at_each_tick_and_the_summary_in_the_run_metrics() -> None:
    near, far = _obstacle(60.0), _obstacle(150.0)
    crit = criticality(_log(far, near))
    assert crit is not None
    expected = (60.0 - 1.0 - FRONT_M - SPEED * crit.t_s) / SPEED
    np.testing.assert_allclose(crit.time_to_collision_s, expected)
    metrics = compute_metrics(_log(far, near))
    assert metrics.min_time_to_collision_s == pytest.approx(expected.min())
    assert metrics.to_dict()["min_time_to_collision_s"] == pytest.approx(expected.min(), abs=1e-6)


def test_the_front_edge_decides_whether_the_obstacle_is_in_the_path() -> None:
    # The centre 1.5 m left of the obstacle's: in the path (1.5 < (2.6 + 2) / 2) heading along
    # the road; turned 0.3 rad away, the nose is at 1.5 + 2.64 sin 0.3 = 2.28 m, beyond
    # (2.6 cos 0.3 + 2) / 2 = 2.24 m: clear of it.
    def ttc(dpsi: float) -> float | None:
        t = np.arange(N) * 0.02
        log = RunLog(run_meta(obstacles=[_obstacle(100.0)]))
        log.extend(ticks(N, s_m=SPEED * t, d_m=1.5, dpsi_rad=dpsi, vx_mps=SPEED,
                         speed_mps=SPEED, mu_front=MU, mu_rear=MU))
        return criticality_summary(log)["min_time_to_collision_s"]

    assert ttc(0.0) is not None
    assert ttc(0.3) is None


def test_a_vanishing_closing_speed_or_gap_gives_inf_without_a_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert time_to_collision_s(np.array([30.0]), np.array([1e-310])).tolist() == [np.inf]
        assert required_deceleration_mps2(np.array([1e-310]), np.array([1e200])).tolist() == [
            np.inf]
