"""Probing and lane recovery: they trigger only when they should, stay bounded, and are logged."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.configurations import FrictionEstimate
from mufusion.fusion import FusedEstimate, assemble_inputs
from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_loop, run_scenario
from mufusion.sim.events import EventKind
from mufusion.sim.lane_recovery import RecoveryOutcome
from mufusion.sim.log import RunLog
from mufusion.sim.loop import ClosedLoop
from mufusion.sim.stop_in_lane import StopProbeEnd
from mufusion.sim.supervision import (
    LaneRecoverySettings,
    ProbeEndReason,
    Prober,
    ProbingSettings,
    planned_footprint_violation_m,
    planned_obstacle_clearance_m,
    planned_obstacle_hit,
    planned_obstacle_shortfall_m,
    plausible_estimate,
    relaxed_estimate,
)
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import State

GRID = np.arange(0.0, 51.0)


def _estimate(mu_hat: float = 0.1, mean: float = 0.3, local: bool = False, fused: bool = True):
    post = FusedEstimate(GRID, np.full(51, mean), np.full(51, 0.05), np.full(51, mu_hat),
                         np.full(51, mu_hat))
    return FrictionEstimate(GRID, np.full(51, mu_hat), local, 0.3, fused=post if fused else None)


def _curve_ahead(start_m: float = 20.0, radius_m: float = 28.0) -> np.ndarray:
    return np.where(GRID >= start_m, -1.0 / radius_m, 0.0)


def _run(scenario: str, overrides: list[str], config: str) -> tuple[RunLog, ClosedLoop]:
    """A run's log, and its loop: what the supervisors did, as they record it."""
    cfg = load_scenario(scenario, overrides)
    loop = build_loop(cfg, friction=config)
    return run_loop(loop, cfg.duration_s), loop


def _events(log: RunLog, kind: EventKind):
    return log.events[log.events["kind"] == kind]


def _prober(**settings) -> Prober:
    return Prober(ProbingSettings(**settings), utilization_factor=0.9)


def test_probe_starts_when_the_estimate_locks_out_a_curve_the_road_may_allow() -> None:
    why = _prober().reason_to_probe(0.0, 12.0, _estimate(), _curve_ahead(), obstacle_near=False)
    # 12² / (28 · 9.81) = 0.52 needed, 0.9 · 0.1 granted.
    assert why is not None and "needs μ 0.52" in why and "grants 0.09" in why


@pytest.mark.parametrize(
    ("case", "kwargs"),
    [
        ("local estimate available", dict(estimate=_estimate(local=True))),
        ("no posterior band (GT, L, P)", dict(estimate=_estimate(fused=False))),
        ("narrow band", dict(estimate=_estimate(mu_hat=0.25, mean=0.3))),
        ("enough friction granted", dict(estimate=_estimate(mu_hat=0.6, mean=0.9))),
        ("in a curve", dict(curvature=_curve_ahead(start_m=0.0))),
        ("obstacle near", dict(obstacle_near=True)),
        ("too slow", dict(speed=4.0)),
    ],
)
def test_probe_does_not_start(case: str, kwargs) -> None:
    args = dict(estimate=_estimate(), curvature=_curve_ahead(), obstacle_near=False, speed=12.0)
    args.update(kwargs)
    why = _prober().reason_to_probe(0.0, args["speed"], args["estimate"], args["curvature"],
                                    args["obstacle_near"])
    assert why is None, case


def test_probe_is_bounded_and_cools_down() -> None:
    prober = _prober(max_decel_mps2=3.0, ramp_s=0.3, max_duration_s=0.6, max_speed_loss_mps=2.0,
                     cooldown_s=2.0)
    prober.start(1.0, 12.0)
    assert prober.decel_mps2(1.15) == pytest.approx(1.5)
    assert prober.decel_mps2(1.5) == pytest.approx(3.0)
    assert prober.reason_to_stop(1.3, 11.5, local_available=False) is None
    assert prober.reason_to_stop(1.3, 11.5, local_available=True) is ProbeEndReason.MEASURED
    assert prober.reason_to_stop(1.6, 11.5, False) is ProbeEndReason.LONGEST
    assert prober.reason_to_stop(1.2, 9.9, False) is ProbeEndReason.SPEED_LOSS
    assert prober.stop(1.4, 11.2) == pytest.approx(0.8)
    # The local estimate is stale again, but a new probe waits for the cool-down.
    assert prober.reason_to_probe(2.0, 11.2, _estimate(), _curve_ahead(), False) is None
    assert prober.reason_to_probe(3.5, 11.2, _estimate(), _curve_ahead(), False) is not None
    assert prober.probes == 1 and prober.speed_lost_mps == pytest.approx(0.8)


def test_relaxation_moves_towards_the_mean_only() -> None:
    est = _estimate(mu_hat=0.1, mean=0.3)
    np.testing.assert_allclose(relaxed_estimate(est, 0.25).mu_hat, 0.15)
    above = _estimate(mu_hat=0.4, mean=0.3)
    assert relaxed_estimate(above, 1.0) is None  # never lowered, nothing to gain
    assert relaxed_estimate(_estimate(fused=False), 1.0) is None
    with pytest.raises(ValueError, match=r"lane_recovery\.steps"):
        LaneRecoverySettings(steps=(0.5, 0.25))


def test_relaxation_never_trusts_the_local_estimate_beyond_its_declared_error() -> None:
    # The adversarial over-estimate of the turn grid: μ 0.9 under and ahead of the vehicle, the
    # local estimate 0.925 ± 0.025, the camera's dry class 0.8 ± 0.2 up to 30 m and a wet class
    # 0.5 ± 0.1 beyond. The posterior mean follows the local value (0.92); the relaxation may
    # carry the measured surface forward over its class, but only at 0.925 − 0.025 = 0.9.
    camera_mu = np.where(GRID < 30.0, 0.8, 0.5)
    camera_margin = np.where(GRID < 30.0, 0.2, 0.1)
    data = assemble_inputs(GRID, camera_mu, camera_margin, local_mu=0.925, mode="safe")
    mean = np.where(GRID < 30.0, 0.92, 0.7)
    post = FusedEstimate(GRID, mean, np.full(51, 0.02), np.full(51, 0.6), np.full(51, 0.6))
    mu_hat = np.where(GRID < 30.0, 0.6, 0.4)  # the classes' lower bounds
    est = FrictionEstimate(GRID, mu_hat, True, 0.925, fused=post, data=data)
    full = relaxed_estimate(est, 1.0)
    assert full is not None
    # Capped: the mean's 0.92 would over-estimate.
    np.testing.assert_allclose(full.mu_hat[GRID < 30.0], 0.9)
    # Another surface: the mean (0.7), but not above the value its class reports (0.5), the
    # most probable μ there; the class's upper edge (0.6) would over-estimate a surface at 0.55.
    np.testing.assert_allclose(full.mu_hat[GRID >= 30.0], 0.5)
    # Halfway: the measured surface at what the local estimate guarantees (twice the pace,
    # docs/decisions/0122), the wet class half its way; at one pace, half of each way.
    half = relaxed_estimate(est, 0.5)
    assert half is not None
    np.testing.assert_allclose(half.mu_hat, np.where(GRID < 30.0, 0.9, 0.45))
    np.testing.assert_allclose(relaxed_estimate(est, 0.5, measured_first=False).mu_hat,
                               np.where(GRID < 30.0, 0.75, 0.45))
    # Without the local estimate the mean is the target up to the classes' reported values.
    unmeasured = FrictionEstimate(GRID, mu_hat, False, None, fused=post,
                                  data=assemble_inputs(GRID, camera_mu, camera_margin,
                                                       mode="safe"))
    declared = np.where(GRID < 30.0, 0.8, 0.5)
    np.testing.assert_allclose(relaxed_estimate(unmeasured, 1.0).mu_hat, np.minimum(mean, declared))
    with pytest.raises(ValueError, match=r"probing\.max_decel_mps2"):
        ProbingSettings(max_decel_mps2=9.0)


def test_plausible_estimate_is_the_band_top_never_below_mu_hat() -> None:
    est = _estimate(mu_hat=0.1, mean=0.3)  # std 0.05
    np.testing.assert_allclose(plausible_estimate(est).mu_hat, 0.3 + 1.96 * 0.05)
    high = _estimate(mu_hat=0.5, mean=0.3)  # μ̂ above the band's top: kept
    np.testing.assert_allclose(plausible_estimate(high).mu_hat, 0.5)
    assert plausible_estimate(_estimate(fused=False)) is None
    assert np.all(plausible_estimate(_estimate(mu_hat=0.1, mean=1.99)).mu_hat <= 2.0)
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ValueError, match=r"lane_recovery\.stop_probe_s"):
            LaneRecoverySettings(stop_probe_s=bad)


def _states(d_m, dpsi_rad=0.0) -> np.ndarray:
    x = np.zeros((np.size(d_m), 6))
    x[:, State.d], x[:, State.dpsi] = d_m, dpsi_rad
    return x


def test_footprint_violation_of_an_aligned_body_is_the_reference_points() -> None:
    # Aligned with a straight lane the corners sit half a width beside the reference point, so
    # the footprint leaves the band exactly as far as the point leaves its bounds.
    x = _states([0.0, 0.5, -0.7])
    assert planned_footprint_violation_m(x, 0.0, (-0.45, 0.45), TRUCK) == pytest.approx(0.25)
    assert planned_footprint_violation_m(x[:1], 0.0, (-0.45, 0.45), TRUCK) == 0.0


def test_footprint_violation_counts_the_swing_of_a_yawed_body() -> None:
    # Yawed 0.3 rad left at the lane centre: the front-left corner lies a_f sin Δψ + w/2 cos Δψ
    # left of the centre, the rear-right one a_r sin Δψ + w/2 cos Δψ right of it (a_f, a_r: the
    # reference point (CoG) to the body's front and rear; the truck's CoG is ahead of its middle).
    dpsi = 0.3
    shift = 0.5 * (TRUCK.cog_to_front_axle_m - TRUCK.cog_to_rear_axle_m)
    a_front, a_rear = 0.5 * TRUCK.length_m + shift, 0.5 * TRUCK.length_m - shift
    edge = 0.45 + 0.5 * TRUCK.width_m
    left = a_front * np.sin(dpsi) + 0.5 * TRUCK.width_m * np.cos(dpsi) - edge
    right = a_rear * np.sin(dpsi) + 0.5 * TRUCK.width_m * np.cos(dpsi) - edge
    assert 0.0 < left < right  # the reference point alone (d = 0) would pass
    got = planned_footprint_violation_m(_states([0.0], dpsi), 0.0, (-0.45, 0.45), TRUCK)
    assert got == pytest.approx(right, rel=1e-12)
    # Shifted left by the difference, both corners leave by the same amount.
    shifted = _states([0.5 * (right - left)], dpsi)
    got = planned_footprint_violation_m(shifted, 0.0, (-0.45, 0.45), TRUCK)
    assert got == pytest.approx(0.5 * (left + right), rel=1e-12)


def test_footprint_violation_counts_the_bulge_outside_a_curve() -> None:
    # On a left curve (κ > 0) the aligned body's ends lie κ a² / 2 right of the chord: at the
    # reference bound on the right, the rear corner (the longer arm) leaves by κ a_r² / 2.
    kappa = 1.0 / 28.0
    a_rear = 0.5 * CAR.length_m - 0.5 * (CAR.cog_to_front_axle_m - CAR.cog_to_rear_axle_m)
    a_front = CAR.length_m - a_rear
    x = _states([-0.45])
    got = planned_footprint_violation_m(x, kappa, (-0.45, 0.45), CAR)
    assert got == pytest.approx(0.5 * kappa * max(a_front, a_rear) ** 2, rel=1e-12)
    # Inside the curve the same body at the left bound stays in.
    assert planned_footprint_violation_m(_states([0.45]), kappa, (-0.45, 0.45), CAR) == 0.0


@pytest.fixture(scope="module")
def caution_runs():
    """F-safe at 12 m/s into the turn on μ 0.3 (μ̂ = 0.1, the snow/ice class minimum)."""
    base = ["initial_speed_mps=12", "friction.mu_turn=0.3", "duration_s=8"]
    variants = {
        "neither": ["probing.enabled=false", "lane_recovery.enabled=false"],
        "probing": ["lane_recovery.enabled=false"],
        "both": [],
    }
    return {k: _run("turn", [*base, *v], "F-safe") for k, v in variants.items()}


@pytest.mark.slow
def test_caution_alone_drives_off_and_lane_recovery_keeps_the_lane(caution_runs) -> None:
    neither = compute_metrics(caution_runs["neither"][0])
    both = compute_metrics(caution_runs["both"][0])
    # Without probing and lane recovery F-safe leaves the lane (by over 1 m before the vehicle
    # had ABS; 0.94 m with it, docs/decisions/0052); with both it keeps it.
    assert neither.max_lane_excursion_m > 0.5
    assert both.max_lane_excursion_m == 0.0 and not both.minimal_risk
    assert len(_events(caution_runs["both"][0], EventKind.LANE_RECOVERY)) >= 3


@pytest.mark.slow
def test_probing_is_logged_bounded_and_makes_the_local_estimate_available(caution_runs) -> None:
    log, loop = caution_runs["probing"]
    start, end = _events(log, EventKind.PROBE_START), _events(log, EventKind.PROBE_END)
    assert len(start) == 1 and len(end) == 1
    duration = float(end["t_s"].iloc[0] - start["t_s"].iloc[0])
    assert 0.0 < duration <= 0.6 + 1e-9
    assert [e.reason for e in loop.supervision.probing.ends] == [ProbeEndReason.MEASURED]
    ts = log.timeseries
    probing = ts[ts["control_mode"] == "probing"]
    assert len(probing) >= 2
    v0 = float(ts["speed_mps"].iloc[0])
    assert v0 - float(probing["speed_mps"].min()) <= 2.0
    steps = log.planning_steps
    assert steps[steps["t_s"] <= float(end["t_s"].iloc[0]) + 0.1]["local_available"].any()
    # Without probing the local estimator measures only once the braking for the curve brings
    # the rear tires to its threshold (0.9-1.0 s in; 0.3 s with the probe). The instant itself
    # moves with any change of the braking, so the test compares the two runs.
    def first_available_s(planning_steps) -> float:
        available = planning_steps[planning_steps["local_available"].astype(bool)]
        return float(available["t_s"].min()) if len(available) else float("inf")

    quiet = caution_runs["neither"][0].planning_steps
    assert first_available_s(steps) + 0.3 <= first_available_s(quiet)


def test_the_probe_can_excite_the_estimator_on_every_surface_the_camera_declares() -> None:
    # Braking with a share of the weight on each axle, a deceleration a loads the tires to
    # a / (μ g): the ceiling must pass the threshold on the highest friction any class admits.
    from mufusion.estimators.classes import PAPER_CLASSES
    from mufusion.estimators.local import UTILIZATION_THRESHOLD
    from mufusion.vehicle.params import GRAVITY_MPS2

    top = max(c.value + c.margin for c in PAPER_CLASSES)
    assert top == pytest.approx(1.0)
    assert ProbingSettings().max_decel_mps2 > UTILIZATION_THRESHOLD * top * GRAVITY_MPS2
    # ... and reaches it within the probe's time, the estimate seen one planning step later.
    cfg = ProbingSettings()
    prober = _prober()
    prober.start(0.0, 18.0)
    reach_s = UTILIZATION_THRESHOLD * top * GRAVITY_MPS2 / cfg.max_decel_mps2 * cfg.ramp_s
    assert prober.decel_mps2(reach_s) == pytest.approx(UTILIZATION_THRESHOLD * top * GRAVITY_MPS2)
    assert reach_s + 0.1 <= cfg.max_duration_s


@pytest.mark.slow
def test_a_probe_on_a_dry_road_measures_the_friction() -> None:
    # The truck 40 m before a curve on μ 0.9 at 18 m/s: F-safe's μ̂ (the dry class minimum)
    # cannot take the curve at this speed, so it probes. With a 3 m/s² ceiling the probe ended
    # at its time limit in all 64 such runs of examples/limits_perturbed.toml, unmeasured.
    log, loop = _run("turn", [
        "vehicle=truck", "initial_speed_mps=18", "friction.mu_turn=0.9",
        "turn.start_ahead_m=40", "turn.clothoid_m=0", "duration_s=1.0"], "F-safe")
    start, end = _events(log, EventKind.PROBE_START), _events(log, EventKind.PROBE_END)
    assert len(start) == 1 and len(end) == 1
    (probe,) = loop.supervision.probing.ends
    assert probe.reason is ProbeEndReason.MEASURED and probe.t_s == float(end["t_s"].iloc[0])
    assert 0.0 < probe.speed_lost_mps <= ProbingSettings().max_speed_loss_mps
    steps = log.planning_steps
    assert steps[steps["t_s"] <= float(end["t_s"].iloc[0])]["local_available"].astype(bool).any()


@pytest.mark.slow
def test_after_lane_recovery_the_planner_continues_the_adopted_plan() -> None:
    # The pop-up's evasion plans leave the road band and trigger recovery at most steps of the
    # first second; where relaxing does not help, the friction-limited plan is adopted after
    # four candidates. The next step must continue (shift, and take its front force from) the
    # plan the controller tracks, not the last candidate tried.
    cfg = load_scenario("popup", ["duration_s=1.0"])
    loop = build_loop(cfg, friction="F")
    mismatches: list[float] = []
    adopted: list[float] = []

    def checked(t: float) -> None:  # after each planning step, loop.plan is the one adopted
        adopted.append(t)
        if loop.plan is not None and loop.planner.last_plan is not loop.plan:
            mismatches.append(t)

    run_loop(loop, cfg.duration_s, progress=checked)
    outcomes = [r.outcome for r in loop.supervision.lane_recovery.recoveries]
    # Both kinds of outcome occur: a relaxed candidate adopted, and none (the first plan kept).
    assert outcomes.count(RecoveryOutcome.DID_NOT_HELP) >= 3
    assert outcomes.count(RecoveryOutcome.RELAXED) >= 1
    assert len(adopted) >= 10 and mismatches == []


def test_planned_obstacle_clearance_by_hand() -> None:
    from mufusion.planner import PlannerObstacle

    x = np.zeros((3, 6))
    x[:, State.s] = [0.0, 10.0, 20.0]
    x[:, State.d] = [0.0, 1.0, 3.0]
    ob = PlannerObstacle(s_m=20.0, d_m=0.0, length_m=1.0, width_m=1.0)
    # Abreast of the obstacle the footprint's right edge is 3 − w/2 from the lane centre.
    side_gap = 3.0 - 0.5 * TRUCK.width_m - 0.5
    assert planned_obstacle_clearance_m(x, [ob], TRUCK) == pytest.approx(side_gap)
    x[2, State.d] = 1.0  # now it runs into it: overlap across the obstacle's 1 m width
    hit = planned_obstacle_clearance_m(x, [ob], TRUCK)
    assert hit < 0.0
    assert planned_obstacle_clearance_m(x, [], TRUCK) == np.inf


def _random_plans(rng: np.random.Generator, count: int):
    """``count`` plans of 41 states over 60 m at random offsets and headings."""
    for _ in range(count):
        x = np.zeros((41, 6))
        x[:, State.s] = np.linspace(0.0, 60.0, 41) + rng.uniform(-1.0, 1.0)
        x[:, State.d] = rng.uniform(-4.0, 4.0) + rng.normal(0.0, 0.3, 41)
        x[:, State.dpsi] = rng.normal(0.0, 0.1, 41)
        yield x


def test_planned_obstacle_hit_agrees_with_the_clearance() -> None:
    # Plans swept past two obstacles at random offsets, some through them, some beside them:
    # the bounding-box shortcut must answer as the full computation does.
    from mufusion.planner import PlannerObstacle

    rng = np.random.default_rng(7)
    obstacles = [PlannerObstacle(s_m=30.0, d_m=0.4, length_m=1.0, width_m=1.5),
                 PlannerObstacle(s_m=45.0, d_m=-1.0, length_m=4.0, width_m=2.0)]
    answers = set()
    for x in _random_plans(rng, 400):
        hit = planned_obstacle_hit(x, obstacles, TRUCK)
        assert hit == (planned_obstacle_clearance_m(x, obstacles, TRUCK) < 0.0)
        answers.add(hit)
    assert answers == {True, False}
    # A moving obstacle (one oncoming): row k of the plan meets it where it is k · dt later.
    moving = [PlannerObstacle(s_m=40.0, d_m=0.0, length_m=4.5, width_m=1.8, speed_mps=-10.0),
              PlannerObstacle(s_m=20.0, d_m=-1.0, length_m=4.5, width_m=1.8, speed_mps=8.0)]
    moving_answers = set()
    for x in _random_plans(rng, 200):
        hit = planned_obstacle_hit(x, moving, TRUCK, 0.1)
        assert hit == (planned_obstacle_clearance_m(x, moving, TRUCK, 0.1) < 0.0)
        moving_answers.add(hit)
    assert moving_answers == {True, False}
    x = next(_random_plans(rng, 1))
    x[:, State.d] = np.nan
    assert planned_obstacle_hit(x, obstacles, TRUCK) is False
    assert planned_obstacle_hit(x, [], TRUCK) is False


def test_planned_obstacle_shortfall_is_the_clearances_bit_for_bit() -> None:
    # The same sweeps, and a margin each: every plan's shortfall must equal max(0, margin −
    # clearance) exactly (lane recovery ranks candidates by it), whether it passes far, within
    # the margin or through the obstacle, and for a moving obstacle.
    from mufusion.planner import PlannerObstacle

    rng = np.random.default_rng(11)
    still = [PlannerObstacle(s_m=30.0, d_m=0.4, length_m=1.0, width_m=1.5),
             PlannerObstacle(s_m=45.0, d_m=-1.0, length_m=4.0, width_m=2.0)]
    moving = [PlannerObstacle(s_m=40.0, d_m=0.0, length_m=4.5, width_m=1.8, speed_mps=-10.0)]
    kinds = set()
    for obstacles, dt in ((still, 0.0), (moving, 0.1)):
        for x in _random_plans(rng, 300):
            margin = float(rng.choice([0.25, 0.5, 2.0]))
            shortfall = planned_obstacle_shortfall_m(x, obstacles, TRUCK, margin, dt)
            gap = planned_obstacle_clearance_m(x, obstacles, TRUCK, dt)
            assert shortfall == max(0.0, margin - gap)
            kinds.add("hit" if gap < 0.0 else "within" if gap < margin else "clear")
    assert kinds == {"hit", "within", "clear"}
    x = next(_random_plans(rng, 1))
    x[3, State.d] = np.nan  # non-finite: the full computation's answer
    gap = planned_obstacle_clearance_m(x, still, TRUCK)
    expected = max(0.0, 0.5 - gap)
    got = planned_obstacle_shortfall_m(x, still, TRUCK, 0.5)
    assert got == expected or (np.isnan(got) and np.isnan(expected))
    assert planned_obstacle_shortfall_m(x, [], TRUCK, 0.5) == 0.0


@pytest.mark.slow
def test_evading_lane_recovery_never_prefers_a_plan_that_hits_the_obstacle() -> None:
    # 24 m/s, obstacle 35 m ahead 1.5 m left of the lane centre, μ 1.0 (the oracle: marginal).
    # F-safe's friction-limited evasion (μ̂ 0.553 beyond the local estimate's reach) is predicted
    # to hit the obstacle at every step of the first second, while its relaxed candidates pass
    # it but leave the road band by more. Ranked by the road band alone, the colliding plan was
    # kept at every step and the truck hit the obstacle at 16.2 m/s; GT passes it by 0.58 m.
    log, loop = _run("popup", [
        "initial_speed_mps=24", "obstacle.distance_m=35", "friction.mu=1.0",
        "obstacle.lateral_offset_m=1.5", "duration_s=2.5"], "F-safe")
    m = compute_metrics(log)
    assert not m.collision and m.min_clearance_m > 0.0
    recoveries = loop.supervision.lane_recovery.recoveries
    relaxed = [r for r in recoveries if r.outcome is RecoveryOutcome.RELAXED and r.t_s < 1.0]
    assert len(relaxed) >= 5
    assert len(_events(log, EventKind.LANE_RECOVERY)) >= 10


@pytest.mark.slow
def test_an_evasion_that_no_plausible_friction_makes_pass_turns_into_braking_in_lane() -> None:
    # 19 m/s, obstacle 18 m ahead, 1.5 m left, μ 1.0 (infeasible: GT hits it at 13.4 m/s in its
    # lane). F-safe's candidates all hit it, and so does the check at the posterior's upper
    # edge; swerving anyway took it 0.99 m out of its lane into the obstacle at 15.4 m/s.
    setting = ["initial_speed_mps=19", "obstacle.distance_m=18", "friction.mu=1.0",
               "obstacle.lateral_offset_m=1.5", "duration_s=2.0"]
    braking, loop = _run("popup", setting, "F-safe")
    swerving = run_scenario(
        load_scenario("popup", [*setting, "lane_recovery.brake_when_futile=false"]), "F-safe")
    b, s = compute_metrics(braking), compute_metrics(swerving)
    assert b.collision and s.collision  # no plan avoids it: physics
    # Braking where the evasion is futile hits slower: by 1.7 m/s (13.3 against 15.0 m/s) before
    # the forces lagged in the OCP (decision 0068), by 0.6 m/s (14.3 against 14.9) since. The
    # first stop's braking now builds from the delivered zero (22 kN at 0.1 s where the plans
    # without the lag had 34 kN from the start), the slip estimator is excited one step later
    # (μ̂ 0.6 at 0.1 s instead of 0.95), and the evasion the later steps keep leaves the lane by
    # 1.08 m where the swerving run stays in it.
    # Since the check plans at the tires' limit (the posterior's upper edge ÷ λ, decision 0103),
    # at the first two steps the check still hits but the stop planned after it, one iteration
    # from the check's evasion, is rejected (outside its polygons), so the candidate is kept
    # (0.41 m out of the lane); the verdict comes at 0.2 s: 14.4 against 17.5 m/s (15.4 against
    # 15.0 m/s before 0103).
    assert b.impact_speed_mps < s.impact_speed_mps - 0.3
    futile = _events(braking, EventKind.FUTILE_EVASION)
    assert len(futile) >= 2 and float(futile["t_s"].min()) <= 0.2
    # At each such step the vehicle brakes in lane instead of the candidate evasion.
    recoveries = loop.supervision.lane_recovery.recoveries
    braked = [r.t_s for r in recoveries if r.outcome is RecoveryOutcome.BRAKING]
    assert braked == list(futile["t_s"])
    assert _events(swerving, EventKind.FUTILE_EVASION).empty


def test_brake_when_futile_must_be_a_bool() -> None:
    with pytest.raises(ValueError, match=r"lane_recovery\.brake_when_futile"):
        LaneRecoverySettings(brake_when_futile="yes")  # type: ignore[arg-type]


def _popup(config: str, mu: float, speed_mps: float, distance_m: float, *extra: str):
    return _run("popup", [
        f"initial_speed_mps={speed_mps}", f"obstacle.distance_m={distance_m}", f"friction.mu={mu}",
        "obstacle.lateral_offset_m=0.0", "duration_s=4", *extra], config)


@pytest.mark.slow
def test_braking_probe_earns_the_stop_in_lane_where_the_estimate_alone_evades() -> None:
    # F-safe at 14 m/s, the obstacle 18 m ahead on dry asphalt (μ 1.0): μ̂ is the dry class's
    # lower bound (0.6), the posterior mean 0.715, and the stop needs 0.85; the band's top (0.88)
    # does not rule it out. Without the probe F-safe swerves through the opposing lane.
    probed, loop = _popup("F-safe", 1.0, 14.0, 18.0)
    plain, _ = _popup("F-safe", 1.0, 14.0, 18.0, "lane_recovery.stop_probe_s=0")
    with_probe, without = compute_metrics(probed), compute_metrics(plain)
    assert without.max_lane_excursion_m > 1.0 and not without.collision
    assert with_probe.max_lane_excursion_m == 0.0 and not with_probe.collision
    assert with_probe.final_speed_mps < 0.1
    start = _events(probed, EventKind.STOP_PROBE)
    end = _events(probed, EventKind.STOP_PROBE_END)
    assert len(start) == 1 and len(end) == 1
    t0, t1 = float(start["t_s"].iloc[0]), float(end["t_s"].iloc[0])
    assert 0.0 < t1 - t0 <= 0.3 + 1e-9
    (probe,) = loop.supervision.stop_in_lane.probes
    assert (probe.start_s, probe.end_s, probe.ended) == (t0, t1, StopProbeEnd.STOP_FITS)
    steps = probed.planning_steps.set_index("t_s")
    # The probe brakes in lane, and the local estimate it earns is in the posterior that
    # grants the stop: the mean under the vehicle rises from the camera's 0.715 towards 0.975.
    assert (steps.loc[t0:t1 - 1e-9, "mode"] == "emergency").all()
    assert not steps.loc[t0, "local_available"] and steps.loc[t1, "local_available"]
    est = probed.estimates
    mean_here = est[est["s_ahead_m"] == 0.0].set_index("t_s")["mean"]
    assert mean_here.loc[t0] < 0.75 < 0.9 < mean_here.loc[t1]
    assert not plain.events["kind"].isin([EventKind.STOP_PROBE, EventKind.STOP_PROBE_END]).any()


@pytest.mark.slow
def test_braking_probe_that_measures_too_little_friction_ends_in_the_evasion() -> None:
    # At 14 m/s with the obstacle 18 m ahead on μ 0.75 the measured friction does not grant
    # the stop: the probe ends within its bound and the vehicle steers around the obstacle.
    log, loop = _popup("F-safe", 0.75, 14.0, 18.0)
    start, end = _events(log, EventKind.STOP_PROBE), _events(log, EventKind.STOP_PROBE_END)
    assert len(start) == 1 and len(end) == 1
    assert float(end["t_s"].iloc[0]) - float(start["t_s"].iloc[0]) <= 0.3 + 1e-9
    assert [p.ended for p in loop.supervision.stop_in_lane.probes] == [StopProbeEnd.EVADING]
    steps = log.planning_steps
    after = steps[steps["t_s"] >= float(end["t_s"].iloc[0])]
    assert (after["mode"].iloc[:5] == "evade").all()
    assert not compute_metrics(log).collision


@pytest.mark.slow
def test_no_braking_probe_without_a_posterior() -> None:
    log, _ = _popup("P", 1.0, 19.0, 35.0)
    assert not log.events["kind"].isin([EventKind.STOP_PROBE, EventKind.STOP_PROBE_END]).any()


@pytest.mark.slow
def test_lane_recovery_holds_its_relaxation_and_gives_it_back_after_the_curve() -> None:
    # F-safe at 18 m/s with a μ 0.9 turn 5 m ahead (clothoid 5 m): μ̂ ahead is the dry class's
    # lower bound 0.6, the posterior mean 0.92 once the local estimate measures. Lane recovery
    # must hold the relaxation it adopts through the curve (re-searching from the unrelaxed μ̂
    # each step, the loop flipped between plans and left the lane by 37 cm), then return to μ̂
    # one step of α at a time once the lane allows.
    log, loop = _run("turn", [
        "initial_speed_mps=18", "friction.mu_turn=0.9", "turn.start_ahead_m=5",
        "turn.direction=left", "turn.clothoid_m=5", "vehicle=truck", "duration_s=6"], "F-safe")
    assert compute_metrics(log).max_lane_excursion_m < 0.1
    recoveries = loop.supervision.lane_recovery.recoveries
    eased = [r for r in recoveries if r.outcome is RecoveryOutcome.EASED]
    # Searches that started from a held relaxation.
    searched = [r for r in recoveries if r.outcome is not RecoveryOutcome.EASED]
    assert sum(r.held_alpha > 0.0 for r in searched) >= 5
    steps = (0.0, *LaneRecoverySettings().steps)
    # Each step-down is one step of α, and the last returns to the unrelaxed μ̂.
    assert len(eased) >= 1
    assert all(steps.index(r.held_alpha) == steps.index(r.alpha) + 1 for r in eased)
    assert eased[-1].alpha == 0.0
    est = log.estimates
    last = est[est["t_s"] == est["t_s"].max()]
    # Back at the class's lower bound beyond the local estimate's reach (safe mode's guarantee).
    assert float(last[last["s_ahead_m"] == 20.0]["mu_hat"].iloc[0]) == pytest.approx(0.6)


def test_relaxation_never_plans_above_the_class_the_camera_reports_ahead() -> None:
    # The general grid's drop inside a curve (docs/decisions/0061): the local estimate 0.925 ±
    # 0.025 on μ 0.9, the camera's class 0.25 ± 0.15 from 16 m on. The posterior mean stays at
    # 0.9 over the low class; relaxing towards it planned the drop at up to 0.9 where every
    # estimate there says μ ≤ 0.4, and relaxing to that edge still planned a surface of 0.3 above
    # its friction (docs/decisions/0069): the target there is the class's own value, 0.25.
    camera_mu = np.where(GRID < 16.0, 0.8, 0.25)
    camera_margin = np.where(GRID < 16.0, 0.2, 0.15)
    data = assemble_inputs(GRID, camera_mu, camera_margin, local_mu=0.925, mode="safe")
    post = FusedEstimate(GRID, np.full(51, 0.9), np.full(51, 0.013), np.full(51, 0.87),
                         np.full(51, 0.87))
    est = FrictionEstimate(GRID, np.where(GRID < 16.0, 0.6, 0.1), True, 0.925, fused=post,
                           data=data)
    full = relaxed_estimate(est, 1.0)
    assert full is not None
    np.testing.assert_allclose(full.mu_hat[GRID < 16.0], 0.9)
    np.testing.assert_allclose(full.mu_hat[GRID >= 16.0], 0.25)
    # The measured surface at twice the pace (docs/decisions/0122), the low class at its own.
    quarter = relaxed_estimate(est, 0.25)
    assert quarter is not None
    np.testing.assert_allclose(quarter.mu_hat, np.where(GRID < 16.0, 0.75, 0.1375))
    for measured_first in (True, False):
        np.testing.assert_allclose(relaxed_estimate(est, 0.5, measured_first).mu_hat[
            GRID >= 16.0], 0.175)


@pytest.mark.parametrize(
    "vehicle, speed_mps, change_ahead_m",
    [("truck", 12.0, 30.0), ("car", 16.0, 10.0)],
    ids=["truck-drop-inside-the-arc", "car-drop-before-the-arc"],
)
def test_fsafe_relaxed_to_the_reported_value_keeps_the_lane_where_gt_does(
    vehicle, speed_mps, change_ahead_m
) -> None:
    # limits_general's 15 m arc, μ 0.9 → 0.3 (the camera: 0.25 ± 0.15). Relaxed towards the
    # class's upper edge, F-safe planned the low surface at 0.325: on 0068's code these runs
    # left the lane by 0.026 m (truck, the drop 10 m into the arc; turning left, 0.086 m with GT
    # in by 0.09 m) and spun 3.7 m out (car, the drop 10 m before it; GT in). Relaxed towards
    # the class's value, 0.25, both keep it (decision 0069).
    overrides = ["turn.start_ahead_m=20", "turn.clothoid_m=5", f"vehicle={vehicle}",
                 "turn.radius_m=15", f"initial_speed_mps={speed_mps}", "duration_s=6",
                 f"friction.change_ahead_m={change_ahead_m}", "friction.mu_before=0.9",
                 "friction.mu_turn=0.3"]
    log = run_scenario(load_scenario("turn", overrides), "F-safe")
    m = compute_metrics(log)
    assert m.max_lane_excursion_m == 0.0 and not m.spun
    assert (log.events["kind"] == EventKind.LANE_RECOVERY).any()
    estimates = log.estimates
    low = estimates[estimates["mu_true"] == 0.3]
    assert (low["mu_hat"] <= 0.3 + 1e-9).all()  # never planned the drop above its friction


@pytest.mark.slow
def test_an_evasion_inside_the_road_band_that_hits_turns_into_braking_without_a_posterior() -> None:
    # The double lane change on snow (μ 0.3): P's camera class bound is 0.1, with which neither
    # a stop nor an evasion fits in the 31 m. Its evasion stays inside the road band it may use
    # (so "keeps the lane" said nothing) and is predicted to hit; re-planned once more with its
    # own μ̂ (it has no posterior to take an upper edge from) it still hits, so it brakes in
    # lane. Measured: 13.8 m/s impact swerving, 12.3 m/s braking.
    from pathlib import Path

    file = Path(__file__).parents[2] / "examples" / "roads" / "double_lane_change_snow.toml"
    # (Braking however wide it meets the obstacle: weighed against the evasion's graze, the
    # futility check swerves at some steps and the impact is 13.7 m/s, docs/decisions/0126.)
    setting = ["duration_s=6.0", "lane_recovery.futility_weighs_contact=false"]
    braking = run_scenario(load_scenario(str(file), setting), "P")
    swerving = run_scenario(
        load_scenario(str(file), [*setting, "lane_recovery.brake_when_futile=false"]), "P")
    b, s = compute_metrics(braking), compute_metrics(swerving)
    assert b.collision and s.collision  # with μ̂ 0.1 no plan avoids it
    assert b.impact_speed_mps < s.impact_speed_mps - 1.0
    assert not _events(braking, EventKind.FUTILE_EVASION).empty
    assert _events(swerving, EventKind.FUTILE_EVASION).empty
