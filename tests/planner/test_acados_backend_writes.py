"""The acados backend writes the problem and the guess, and reads the plan, in one call each
through C compiled into the solver; the plans are bit for bit those of acados' own per-stage
setters and getters."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from mufusion.planner import acados_backend
from mufusion.planner.ocp import PlannerConfig, PlannerObstacle
from mufusion.planner.ocp_state import augmented_problem, plan_from_augmented
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_INPUTS, N_STATES

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=3.95)


def _solve_through_the_wrapper(self, x0, guess_x, guess_u, p, yref, weights, lbx, ubx, ubu,
                               lbu):
    """The reference: every stage and field through acados' wrapper's public set calls
    (the lower input bounds, as the one-call writer, only when they differ from the generated
    ones or did at the last solve)."""
    s, n = self.solver, self.n
    changed = not np.array_equal(lbu, self._generated_lbu)
    write_lbu = changed or self._lbu_changed
    self._lbu_changed = changed
    if self.layout.augmented:
        x0, guess_x, guess_u = augmented_problem(
            x0, guess_x, guess_u, p, self.params, self.config, self.layout)
    s.set(0, "lbx", x0)
    s.set(0, "ubx", x0)
    w_stage = np.diag(weights[: N_STATES + N_INPUTS])
    ubu = np.broadcast_to(ubu, (n, ubu.shape[-1]))  # one bound for all stages, or per stage
    for k in range(n):
        s.set(k, "x", guess_x[k])
        s.set(k, "u", guess_u[k])
        s.set(k, "p", p[k])
        s.cost_set(k, "yref", yref[k])
        s.cost_set(k, "W", w_stage)
        s.constraints_set(k, "ubu", ubu[k])
        if write_lbu:
            s.constraints_set(k, "lbu", lbu[k])
        if k > 0:
            s.constraints_set(k, "lbx", lbx[k - 1])
            s.constraints_set(k, "ubx", ubx[k - 1])
    s.set(n, "x", guess_x[n])
    s.set(n, "p", p[n - 1])
    s.cost_set(n, "yref", yref[n, :N_STATES])
    s.cost_set(n, "W", w_stage[:N_STATES, :N_STATES])
    s.constraints_set(n, "lbx", lbx[-1, :1])
    s.constraints_set(n, "ubx", ubx[-1, :1])
    status = s.solve()
    xs = np.array([s.get(k, "x") for k in range(n + 1)])
    us = np.array([s.get(k, "u") for k in range(n)])
    if self.layout.augmented:
        xs, us = plan_from_augmented(xs, us, self.layout)
    return int(status), xs, us


class Probe:
    """Wraps an acados backend and poisons the parameters of chosen solves (a NaN solve makes
    the planner reset it)."""

    def __init__(self, inner) -> None:
        self.inner = inner
        self.poison = False

    @property
    def last_solve_retried(self) -> bool:
        return self.inner.last_solve_retried

    def solve(self, x0, guess_x, guess_u, p, *args):
        if self.poison:
            p = np.full_like(p, np.nan)
        return self.inner.solve(x0, guess_x, guess_u, p, *args)

    def reset(self) -> None:
        self.inner.reset()


def _drive(probe: Probe, config: PlannerConfig) -> list:
    planner = TractionAdaptivePlanner(TRUCK, config, backend=probe)
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


# The product's problem (front-force state, polygons at the stages' own loads) and the paper's
# (neither: fewer states and constraint rows, another layout).
@pytest.mark.parametrize("product", [False, True], ids=["paper", "product"])
def test_one_call_writes_and_reads_give_the_plans_of_the_per_stage_setters(
    product: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = dataclasses.replace(CONFIG, steering_rate_limit=product, load_transfer=product)
    got = _drive(Probe(TractionAdaptivePlanner(TRUCK, config).backend), config)
    reference = TractionAdaptivePlanner(TRUCK, config).backend
    solved: list[int] = []

    def through_the_wrapper(solver, *args):
        solved.append(1)
        return _solve_through_the_wrapper(solver, *args)

    for solver in reference.solvers():  # each generated solver solves through the wrapper
        monkeypatch.setattr(solver, "solve", functools.partial(through_the_wrapper, solver))
    want = _drive(Probe(reference), config)
    assert len(solved) >= len(want)  # the reference path, not the one-call writes
    assert not want[17].ok and want[18].ok  # the poisoned solve, then a reset solver
    assert [p.mode for p in want] == [p.mode for p in got]
    for a, b in zip(want, got, strict=True):
        assert a.status == b.status and a.fallback_reason == b.fallback_reason
        assert np.array_equal(a.states, b.states) and np.array_equal(a.inputs, b.inputs)


@pytest.mark.parametrize("mode", [1.0, 2.0, 3.0])  # write, read, no such mode
def test_a_buffer_of_another_layout_is_refused_untouched(mode: float) -> None:
    # The problem, the guess and the plan cross in one call into the solver's own C; a buffer of
    # the wrong size must neither be written past, nor half written, nor pass for a plan.
    solver = TractionAdaptivePlanner(TRUCK, CONFIG).backend.solvers()[0]
    data = np.zeros(6)
    data[0] = mode
    with pytest.raises(RuntimeError, match="another layout"):
        solver._exchange(data)
    assert not data[1:].any()


def test_the_problem_hash_names_the_slack_penalties():
    """The soft constraints' penalties are generated into the solver, not written at each solve:
    a configuration that changes them must get its own generated code, not a cached solver
    with the old penalties (which would silently ignore the change)."""
    base = acados_backend.problem_hash(TRUCK, CONFIG)
    assert acados_backend.problem_hash(TRUCK, CONFIG) == base
    for field in ("slack_l1", "slack_l2"):
        weights = dataclasses.replace(CONFIG.weights, **{field: 2e4})
        changed = dataclasses.replace(CONFIG, weights=weights)
        assert acados_backend.problem_hash(TRUCK, changed) != base, field
    # The stage weights are written at each solve: they do not need new code.
    weights = dataclasses.replace(CONFIG.weights, speed=2.0)
    assert acados_backend.problem_hash(TRUCK, dataclasses.replace(CONFIG, weights=weights)) == base


def test_each_acados_install_gets_its_own_solvers(monkeypatch):
    """A compiled solver links the acados libraries of the install that built it; a cache
    shared by two installs (two virtual environments) must not hand one's solver to the other,
    which fails to load once the first install is gone."""
    monkeypatch.setenv("ACADOS_SOURCE_DIR", "/venv-a/lib/python3.11/site-packages/acados")
    first = acados_backend.problem_hash(TRUCK, CONFIG)
    assert acados_backend.problem_hash(TRUCK, CONFIG) == first
    monkeypatch.setenv("ACADOS_SOURCE_DIR", "/venv-b/lib/python3.11/site-packages/acados")
    assert acados_backend.problem_hash(TRUCK, CONFIG) != first


def test_an_edit_to_the_code_that_describes_the_problem_regenerates_the_solver(
        tmp_path, monkeypatch):
    """The hash covers the source of the problem's description and of every module it imports:
    an edit there (a constraint row, a solver option) must not load a solver generated from the
    code before it, which a manual format version missed once."""
    package = tmp_path / "mufusion_probe"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "describe.py").write_text("from mufusion_probe.rows import ROWS\n")
    (package / "rows.py").write_text("ROWS = 3\n")
    (package / "unrelated.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    digest = acados_backend.generator_source_digest.__wrapped__  # uncached
    before = digest("mufusion_probe.describe")
    assert digest("mufusion_probe.describe") == before
    (package / "unrelated.py").write_text("X = 2\n")  # not imported by the description
    assert digest("mufusion_probe.describe") == before
    (package / "rows.py").write_text("ROWS = 4\n")  # imported: its edit is seen
    assert digest("mufusion_probe.describe") != before
    # The product's own description reaches the dynamics and the polygons' rows.
    modules = acados_backend.generator_modules()
    assert {"mufusion.planner.acados_ocp", "mufusion.vehicle.planner_model",
            "mufusion.planner.ocp", "mufusion.planner.penalties"} <= modules
    base = acados_backend.problem_hash(TRUCK, CONFIG)
    monkeypatch.setattr(acados_backend, "generator_source_digest", lambda: "an edited description")
    assert acados_backend.problem_hash(TRUCK, CONFIG) != base
