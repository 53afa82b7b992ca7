"""A stop the stop-or-evade rule chooses because the road is blocked, where μ̂ grants none: the
vehicle brakes with μ̂ relaxed towards the posterior mean (docs/decisions/0095)."""

from __future__ import annotations

import pytest

from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_loop
from mufusion.sim.events import EventKind

# The truck at 9 m/s on μ 0.2, a 2 m wide obstacle 36 m ahead, 1.3 m left of the lane centre:
# neither side has room, so the rule stops (oracle: feasible; GT stops 10 m short). F-safe's
# μ̂ is the lowest class's minimum, 0.1: braking with it (0.09 g where the stop needs 0.12 g)
# loads the tires to 0.45 of the road's friction, under the slip estimator's 0.5, so nothing
# ever measured the road and the truck hit at 4.9 m/s.
_BLOCKED = ["vehicle=truck", "obstacle.width_m=2.0", "friction.mu=0.2", "initial_speed_mps=9",
            "obstacle.distance_m=36", "obstacle.lateral_offset_m=1.3"]


def _run(*extra: str):
    cfg = load_scenario("popup", [*_BLOCKED, *extra])
    return run_loop(build_loop(cfg, friction="F-safe"), cfg.duration_s)


@pytest.mark.slow
def test_a_blocked_road_is_stopped_for_with_the_friction_the_estimates_support() -> None:
    relaxed, plain = _run(), _run("lane_recovery.enabled=false")
    r, p = compute_metrics(relaxed), compute_metrics(plain)
    assert p.collision and p.impact_speed_mps > 3.0
    assert not r.collision and not r.left_lane
    assert float(relaxed.timeseries["clearance_m"].min()) > 1.0
    # It braked in lane from the start, and the braking reached the slip estimator.
    steps = relaxed.planning_steps
    assert (steps["mode"] == "emergency").all()
    assert steps["local_available"].any() and not plain.planning_steps["local_available"].any()
    blocked = relaxed.events[relaxed.events["kind"] == EventKind.LANE_RECOVERY]
    assert len(blocked) >= 1 and float(blocked["t_s"].iloc[0]) == 0.0
    assert blocked["detail"].str.startswith("the road is blocked").all()


@pytest.mark.slow
def test_where_nothing_the_estimates_vouch_for_stops_in_time_it_brakes_at_the_upper_edge(
) -> None:
    # The truck at 12 m/s on μ 0.3 in a 3.0 m lane, a 1 m obstacle 32 m ahead, 0.9 m left: the
    # road is blocked (oracle: marginal; GT stops 1.4 m short at λ μ). F-safe's local estimate
    # reports 0.275, so all it vouches for is 0.25 (μ_l − m_l): relaxed that far it still hit,
    # at 4.2 m/s. The posterior's upper edge is above the truth; the slip control holds the
    # wheels at the road's limit, and the truck stops short.
    cfg = load_scenario("popup", ["vehicle=truck", "road.lane_width_m=3.0", "friction.mu=0.3",
                                  "initial_speed_mps=12", "obstacle.distance_m=32",
                                  "obstacle.lateral_offset_m=0.9"])
    log = run_loop(build_loop(cfg, friction="F-safe"), cfg.duration_s)
    m = compute_metrics(log)
    assert not m.collision and m.final_speed_mps < 0.5
    assert (log.planning_steps["mode"] == "emergency").all()
    details = log.events.loc[log.events["kind"] == EventKind.LANE_RECOVERY, "detail"]
    assert details.str.contains("upper 95 % edge").any()
