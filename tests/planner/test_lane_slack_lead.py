"""The corridor's slack priced by stage (``PlannerConfig.lane_slack_lead``, 1 by default:
measured, not adopted, docs/decisions/0089): both backends price the first stages' excursions
higher, so a plan that cannot keep the corridor leaves it later."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.penalties import corridor_slack_scale
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import planner_config
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import State
from ocp_problems import cruise_problem

# The linear rear tire: the gate is out of reach and the plans drive the rear beyond its
# friction, where IPOPT stops at its 300 iterations on the saturated tire's kink (decision 0109;
# the acados RTI solves it).
CONFIG = PlannerConfig(horizon_steps=20, rear_saturation=False)
HALF = 10  # stages 1 … HALF: the first half of the horizon


def test_the_scale_falls_from_the_lead_to_one_and_rejects_what_is_not_a_lead() -> None:
    scale = corridor_slack_scale(40, 10.0)
    assert scale.shape == (40,) and scale[-1] == 1.0
    assert np.all(np.diff(scale) < 0.0) and 9.0 < scale[0] < 10.0
    np.testing.assert_array_equal(corridor_slack_scale(40, 1.0), np.ones(40))
    for lead in (0.5, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="lead"):
            corridor_slack_scale(40, lead)
    with pytest.raises(ValueError, match="horizon_steps"):
        corridor_slack_scale(0, 2.0)
    with pytest.raises(ValueError, match="lane_slack_lead"):
        PlannerConfig(lane_slack_lead=0.9)


def test_the_scenario_key_reaches_the_planner_and_is_validated() -> None:
    cfg = load_scenario("turn", ["planner.lane_slack_lead=4"])
    assert planner_config(cfg, TRUCK).lane_slack_lead == 4.0
    assert planner_config(load_scenario("turn"), TRUCK).lane_slack_lead == 1.0
    with pytest.raises(ValueError, match="lane_slack_lead"):
        load_scenario("turn", ["planner.lane_slack_lead=0.5"])


def _corridor_problem(cfg: PlannerConfig, speed_mps: float = 20.0, mu: float = 0.9):
    n = cfg.horizon_steps
    # d_lo/d_hi bound stages 1 … N (index k: stage k + 1): ±0.1 m up to the last stage, which
    # lies in a gate 6 m to the left, out of reach (priced as the first stage's without a lead).
    d_lo, d_hi = np.full(n, -0.1), np.full(n, 0.1)
    d_lo[-1], d_hi[-1] = 6.0, 6.5
    return (*cruise_problem(cfg, speed_mps, mu), d_lo, d_hi)


# Each (backend, lead) plan is solved once per module: the two backends' test and their
# comparison below read the same two plans at lead 10, and the CasADi one builds its own NLP
# (≈ 1.2 s of CPU) before one IPOPT solve. The solves start from the same problem each time, so
# a second solve would give the same plan; it is returned read-only, as every caller only reads it.
@functools.cache
def _plan(backend_name: str, lead: float) -> np.ndarray:
    cfg = dataclasses.replace(CONFIG, lane_slack_lead=lead)
    if backend_name == "acados":
        from mufusion.planner.acados_backend import AcadosBackend

        backend, iterations = AcadosBackend(TRUCK, cfg), 10
    else:
        from mufusion.planner.casadi_backend import CasadiBackend

        backend, iterations = CasadiBackend(TRUCK, cfg), 1
    guess_x, guess_u, p, yref, weights, d_lo, d_hi = _corridor_problem(cfg)
    x0 = guess_x[0].copy()
    for _ in range(iterations):
        status, guess_x, guess_u = backend.solve(x0, guess_x, guess_u, p, yref, weights,
                                                 d_lo, d_hi, 0.5)
    assert status in (0, 2), status
    d = guess_x[:, State.d].copy()
    d.flags.writeable = False
    return d


@pytest.mark.parametrize("backend_name", ["acados", "casadi"])
def test_a_plan_that_cannot_keep_the_corridor_leaves_it_later_with_a_lead(backend_name) -> None:
    """Ending in a gate 6 m to the left of a ±0.1 m corridor (out of reach), priced alike the
    plan leaves the corridor from its first stages on to get closer to the gate; with the first
    stages priced ten times higher it keeps the first half nearer the corridor and ends further
    from the gate."""
    same, lead = _plan(backend_name, 1.0), _plan(backend_name, 10.0)
    n = CONFIG.horizon_steps

    def first_half_excursion(d):
        return float(np.sum(np.maximum(np.abs(d[1:HALF + 1]) - 0.1, 0.0)))

    assert first_half_excursion(same) > 0.5  # priced alike, it leaves early
    assert first_half_excursion(lead) < 0.5 * first_half_excursion(same)
    assert lead[n] < same[n] < 6.0  # and misses the gate by more


def test_both_backends_price_the_stages_alike() -> None:
    """acados writes the scale per stage at load time, the reference backend builds it into its
    objective: the same plan, up to the solvers' tolerances."""
    np.testing.assert_allclose(_plan("acados", 10.0), _plan("casadi", 10.0), atol=0.03)
