"""The acados backend writes only the problem data that changed; the plans stay bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.ocp import PlannerConfig, PlannerObstacle
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.vehicle.params import TRUCK

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=3.95)


class Probe:
    """Wraps an acados backend: optionally forgets what it wrote (so it writes everything),
    and poisons the parameters of chosen solves (a NaN solve makes the planner reset it)."""

    def __init__(self, inner, write_all: bool) -> None:
        self.inner, self.write_all = inner, write_all
        self.poison = False

    @property
    def last_solve_retried(self) -> bool:
        return self.inner.last_solve_retried

    def solve(self, x0, guess_x, guess_u, p, *args):
        if self.write_all:
            for generated in self.inner.solvers():
                generated._written.clear()
        if self.poison:
            p = np.full_like(p, np.nan)
        return self.inner.solve(x0, guess_x, guess_u, p, *args)

    def reset(self) -> None:
        self.inner.reset()


def _drive(probe: Probe) -> list:
    planner = TractionAdaptivePlanner(TRUCK, CONFIG, backend=probe)
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    plans = []
    for i in range(24):
        kappa = 0.0 if i < 5 else 1.0 / 60.0

        def curvature(s, kappa=kappa):
            return kappa + 0.0 * np.asarray(s, dtype=float)

        def mu_hat(s, i=i):
            s = np.asarray(s, dtype=float)
            return np.where(s > 30.0 + 5.0 * i, 0.4, 0.8) if i < 8 else 0.6 + 0.0 * s

        obstacles = [PlannerObstacle(x[0] + 35.0, 0.0, 4.0, 2.0)] if 10 <= i < 16 else []
        mode = "evade" if obstacles else "emergency" if i >= 20 else "cruise"
        probe.poison = i == 17
        plan = planner.step(x, 0.1 * i, curvature, mu_hat, obstacles, mode, 15.0)
        plans.append(plan)
        x = plan.states[1]
    return plans


def test_writing_only_changed_stages_gives_the_same_plans_as_writing_all() -> None:
    reference = TractionAdaptivePlanner(TRUCK, CONFIG).backend
    cached = TractionAdaptivePlanner(TRUCK, CONFIG).backend
    want = _drive(Probe(reference, write_all=True))
    got = _drive(Probe(cached, write_all=False))
    assert not want[17].ok and want[18].ok  # the poisoned solve, then a reset solver
    assert [p.mode for p in want] == [p.mode for p in got]
    for a, b in zip(want, got, strict=True):
        assert a.status == b.status and a.fallback_reason == b.fallback_reason
        assert np.array_equal(a.states, b.states) and np.array_equal(a.inputs, b.inputs)


def test_an_iterate_of_another_layout_is_refused_not_read_past() -> None:
    # The guess and the plan cross in one call into the solver's own C; a buffer of the wrong
    # size must neither be written past nor pass for a plan.
    solver = TractionAdaptivePlanner(TRUCK, CONFIG).backend.solvers()[0]
    for mode in (1.0, 2.0):
        data = np.zeros(6)
        data[0] = mode
        with pytest.raises(RuntimeError, match="another layout"):
            solver._iterate(data)
        assert data[0] == mode and not data[1:].any()
