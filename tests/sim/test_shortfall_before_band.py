"""Evading, lane recovery ranks the candidates short of the obstacle margin by how short they are
before their violation of the band within its tolerance (``lane_recovery.shortfall_before_band``,
docs/decisions/0127): the search no longer keeps the least relaxed evasion, the furthest short,
because a swerve with more friction puts a corner a centimetre further out."""

from __future__ import annotations

import numpy as np
import pytest

from factories import straight_plan
from mufusion.configurations import FrictionEstimate
from mufusion.fusion import FusedEstimate
from mufusion.metrics import compute_metrics
from mufusion.planner import Plan, PlannerObstacle
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_loop
from mufusion.sim.lane_recovery import LaneRecovery, RecoveryOutcome
from mufusion.sim.settings import LaneRecoverySettings
from mufusion.sim.supervisor import PlanningContext
from mufusion.vehicle.params import CAR
from mufusion.vehicle.planner_model import State

GRID = np.arange(0.0, 51.0)
LANE_M = (-1.0, 1.0)
# Its left edge on the lane centre, beside the plans' stages 8-12; the plans keep d constant,
# so a plan at d passes it ``d − w/2`` clear: short of the 0.25 m (half the 0.5 m margin) by
# 1.055 − d for the car.
OBSTACLE = PlannerObstacle(s_m=10.0, d_m=-0.5, length_m=2.0, width_m=1.0)


def _plan(d_m: float) -> Plan:
    plan = straight_plan(0.0, mode="evade")
    plan.states[:, State.d] = d_m
    return plan


def _review(shortfall_first: bool, record=None) -> tuple[LaneRecovery, list[float], Plan]:
    """One evading step: the friction-limited plan (μ̂ 0.1) passes at d = 0.90, in its band but
    0.155 m short of the margin; each relaxed one swerves further, d = 1.01 … 1.04, 1–4 cm
    beyond the band (within the 5 cm tolerance) and 4.5–1.5 cm short."""
    asked: list[float] = []

    class Planner:
        memory: object = None

        def restore(self, memory: object) -> None:
            self.memory = memory

    def plan(estimate: FrictionEstimate, mode: str) -> Plan:
        mu = float(estimate.mu_hat[0])
        asked.append(round(mu, 6))
        return _plan(1.01 + 0.2 * (mu - 0.15))

    recovery = LaneRecovery(LaneRecoverySettings(shortfall_before_band=shortfall_first),
                            Planner(), CAR, LANE_M, lambda s: np.zeros_like(s),
                            lambda *a: None, obstacle_margin_m=0.5, record=record)
    ctx = PlanningContext(0.0, np.array([0.0, 0.0, 0.0, 0.0, 10.0, 0.0]), [OBSTACLE], False,
                          "evade", plan, lambda e: "evade")
    post = FusedEstimate(GRID, np.full(51, 0.3), np.full(51, 0.05), np.full(51, 0.1),
                         np.full(51, 0.1))
    estimate = FrictionEstimate(GRID, np.full(51, 0.1), False, None, fused=post)
    adopted, _ = recovery.review(ctx, "evade", estimate, _plan(0.9))
    return recovery, asked, adopted


def test_the_less_short_candidate_ranks_first_among_those_within_the_bands_tolerance() -> None:
    recovery, asked, adopted = _review(True)
    assert asked == pytest.approx([0.15, 0.2, 0.25, 0.3])  # every one is short: searched on
    assert recovery.recoveries[-1].outcome is RecoveryOutcome.RELAXED
    assert recovery.recoveries[-1].alpha == 1.0
    assert float(adopted.states[-1, State.d]) == pytest.approx(1.04)


def test_each_plan_weighed_is_logged_with_what_its_ranking_read() -> None:
    logged: list = []
    _review(True, logged.append)
    # The plan reviewed (no relaxation held), then the four candidates in the order planned.
    assert [r.alpha for r in logged] == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert [round(r.violation_m, 6) for r in logged] == [0.0, 0.01, 0.02, 0.03, 0.04]
    assert [round(r.shortfall_m, 6) for r in logged] == [0.155, 0.045, 0.035, 0.025, 0.015]
    assert not any(r.hits or r.fallback for r in logged)
    assert {r.t_s for r in logged} == {0.0}


def test_ranked_by_the_band_first_the_furthest_short_plan_was_kept() -> None:
    recovery, asked, adopted = _review(False)
    assert asked == pytest.approx([0.15, 0.2, 0.25, 0.3])
    assert recovery.recoveries[-1].outcome is RecoveryOutcome.DID_NOT_HELP
    assert float(adopted.states[-1, State.d]) == pytest.approx(0.9)


@pytest.mark.slow
def test_f_safe_clears_an_edge_draws_obstacle_it_hit_when_the_band_ranked_first() -> None:
    # `limit_edge_draw.py popup --seed 15`, feasible: the car at 30.6 m/s on μ 0.78, the
    # obstacle 32 m ahead and 0.5 m left. GT passes it 0.33 m clear.
    overrides = ["vehicle=car", "friction.mu=0.78", "initial_speed_mps=30.6",
                 "obstacle.distance_m=32", "obstacle.lateral_offset_m=0.5", "duration_s=2.5"]
    runs, logs = {}, {}
    for first in (True, False):
        cfg = load_scenario(
            "popup", [*overrides, f"lane_recovery.shortfall_before_band={str(first).lower()}"])
        log = run_loop(build_loop(cfg, friction="F-safe"), cfg.duration_s)
        runs[first], logs[first] = compute_metrics(log), log.frame("recovery_candidates")
    assert runs[False].collision and runs[False].impact_speed_mps > 20.0
    assert not runs[True].collision and runs[True].min_clearance_m > 0.03
    assert not runs[True].off_road
    # The run log holds every plan lane recovery weighed: at the evading steps the plan
    # reviewed and its relaxed candidates, some short of the margin.
    assert not logs[True].empty and (logs[True]["alpha"] == 0.0).any()
    assert (logs[True]["alpha"] > 0.0).any() and (logs[True]["shortfall_m"] > 0.0).any()


def test_shortfall_before_band_must_be_a_bool() -> None:
    with pytest.raises(ValueError, match=r"lane_recovery\.shortfall_before_band"):
        LaneRecoverySettings(shortfall_before_band="yes")  # type: ignore[arg-type]
