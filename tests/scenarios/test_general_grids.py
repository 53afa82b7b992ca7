"""The general grids (``examples/limits_general.toml``, ``examples/limits_popup_general.toml``):
seeded draws of their variants, the oracle over them, and GT's closed loop where the oracle
calls a variant feasible (issue 38: GT keeps its lane / does not collide there)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, assume, given, seed, settings
from hypothesis import strategies as st

from mufusion.campaign import campaign_specs, load_campaign
from mufusion.campaign.schema import CampaignFile
from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import FeasibilityClass, classify_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.vehicle.params import vehicle_preset

EXAMPLES = Path(__file__).parents[2] / "examples"
TURN_GRID = EXAMPLES / "limits_general.toml"
POPUP_GRID = EXAMPLES / "limits_popup_general.toml"

# Closed-loop budget: the draws run GT only, and a turn's run stops at this many seconds (the
# grid's hairpins on 150 m run 26 s; the first 12 s hold the approach, the friction change and
# the curve's entry, where the published failures happen). Pop-up runs keep the grid's duration.
TURN_DURATION_CAP_S = 12.0
TURN_DRAWS = 24
POPUP_DRAWS = 16


@cache
def _campaign(path: Path) -> CampaignFile:
    return load_campaign(path)


def grid_points(path: Path) -> st.SearchStrategy[tuple[str, ...]]:
    """A variant of the campaign file's grid: one value per axis (a zipped axis's values
    together), as the overrides the campaign gives that variant."""
    campaign = _campaign(path)
    axes = campaign.axes()

    def overrides(values: tuple[tuple[object, ...], ...]) -> tuple[str, ...]:
        pairs = [(k, v) for (keys, _), vals in zip(axes, values, strict=True)
                 for k, v in zip(keys, vals, strict=True)]
        return (*campaign.overrides, *(f"{k}={v}" for k, v in pairs))

    return st.tuples(*(st.sampled_from(values) for _, values in axes)).map(overrides)


@cache
def _variants(path: Path) -> frozenset[tuple[str, ...]]:
    """Every variant's overrides as the campaign gives them (GT only: one run per variant)."""
    return frozenset(spec.overrides for spec in campaign_specs(
        _campaign(path).model_copy(update={"configs": ["GT"]})))


def _verdict(kind: str, overrides: tuple[str, ...]):
    cfg = load_scenario(kind, list(overrides))
    return cfg, classify_scenario(cfg, vehicle_preset(cfg.vehicle))


def _with(overrides: tuple[str, ...], key: str, value: float) -> tuple[str, ...]:
    return (*(o for o in overrides if o.partition("=")[0] != key), f"{key}={value}")


def _value(overrides: tuple[str, ...], key: str) -> float:
    return next(float(o.partition("=")[2]) for o in overrides if o.partition("=")[0] == key)


# --- the draw and the oracle over the spaces (fast) ---------------------------------------------
@pytest.mark.parametrize(("kind", "path"), [("turn", TURN_GRID), ("popup", POPUP_GRID)])
@settings(max_examples=30, deadline=None, database=None)
@given(data=st.data())
def test_a_draw_is_one_of_the_grids_variants(kind, path, data) -> None:
    drawn = data.draw(grid_points(path))
    # The campaign's variants are expanded once per file, not once per draw (the expansion
    # was most of this test's time).
    assert drawn in _variants(path)  # zipped values stay together, every axis has its value
    assert load_scenario(kind, list(drawn)).name == kind


@settings(max_examples=25, deadline=None, database=None)
@given(drawn=grid_points(TURN_GRID), slower=st.floats(0.5, 6.0), more=st.floats(0.05, 0.5))
def test_turn_oracle_over_the_general_space(drawn, slower, more) -> None:
    cfg, base = _verdict("turn", drawn)
    # Slower is never less feasible; more friction before or after the change never either.
    speed = cfg.initial_speed_mps
    assert _verdict("turn", _with(drawn, "initial_speed_mps", speed - slower))[1] \
        .feasibility_class.rank >= base.feasibility_class.rank
    for key in ("friction.mu_before", "friction.mu_turn"):
        higher = _verdict("turn", _with(drawn, key, min(_value(drawn, key) + more, 1.5)))[1]
        assert higher.feasibility_class.rank >= base.feasibility_class.rank
        assert higher.margin_mps >= base.margin_mps - 1e-9
    # The lower friction everywhere is never easier; the higher everywhere never harder.
    low, high = sorted((cfg.friction.mu_before, cfg.friction.mu_turn))
    for mu, sign in ((low, -1.0), (high, 1.0)):
        constant = _verdict("turn", _with(_with(drawn, "friction.mu_before", mu),
                                          "friction.mu_turn", mu))[1]
        assert sign * (constant.margin_mps - base.margin_mps) >= -1e-9


@settings(max_examples=40, deadline=None, database=None)
@given(drawn=grid_points(POPUP_GRID), slower=st.floats(0.5, 6.0), more=st.floats(0.05, 0.5),
       further=st.floats(0.5, 10.0))
def test_popup_oracle_over_the_general_space(drawn, slower, more, further) -> None:
    cfg, base = _verdict("popup", drawn)
    rank = base.feasibility_class.rank
    changed = {
        "initial_speed_mps": cfg.initial_speed_mps - slower,
        "friction.mu": min(cfg.friction.mu + more, 1.5),
        "obstacle.distance_m": cfg.obstacle.distance_m + further,
    }
    for key, value in changed.items():
        assert _verdict("popup", _with(drawn, key, value))[1].feasibility_class.rank >= rank, key


# --- GT's closed loop where the oracle says feasible (slow) -------------------------------------
_CLOSED_LOOP = settings(
    max_examples=TURN_DRAWS, deadline=None, database=None, derandomize=True,
    phases=[Phase.explicit, Phase.generate],  # no shrinking: each draw is a full closed loop
    suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow],
)


@cache
def _gt_turn(drawn: tuple[str, ...]):
    """GT's closed loop on a drawn turn (capped duration), once per draw for both tests below."""
    cfg, verdict = _verdict("turn", drawn)
    cfg = cfg.model_copy(update={"duration_s": min(cfg.duration_s, TURN_DURATION_CAP_S)})
    return verdict, compute_metrics(run_scenario(cfg, "GT"))


@pytest.mark.slow
@seed(38)
@_CLOSED_LOOP
@given(drawn=grid_points(TURN_GRID))
def test_gt_in_feasible_general_turns_locks_no_wheel_and_keeps_its_lane_on_rises(drawn) -> None:
    verdict = _verdict("turn", drawn)[1]
    assume(verdict.feasibility_class is FeasibilityClass.FEASIBLE)
    _, m = _gt_turn(drawn)
    assert m.wheel_lock_within_abs_cycle, (
        f"a wheel stayed locked {m.wheel_lock_max_s:.2f} s: {', '.join(drawn)}")
    if _value(drawn, "friction.mu_turn") > _value(drawn, "friction.mu_before"):
        assert not m.left_lane, (
            f"GT left its lane by {m.max_lane_excursion_m:.2f} m on a rise: {', '.join(drawn)}")


# Issue 38's acceptance over seeded draws. Decision 0064 (the front braking bounded where its
# torque lands) took the drops into 15 m arcs back into the lane; the four rises of mechanism B
# below are still out in the full grid (docs/limit-grids.md).
@pytest.mark.slow
@seed(38)
@_CLOSED_LOOP
@given(drawn=grid_points(TURN_GRID))
def test_gt_keeps_its_lane_in_feasible_general_turns(drawn) -> None:
    verdict = _verdict("turn", drawn)[1]
    assume(verdict.feasibility_class is FeasibilityClass.FEASIBLE)
    _, m = _gt_turn(drawn)
    assert not m.left_lane, (
        f"GT left its lane by {m.max_lane_excursion_m:.2f} m in a feasible variant "
        f"(margin {verdict.margin_mps:+.2f} m/s): {', '.join(drawn)}")


# Mechanism B (decision 0061): the truck at 19 m/s onto a 40 m arc after a rise 0.3 → 0.9; its
# plans exceed |ψ̇| ≤ μ̂ g / v and the body slip reached 0.18-0.20 rad, 0.33-0.39 m out; with
# the rear tire at the plan's own load and the curvature under the axles (decision 0066) 2.1 cm,
# the plans alternating braking and driving stage by stage; with the longitudinal forces as
# OCP states that follow the torques' lag (decision 0068) in lane.
@pytest.mark.slow
def test_gt_keeps_its_lane_on_the_rise_onto_a_40_m_arc_at_19_mps() -> None:
    drawn = (*_campaign(TURN_GRID).overrides, "vehicle=truck", "turn.radius_m=40.0",
             "turn.angle_rad=1.5708", "initial_speed_mps=19.0", "duration_s=10.0",
             "friction.change_ahead_m=10.0", "friction.mu_before=0.3", "friction.mu_turn=0.9",
             "turn.direction=left")
    verdict, m = _gt_turn(drawn)
    assert verdict.feasibility_class is FeasibilityClass.FEASIBLE
    assert not m.left_lane, f"GT left its lane by {m.max_lane_excursion_m:.2f} m"


# Decision 0065: the same run with the speed reference's curve speeds at 0.9 of the polygon's
# lateral reach (not the default: measured on the grids first) keeps the lane.
@pytest.mark.slow
def test_gt_keeps_its_lane_on_that_rise_with_a_curve_speed_reserve() -> None:
    drawn = (*_campaign(TURN_GRID).overrides, "vehicle=truck", "turn.radius_m=40.0",
             "turn.angle_rad=1.5708", "initial_speed_mps=19.0", "duration_s=10.0",
             "friction.change_ahead_m=10.0", "friction.mu_before=0.3", "friction.mu_turn=0.9",
             "turn.direction=left", "planner.reference_curve_fraction=0.9")
    verdict, m = _gt_turn(drawn)
    assert verdict.feasibility_class is FeasibilityClass.FEASIBLE
    assert not m.left_lane, f"GT left its lane by {m.max_lane_excursion_m:.2f} m"


@pytest.mark.slow
@seed(38)
@settings(_CLOSED_LOOP, max_examples=POPUP_DRAWS)
@given(drawn=grid_points(POPUP_GRID))
def test_gt_does_not_collide_in_feasible_general_popups(drawn) -> None:
    cfg, verdict = _verdict("popup", drawn)
    assume(verdict.feasibility_class is FeasibilityClass.FEASIBLE)
    m = compute_metrics(run_scenario(cfg, "GT"))
    assert not m.collision, (
        f"GT hit the obstacle at {m.impact_speed_mps} m/s in a feasible variant "
        f"(margin {verdict.margin_mps:+.2f} m/s): {', '.join(drawn)}")
