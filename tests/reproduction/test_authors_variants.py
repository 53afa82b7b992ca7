"""The authors' variants, their ablation and the slide diagnosis, from data and crafted logs."""

from __future__ import annotations

import numpy as np
import pytest

from factories import plan_stages, planning_step, run_meta, ticks
from mufusion.configurations import Configuration
from mufusion.reproduction.ablation import ABLATION_CONFIGS, ablation_specs, authors_variants
from mufusion.reproduction.authors import POPUP_SETTINGS, TURN_SETTINGS, combined_overrides
from mufusion.reproduction.graded import lane_excursion_m
from mufusion.reproduction.slide import slide_diagnosis, slide_text
from mufusion.reproduction.variants import PAPER_FACTS, variant
from mufusion.scenarios import load_scenario
from mufusion.sim.log import RunLog
from mufusion.sim.world import World
from mufusion.vehicle.params import TRUCK

C = Configuration


def test_authors_turn_is_a_pure_arc_with_mu_dropping_44_m_before_it() -> None:
    var = variant("turn-authors")
    cfg = load_scenario("turn", list(var.overrides))
    road = cfg.build_road(TRUCK)
    s0 = cfg.start_s_m
    assert road.mu_at(s0 - 1.0) == pytest.approx(0.8)
    assert road.mu_at(s0 + 1.0) == pytest.approx(0.4)
    # No clothoid: the curvature jumps from 0 to the arc's 1/28 m at the arc, 44 m ahead.
    assert road.curvature(s0 + 43.9) == pytest.approx(0.0)
    assert abs(road.curvature(s0 + 44.1)) == pytest.approx(1.0 / 28.0)
    assert cfg.cruise_speed_mps == 15.0 and cfg.initial_speed_mps == 15.0
    assert (cfg.estimation.local_timing, cfg.estimation.class_table) == ("authors", "authors")
    assert cfg.estimation.local_error == "worst_under" and cfg.estimation.initial_local_mu == 0.8
    assert (cfg.sim.tires, cfg.planner.stiffness) == ("authors", "from_mu_hat")


def test_authors_popup_puts_the_obstacle_20_m_ahead_of_the_centre_of_gravity() -> None:
    var = variant("popup-authors")
    cfg = load_scenario("popup", list(var.overrides))
    (obstacle,) = cfg.build_road(TRUCK).obstacles
    assert obstacle.s_m - cfg.start_s_m == pytest.approx(20.0, abs=1e-3)
    assert obstacle.d_m == 0.2 and cfg.friction.mu == 0.89
    # The authors' corridor: 0.5 R_obs + half the width + 1 m = 2.55 m centre to centre.
    clear = 0.5 * obstacle.width_m + 0.5 * TRUCK.width_m + cfg.planner.obstacle_margin_m
    assert clear == pytest.approx(2.55)


def test_authors_variants_check_the_papers_outcomes_and_name_what_they_cannot_represent():
    for key, scenario in (("turn-authors", "turn"), ("popup-authors", "popup")):
        var = variant(key)
        assert var.baseline == f"{scenario}-paper" and var.unrepresented
        for config, facts in PAPER_FACTS[scenario].items():
            assert set(facts) <= set(var.facts(config))
    assert any("4.6 m band" in text for text in variant("turn-authors").unrepresented)


def test_combined_overrides_are_the_settings_overrides_each_key_once() -> None:
    for settings in (TURN_SETTINGS, POPUP_SETTINGS):
        merged = combined_overrides(settings)
        keys = [o.split("=")[0] for o in merged]
        assert len(keys) == len(set(keys))
        assert {o for s in settings for o in s.overrides} == set(merged)


def test_ablation_runs_each_setting_alone_on_the_paper_variant_where_it_reaches() -> None:
    specs = ablation_specs()
    assert len({(s.variant, s.config) for s in specs}) == len(specs)
    for var in authors_variants():
        base = variant(str(var.baseline))
        for setting in var.settings:
            runs = [s for s in specs if s.variant == f"{base.key}+{setting.key}"]
            expected = [c.value for c in ABLATION_CONFIGS[var.scenario] if c in setting.reaches]
            assert [r.config for r in runs] == expected
            for run in runs:
                assert run.overrides == (*base.overrides, *setting.overrides)
                load_scenario(run.scenario, list(run.overrides))
    # The camera classes never reach GT or L; the local estimator's settings never GT or P.
    classes = [s for s in specs if s.variant == "turn-paper+classes"]
    assert [s.config for s in classes] == ["F"]


# -- crafted logs -----------------------------------------------------------------------------

def _turn_log(d_m, util_front, ratio, available_from_s, left_from_s=None, util_rear=0.5,
              speed_mps=10.0):
    """A log on the paper's turn road: ticks every 0.02 s, plans every 0.1 s for 4 s."""
    cfg = load_scenario("turn")
    road = cfg.build_road(TRUCK)
    t = np.arange(0.0, 4.0, 0.02)
    s = cfg.start_s_m + speed_mps * t
    d = np.broadcast_to(np.asarray(d_m, dtype=float), t.shape)
    x, y, psi = road.to_cartesian(s, d, 0.0)
    left = np.zeros(t.shape, bool) if left_from_s is None else t >= left_from_s
    meta = run_meta(configuration=C.L, scenario_config=cfg.model_dump(mode="json"))
    log = RunLog(meta)
    # The lane margin as the loop records it: the footprint placed on the road.
    world = World(road, to_planner_obstacle=lambda o: o)
    margin = [world.footprint_status((float(xi), float(yi), float(pi)), 0.0, float(si),
                                     TRUCK).lane_margin_m
              for xi, yi, pi, si in zip(x, y, psi, s, strict=True)]
    log.extend(ticks(t.size, s_m=s, d_m=d, x_m=x, y_m=y, psi_rad=psi, util_front=util_front,
                     util_rear=util_rear, left_lane=left, in_opposing_lane=left,
                     body_slip_rad=0.01, speed_mps=10.0, lane_margin_m=np.asarray(margin)))
    fzf, mu = 5e4, 0.4
    for step, t_plan in enumerate(np.arange(0.0, 4.0, 0.1).round(1)):
        r = float(ratio(t_plan))
        log.append(plan_stages(step, float(t_plan), fyf_n=r * mu * fzf, fzf_n=fzf, mu_true=mu,
                               mu_hat=0.8 if t_plan < available_from_s else 0.425))
        log.append(planning_step(step=step, t_s=float(t_plan),
                                 local_available=bool(t_plan >= available_from_s)))
    return log


def test_slide_diagnosis_reads_the_mechanism_from_the_log() -> None:
    t = np.arange(0.0, 4.0, 0.02)
    util = np.clip((t - 0.5) / 1.0, 0.0, 1.0)  # crosses 0.5 at 1.0 s, saturates at 1.48 s
    log = _turn_log(np.where(t < 1.6, 0.0, 2.0), util,
                    ratio=lambda tp: 1.5 if 1.0 <= tp < 2.0 else 0.5,
                    available_from_s=1.8, left_from_s=1.6)
    diag = slide_diagnosis(log)
    assert diag.over_limit_t_s == pytest.approx(1.0)
    assert diag.over_limit_duration_s == pytest.approx(1.0)
    assert diag.peak_planned_ratio == pytest.approx(1.5)
    assert diag.excited_t_s == pytest.approx(1.02)
    assert diag.saturated_t_s == pytest.approx(1.48)
    assert diag.local_available_t_s == pytest.approx(1.8)
    assert diag.estimate_drop_t_s == pytest.approx(1.8)
    assert (diag.mu_hat_start, diag.mu_true_start) == (0.8, 0.4)
    text = slide_text(diag)
    assert "exceeded the true limit μ_gt F_z first at t = 1.00 s" in text
    assert "the front at t = 1.48 s (before the estimate dropped)" in text
    assert "with the front tires saturated: L slid into the opposing lane" in text


def test_slide_text_without_saturation_says_why_the_vehicle_stayed() -> None:
    log = _turn_log(0.1, 0.6, ratio=lambda tp: 0.8, available_from_s=0.5)
    diag = slide_diagnosis(log)
    assert diag.over_limit_t_s is None and not diag.saturated and not diag.left_lane
    text = slide_text(diag)
    assert "never exceeded the true limit" in text
    assert "Neither axle saturated (peak utilisation front 0.60, rear 0.50)" in text
    assert "stayed in its lane: without a saturated axle" in text


def test_lane_excursion_reads_the_recorded_footprint_margin() -> None:
    # On the straight before the turn (8 m at 2 m/s; the curve begins 20 m ahead), an aligned
    # truck at d = 0.65 m has its left corners at 0.65 + 1.3 = 1.95 m: 0.2 m beyond the 3.5 m
    # lane's edge; at d = 0 they are 0.45 m inside.
    def straight(d_m):
        return _turn_log(d_m, 0.1, lambda tp: 0.1, 9.0, speed_mps=2.0)

    assert lane_excursion_m(straight(0.65)) == pytest.approx(0.2, abs=1e-6)
    assert lane_excursion_m(straight(0.0)) == pytest.approx(-0.45, abs=1e-6)
    # In the curve the body's ends stick out of the arc: the same offset reaches further.
    assert lane_excursion_m(_turn_log(0.65, 0.1, lambda tp: 0.1, 9.0)) > 0.3
