"""The probe's trigger reads the road as far as the planner plans, past the camera's grid
(docs/decisions/0101)."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.configurations import FrictionEstimate
from mufusion.fusion import FusedEstimate
from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.sim.events import EventKind
from mufusion.sim.probing import Probing
from mufusion.sim.supervision import Prober, ProbingSettings, RoadBeyond
from mufusion.vehicle.params import CAR

GRID = np.arange(0.0, 51.0)
CURVE_M = 68.0


def _estimate(unseen_mu: float | None = None) -> FrictionEstimate:
    post = FusedEstimate(GRID, np.full(51, 0.32), np.full(51, 0.05), np.full(51, 0.1),
                         np.full(51, 0.1))
    return FrictionEstimate(GRID, np.full(51, 0.1), False, None, fused=post,
                            unseen_mu=unseen_mu)


def _curvature(s_m: np.ndarray) -> np.ndarray:
    return np.where(np.asarray(s_m) >= CURVE_M, 1.0 / 64.0, 0.0)


def test_a_curve_past_the_grid_starts_a_probe_only_when_the_trigger_reads_past_it() -> None:
    prober = Prober(ProbingSettings(), utilization_factor=0.9)
    on_grid = _curvature(GRID)
    assert prober.reason_to_probe(0.0, 19.7, _estimate(), on_grid, obstacle_near=False) is None
    s = np.arange(51.0, 80.0)
    beyond = RoadBeyond(s, _curvature(s), np.full(s.shape, 0.1))
    why = prober.reason_to_probe(0.0, 19.7, _estimate(), on_grid, False, lambda: beyond)
    # 19.7² / (64 · 9.81) = 0.62 needed at 68 m, 0.9 · 0.1 granted.
    assert why is not None and "68 m ahead needs μ 0.62" in why and "grants 0.09" in why


@pytest.mark.parametrize(
    ("settings", "speed_mps", "unseen_mu", "expected"),
    [
        (ProbingSettings(), 19.7, 0.1, (51.0, 79.0, 0.1)),  # past 19.7 m/s × 4 s, declared μ
        (ProbingSettings(), 19.7, None, (51.0, 79.0, 0.1)),  # the grid's last value holds
        (ProbingSettings(), 12.0, 0.1, None),  # 48 m: inside the grid
        (ProbingSettings(beyond_camera=False), 19.7, 0.1, None),
    ],
)
def test_the_road_read_past_the_grid_reaches_the_planners_horizon(
    settings, speed_mps, unseen_mu, expected
) -> None:
    probing = Probing(settings, 0.9, 4.0, CAR, GRID, _curvature, lambda *_: None)
    beyond = probing._beyond(0.0, speed_mps, _estimate(unseen_mu))
    if expected is None:
        assert beyond is None
        return
    first, last, mu = expected
    assert beyond.s_m[0] == first and beyond.s_m[-1] == last
    assert np.all(beyond.mu_hat == mu)
    np.testing.assert_array_equal(beyond.curvature_1pm, _curvature(beyond.s_m))


@pytest.mark.slow
def test_f_safe_keeps_its_lane_where_a_same_class_drop_lies_past_the_camera_at_the_start():
    # The edge draw's car (docs/decisions/0100): μ 0.27 → 0.15 at a 64 m arc 78 m ahead, both
    # inside the camera's snow/ice class; the curve is 68 m ahead at the start, past the 50 m
    # grid. Reading only the grid, the probe waited until the curve came within 50 m (1.1 s),
    # the car braked on μ̂ 0.10 meanwhile and reached the arc at 10.6 m/s: 3.6 m out.
    overrides = ["vehicle=car", "turn.radius_m=64", "turn.angle_rad=2.48", "turn.clothoid_m=10",
                 "turn.start_ahead_m=68", "friction.change_ahead_m=78",
                 "friction.mu_before=0.27", "friction.mu_turn=0.15", "road.lane_width_m=4.0",
                 "turn.direction=left", "initial_speed_mps=19.7", "duration_s=14"]
    runs = {}
    for beyond in (True, False):
        cfg = load_scenario("turn", [*overrides, f"probing.beyond_camera={str(beyond).lower()}"])
        log = run_scenario(cfg, "F-safe")
        starts = log.events[log.events["kind"] == EventKind.PROBE_START]
        runs[beyond] = (compute_metrics(log), float(starts["t_s"].iloc[0]))
    (kept, kept_probe_s), (left, left_probe_s) = runs[True], runs[False]
    assert kept_probe_s == 0.0 and left_probe_s >= 1.0
    assert not kept.left_lane
    assert left.left_lane and left.max_lane_excursion_m > 1.0
