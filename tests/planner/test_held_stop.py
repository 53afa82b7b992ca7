"""A stop at rest is held with the brakes on, not solved (docs/decisions/0098)."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.minimal_risk import AT_REST_MPS, HELD_AT_REST_MODES
from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import Input, State

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45)


class _CountingBackend:
    """Passes every solve and reset through to a real backend and counts them."""

    def __init__(self, inner) -> None:
        self.inner, self.solves, self.resets = inner, 0, 0

    @property
    def last_solve_retried(self) -> bool:
        return self.inner.last_solve_retried

    def solve(self, *args, **kwargs):
        self.solves += 1
        return self.inner.solve(*args, **kwargs)

    def reset(self) -> None:
        self.resets += 1
        self.inner.reset()


@pytest.fixture(scope="module")
def counted() -> tuple[TractionAdaptivePlanner, _CountingBackend]:
    backend = _CountingBackend(TractionAdaptivePlanner(TRUCK, CONFIG).backend)
    return TractionAdaptivePlanner(TRUCK, CONFIG, backend=backend), backend


def _straight(s):
    return 0.0 * np.asarray(s, dtype=float)


def _mu(s):
    return 0.6 + 0.0 * np.asarray(s, dtype=float)


def _step(planner, speed_mps: float, mode: str, t_s: float = 0.0):
    x0 = np.array([80.0, 0.1, 0.0, 0.0, speed_mps, 0.0])
    return planner.step(x0, t_s, _straight, _mu, [], mode, 0.0)


@pytest.mark.parametrize("mode", HELD_AT_REST_MODES)
def test_a_stop_at_rest_is_held_with_the_brakes_on_without_a_solve(counted, mode) -> None:
    planner, backend = counted
    planner.reset()
    solves, resets = backend.solves, backend.resets
    plans = [_step(planner, 0.5 * AT_REST_MPS, mode, 0.1 * i) for i in range(3)]
    assert backend.solves == solves
    # The solver is re-initialised once, when the hold begins, as the failed solves at rest did.
    assert backend.resets == resets + 1
    for plan in plans:
        assert plan.held and plan.ok and not plan.fallback
        assert plan.mode == mode and planner.consecutive_fallbacks == 0
        # Held where it is (what is left of 5 cm/s at the stop's deceleration: under a mm) ...
        assert np.ptp(plan.states[:, State.s]) < 1e-3
        assert np.all(plan.states[1:, State.vx] == 0.0)
        # ... with the brakes on at both axles, not steering.
        assert np.all(plan.inputs[:, Input.fxf] < 0.0) and np.all(plan.inputs[:, Input.fxr] < 0.0)
        assert np.all(plan.inputs[:, Input.fyf] == 0.0)


@pytest.mark.parametrize(("speed_mps", "mode"), [
    (0.5 * AT_REST_MPS, "cruise"),  # driving off from rest is planned
    (0.5 * AT_REST_MPS, "evade"),
    (3.0, "emergency"),  # a stop under way is planned
])
def test_everything_else_is_solved(counted, speed_mps, mode) -> None:
    planner, backend = counted
    planner.reset()
    solves = backend.solves
    plan = _step(planner, speed_mps, mode)
    assert backend.solves > solves and not plan.held


@pytest.mark.parametrize(("forces_n", "held"), [((-20000.0, -10000.0), True),
                                                 ((-2000.0, -1000.0), False)])
def test_a_stop_the_delivered_braking_ends_whatever_the_plan_is_held(counted, forces_n,
                                                                         held) -> None:
    # The truck at 0.2 m/s, braked by 30 kN (3.6 m/s²): even released at once (τ 0.15 s) the
    # brakes take 0.54 m/s off, so the OCP's speed would fall below its bound; braked by 3 kN
    # (0.05 m/s) it can still plan the stop's end.
    planner, backend = counted
    planner.reset()
    solves = backend.solves
    x0 = np.array([80.0, 0.1, 0.0, 0.0, 0.2, 0.0])
    plan = planner.step(x0, 0.0, _straight, _mu, [], "emergency", 0.0,
                        longitudinal_forces_n=forces_n)
    assert plan.held is held and (backend.solves == solves) is held and not plan.fallback
