"""The futility check weighs the evasion's graze against braking in lane (docs/decisions/0126):
where every evasion comes up short, even with the most friction the estimates allow, braking in
lane is chosen only where it would meet the obstacle no wider than the evasion would."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.metrics import compute_metrics
from mufusion.planner import PlannerObstacle
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_loop
from mufusion.sim.events import EventKind
from mufusion.sim.lane_recovery import RecoveryOutcome
from mufusion.sim.plan_checks import planned_contact_width_m
from mufusion.sim.settings import LaneRecoverySettings
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import State

# A held-out pop-up (limits_popup_heldout6, feasible): the car at 29 m/s on μ 1.0, an obstacle
# 28 m ahead and 0.4 m left of the lane centre. A stop needs 43 m; GT passes it 0.45 m clear.
# F-safe's μ̂ is the dry class's lower bound, 0.6.
_POPUP = ["vehicle=car", "friction.mu=1.0", "initial_speed_mps=29", "obstacle.distance_m=28",
          "obstacle.lateral_offset_m=0.4", "duration_s=2.0"]


def _run(*extra: str):
    cfg = load_scenario("popup", [*_POPUP, *extra])
    loop = build_loop(cfg, friction="F-safe")
    return run_loop(loop, cfg.duration_s), loop


@pytest.mark.slow
def test_f_safe_keeps_the_evasion_that_comes_up_short_rather_than_braking_into_the_obstacle(
) -> None:
    weighed, loop = _run()
    braked, _ = _run("lane_recovery.futility_weighs_contact=false")
    w, b = compute_metrics(weighed), compute_metrics(braked)
    # Every evasion predicted a few centimetres short, braking in lane took off 2 m/s.
    assert b.collision and b.impact_speed_mps > 20.0
    assert (braked.events["kind"] == EventKind.FUTILE_EVASION).any()
    # Kept, the evasion with the most friction passes.
    assert not w.collision and w.min_clearance_m is not None and w.min_clearance_m > 0.0
    assert not w.off_road
    grazes = weighed.events[weighed.events["kind"] == EventKind.GRAZE_OVER_STOP]
    assert len(grazes) >= 1
    recoveries = loop.supervision.lane_recovery.recoveries
    assert [r.t_s for r in recoveries if r.outcome is RecoveryOutcome.GRAZE] == list(
        grazes["t_s"])


def test_the_contact_width_tells_a_graze_from_a_frontal_impact() -> None:
    ob = PlannerObstacle(s_m=30.0, d_m=0.4, length_m=4.0, width_m=1.8)
    x = np.zeros((4, 6))
    x[:, State.s] = [0.0, 10.0, 20.0, 30.0]
    frontal = planned_contact_width_m(x, [ob], TRUCK)
    assert frontal == pytest.approx(0.5 * TRUCK.width_m + 0.9 - 0.4)
    # Swerving left, the first contact is at the obstacle, its left edge (1.3 m) over the car's
    # right one: 5.5 cm of its width.
    x[:, State.d] = [0.0, 1.0, 2.0, 2.05]
    graze = planned_contact_width_m(x, [ob], CAR)
    assert graze == pytest.approx(1.3 - (2.05 - 0.5 * CAR.width_m))
    x[:, State.d] = [0.0, 1.0, 2.2, 2.5]
    assert planned_contact_width_m(x, [ob], CAR) == 0.0
    assert planned_contact_width_m(x, [], CAR) == 0.0
    x[2, State.s] = np.nan
    assert planned_contact_width_m(x, [ob], CAR) == np.inf


def test_futility_weighs_contact_must_be_a_bool() -> None:
    with pytest.raises(ValueError, match=r"lane_recovery\.futility_weighs_contact"):
        LaneRecoverySettings(futility_weighs_contact=1)  # type: ignore[arg-type]
