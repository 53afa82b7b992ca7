"""Lane recovery's search while evading: the most relaxed candidate first
(``lane_recovery.evade_top_first``, docs/decisions/0091) ends the search after one solve where
nothing helps, and adopts the same relaxation as the ascending search where something does."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from factories import straight_plan
from mufusion.configurations import FrictionEstimate
from mufusion.fusion import FusedEstimate
from mufusion.planner import Plan
from mufusion.sim.lane_recovery import LaneRecovery, RecoveryOutcome
from mufusion.sim.settings import LaneRecoverySettings
from mufusion.sim.supervisor import PlanningContext
from mufusion.vehicle.params import CAR
from mufusion.vehicle.planner_model import State

GRID = np.arange(0.0, 51.0)
N = 20
LANE_M = (-1.0, 1.0)


def _estimate() -> FrictionEstimate:
    """μ̂ 0.1 ahead, posterior mean 0.3: relaxed by α, μ̂ is 0.1 + 0.2 α."""
    post = FusedEstimate(GRID, np.full(51, 0.3), np.full(51, 0.05), np.full(51, 0.1),
                         np.full(51, 0.1))
    return FrictionEstimate(GRID, np.full(51, 0.1), False, None, fused=post)


def _plan(d_m: float) -> Plan:
    """A straight plan at 10 m/s whose reference point ends at ``d_m`` off the lane centre."""
    return straight_plan(d_m, n=N, mode="evade")


@dataclass
class _Planner:
    """What lane recovery needs of a planner: a memory it can take and restore."""

    memory: object = None
    restored: list[object] = field(default_factory=list)

    def restore(self, memory: object) -> None:
        self.restored.append(memory)
        self.memory = memory


def _recover(top_first: bool, d_of_mu: object) -> tuple[LaneRecovery, list[float], Plan,
                                                           FrictionEstimate, _Planner]:
    """One evading step whose friction-limited plan ends 2 m out; ``d_of_mu(μ̂)`` places each
    candidate. Returns the supervisor, the μ̂ of each candidate planned, the plan adopted and
    its estimate, and the planner (whose memory names the plan it continues)."""
    planner = _Planner(memory="friction-limited")
    asked: list[float] = []

    def plan(estimate: FrictionEstimate, mode: str) -> Plan:
        mu = float(estimate.mu_hat[0])
        asked.append(mu)
        planner.memory = f"μ̂ {mu:.2f}"
        return _plan(d_of_mu(mu))  # type: ignore[operator]

    recovery = LaneRecovery(LaneRecoverySettings(evade_top_first=top_first), planner,
                            CAR, LANE_M, lambda s: np.zeros_like(s), lambda *a: None)
    ctx = PlanningContext(0.0, np.array([0.0, 0.0, 0.0, 0.0, 10.0, 0.0]), [], False, "evade",
                          plan, lambda e: "evade")
    estimate = _estimate()
    adopted, adopted_estimate = recovery.review(ctx, "evade", estimate, _plan(3.0))
    return recovery, asked, adopted, adopted_estimate, planner


def test_where_no_relaxation_helps_the_top_first_search_plans_only_the_top() -> None:
    def same(mu: float) -> float:
        return 3.0

    for top_first, asked_for in ((False, [0.15, 0.2, 0.25, 0.3]), (True, [0.3] * 2)):
        recovery, asked, adopted, estimate, planner = _recover(top_first, same)
        # Top first: its RTI iterations (TOP_FIRST_ITERATIONS), not one per step.
        assert asked == pytest.approx(asked_for)
        assert recovery.recoveries[-1].outcome is RecoveryOutcome.DID_NOT_HELP
        assert float(adopted.states[-1, State.d]) == 3.0
        np.testing.assert_allclose(estimate.mu_hat, 0.1)
        assert planner.memory == "friction-limited"  # the next step continues the plan driven


def test_where_a_relaxation_helps_both_searches_adopt_the_smallest_that_keeps_the_lane() -> None:
    def keeps_from_half(mu: float) -> float:  # in lane from μ̂ 0.2 (α 0.5) on
        return 0.0 if mu >= 0.2 - 1e-9 else 3.0

    ascending = _recover(False, keeps_from_half)
    top_first = _recover(True, keeps_from_half)
    assert ascending[1] == pytest.approx([0.15, 0.2])
    # The top first, then from the friction-limited plan again in increasing order.
    assert top_first[1] == pytest.approx([0.3, 0.15, 0.2])
    assert top_first[4].restored[0] == "friction-limited"
    for recovery, _, adopted, estimate, planner in (ascending, top_first):
        assert recovery.recoveries[-1].outcome is RecoveryOutcome.RELAXED
        assert recovery.recoveries[-1].alpha == 0.5
        np.testing.assert_allclose(estimate.mu_hat, 0.2)
        assert float(adopted.states[-1, State.d]) == 0.0
        assert planner.memory == "μ̂ 0.20"


def test_where_only_the_top_keeps_the_lane_it_is_adopted_without_planning_it_twice() -> None:
    def keeps_at_top(mu: float) -> float:  # the smaller ones leave less far, but leave
        return 0.0 if mu >= 0.3 - 1e-9 else 3.0 - 5.0 * (mu - 0.1)

    recovery, asked, adopted, estimate, planner = _recover(True, keeps_at_top)
    assert asked == pytest.approx([0.3, 0.15, 0.2, 0.25])
    assert float(adopted.states[-1, State.d]) == 0.0
    assert recovery.recoveries[-1].alpha == 1.0
    np.testing.assert_allclose(estimate.mu_hat, 0.3)
    assert planner.memory == "μ̂ 0.30"


def test_evade_top_first_must_be_a_bool() -> None:
    with pytest.raises(ValueError, match=r"lane_recovery\.evade_top_first"):
        LaneRecoverySettings(evade_top_first="yes")  # type: ignore[arg-type]
