"""Safe mode's speed reference keeps a curve beyond the camera reachable on the lowest class
(docs/decisions/0084)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, seed, settings
from hypothesis import strategies as st

from mufusion.configurations.interface import (
    MU_HAT_MAX,
    MU_HAT_MIN,
    FrictionEstimate,
    step_source,
)
from mufusion.configurations.sources import make_estimator
from mufusion.estimators.classes import PAPER_CLASSES, SurfaceClass, class_table
from mufusion.estimators.sensor_model import SensorModel
from mufusion.metrics import compute_metrics
from mufusion.planner import UnseenRoad
from mufusion.planner.speed_profile import curve_speed_reference_mps, descent_limited_profile_mps
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_scenario


def _reference(kappa_1pm: float, unseen: UnseenRoad | None, stages_m: np.ndarray,
               speed_mps: float = 30.0) -> np.ndarray:
    def curvature(s: np.ndarray) -> np.ndarray:
        return np.where(np.asarray(s) >= 120.0, kappa_1pm, 0.0)

    def mu(s: np.ndarray) -> np.ndarray:
        return np.full(np.shape(s), 0.8)

    return curve_speed_reference_mps(
        stages_m, curvature, mu, 30.0, 0.9, 3.0, 0.8,
        unseen=None if unseen is None else (unseen.cap(mu), speed_mps))


@seed(84)
@settings(max_examples=40, deadline=None)
@given(kappa=st.sampled_from([0.0, 1 / 400, 1 / 200, 1 / 50, 1 / 15]),
       seen_m=st.floats(0.0, 150.0), floor=st.floats(0.05, 0.8), speed=st.floats(0.0, 40.0))
def test_the_unseen_floor_only_ever_lowers_the_reference_and_only_before_curves(
        kappa, seen_m, floor, speed) -> None:
    stages = np.linspace(0.0, 90.0, 31)
    held = _reference(kappa, None, stages)
    capped = _reference(kappa, UnseenRoad(seen_m, floor), stages, speed)
    assert np.all(capped <= held + 1e-9)
    if kappa == 0.0:  # a straight road asks for no speed whatever its friction
        np.testing.assert_allclose(capped, held)


def test_a_curve_beyond_the_sight_lowers_the_reference_no_faster_than_braking_allows() -> None:
    stages = np.arange(0.0, 91.0)
    held = _reference(1 / 200, None, stages)
    assert held[0] == pytest.approx(30.0)  # 0.8 holds the 200 m arc at 30 m/s with room
    # The floor's profile: the arc's limit on 0.1 (v² = 0.9·0.1·g·200), its ramp back to 51 m
    # (the step into the arc has no friction left to brake with) at 0.8 of 0.9·0.1·g, and the
    # seen 0.8's from 51 m back to the vehicle.
    g = 9.81
    floor_at_0 = g * (0.9 * 0.1 * 200.0 + 1.6 * 0.9 * 0.1 * 68.0 + 1.6 * 0.9 * 0.8 * 51.0)
    slow = _reference(1 / 200, UnseenRoad(50.0, 0.1), stages, speed_mps=20.0)
    assert slow[0] ** 2 == pytest.approx(floor_at_0, rel=1e-6)  # 29.1 m/s: a vehicle below it
    # A vehicle at 30 m/s is asked to brake from its own speed (no step) at the reference's
    # rate, 0.8 of 0.9·0.8·g: a ramp parallel to the floor's, 51 (m/s)² above it, until the
    # camera's estimate takes over.
    fast = _reference(1 / 200, UnseenRoad(50.0, 0.1), stages, speed_mps=30.0)
    assert fast[0] == pytest.approx(30.0)
    np.testing.assert_allclose(fast[:51] ** 2, 900.0 - 1.6 * 0.9 * 0.8 * g * stages[:51],
                               rtol=1e-9)
    assert np.all(fast[:51] ** 2 - slow[:51] ** 2 == pytest.approx(900.0 - floor_at_0))


def test_a_vehicle_below_the_floors_limit_regains_speed_up_to_it() -> None:
    # In a long 150 m arc on μ 0.9 whose far part lies beyond the camera: the floor's curve is
    # always 50 m ahead. A vehicle at 12 m/s, well below what the floor allows from here, is
    # asked to speed up (the regain pass's hold before a curve's lowest point is for curves
    # that exist, not for the hypothesis).
    def curvature(s: np.ndarray) -> np.ndarray:
        return np.full(np.shape(s), 1 / 150)

    def mu(s: np.ndarray) -> np.ndarray:
        return np.full(np.shape(s), 0.9)

    stages = np.linspace(0.0, 60.0, 41)
    unseen = UnseenRoad(50.0, 0.1)
    ref = curve_speed_reference_mps(stages, curvature, mu, 30.0, 0.9, 4.0, 0.8, (12.0, 1.5),
                                    (unseen.cap(mu), 12.0))
    held = curve_speed_reference_mps(stages, curvature, mu, 30.0, 0.9, 4.0, 0.8, (12.0, 1.5))
    assert ref[0] == pytest.approx(12.0)
    assert np.all(np.diff(ref[:21]) > 0.0)  # regaining over the first 30 m
    assert ref[20] > 14.0
    assert np.all(ref <= held + 1e-9) and ref[-1] < held[-1] - 4.0  # the floor still lowers it


def test_a_vehicle_cornering_beyond_the_share_is_asked_for_no_braking() -> None:
    # A 150 m arc on μ 0.3: at 17 m/s 1.93 m/s² of lateral against 0.8 of 0.9·0.3·g = 2.12 (some
    # braking left), at 18 m/s 2.16 (none).
    s = np.arange(0.0, 31.0)
    kappa, mu = np.full(s.size, 1 / 150), np.full(s.size, 0.3)
    floor = np.full(s.size, 11.0)
    held = descent_limited_profile_mps(s, kappa, mu, 0.9, floor, 17.0, 0.8)
    braking = np.sqrt((0.8 * 0.9 * 0.3 * 9.81) ** 2 - (17.0**2 / 150) ** 2)
    assert held[1] ** 2 == pytest.approx(17.0**2 - 2 * braking, rel=1e-12)  # within the share
    assert np.all(descent_limited_profile_mps(s, kappa, mu, 0.9, floor, 18.0, 0.8) == 18.0)


@pytest.mark.parametrize("from_s_m, mu, field", [(float("nan"), 0.1, "from_s_m"),
                                                  (50.0, 0.0, "mu"), (50.0, 2.5, "mu")])
def test_an_unseen_road_names_its_bad_field(from_s_m, mu, field) -> None:
    with pytest.raises(ValueError, match=rf"UnseenRoad\.{field}"):
        UnseenRoad(from_s_m, mu)


def test_the_scenario_switch_reaches_the_built_source() -> None:
    on = build_loop(load_scenario("turn", []), friction="F-safe")
    off = build_loop(load_scenario("turn", ["estimation.safe_beyond_camera=false"]),
                     friction="F-safe")
    assert on.friction.unseen_mu == pytest.approx(0.1) and off.friction.unseen_mu is None
    with pytest.raises(ValueError, match=r"estimation\.safe_beyond_camera"):
        load_scenario("turn", ["estimation.safe_beyond_camera=2"])


def test_safe_configurations_declare_the_lowest_class_beyond_their_grid() -> None:
    assert make_estimator("F-safe").unseen_mu == pytest.approx(0.1)
    assert make_estimator("F").unseen_mu is None
    table = [SurfaceClass("snow/ice", 0.2, 0.4, 0.3, 0.1), *PAPER_CLASSES[1:]]
    assert make_estimator("F-safe", classes=table).unseen_mu == pytest.approx(0.2)
    # The authors' rounding scheme's lowest class starts at 0: μ̂'s floor instead.
    assert make_estimator("F-safe", classes=class_table("authors")).unseen_mu == MU_HAT_MIN


class _Declaring:
    """A plug-in source declaring ``unseen_mu`` beyond its grid."""

    def __init__(self, unseen_mu: float) -> None:
        self.unseen_mu = unseen_mu

    def step(self, frame):
        s = frame.s_ahead_m
        return FrictionEstimate(s, np.full(s.shape, 0.5), False, None, unseen_mu=self.unseen_mu)


def _stepped(source) -> FrictionEstimate:
    s = np.linspace(0.0, 50.0, 11)
    return step_source(source, SensorModel(rng=np.random.default_rng(0)), s, np.full(s.shape, 0.6),
                       0.0)


def test_a_plug_ins_unseen_friction_is_clipped_as_mu_hat_or_refused_by_name() -> None:
    assert _stepped(_Declaring(0.2)).unseen_mu == pytest.approx(0.2)
    assert _stepped(_Declaring(0.0)).unseen_mu == MU_HAT_MIN
    assert _stepped(_Declaring(3.0)).unseen_mu == MU_HAT_MAX
    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValueError, match=r"_Declaring.*non-finite unseen_mu"):
            _stepped(_Declaring(bad))


# A truck at 30 m/s with a 200 m arc 100 m ahead, the friction dropping 0.7 → 0.15 110 m ahead
# (examples/limits_turn_heldout3.toml; GT keeps its lane). The camera sees the drop 50 m before
# it: braking from 30 m/s to the arc's limit on 0.15 then needs more than safe mode's 0.7 lower
# bound gives over 50 m.
_BEYOND_THE_CAMERA = [
    "vehicle=truck", "turn.radius_m=200", "turn.angle_rad=1.2", "initial_speed_mps=30",
    "turn.start_ahead_m=100", "turn.clothoid_m=20", "turn.direction=left", "duration_s=16",
    "friction.change_ahead_m=110", "friction.mu_before=0.7", "friction.mu_turn=0.15"]


@pytest.mark.slow
@pytest.mark.parametrize("switch, keeps_lane", [("true", True), ("false", False)],
                         ids=["lowest-class-beyond", "last-value-held"])
def test_safe_mode_keeps_a_curve_beyond_the_camera_reachable(switch, keeps_lane) -> None:
    cfg = load_scenario("turn", [*_BEYOND_THE_CAMERA, f"estimation.safe_beyond_camera={switch}"])
    m = compute_metrics(run_scenario(cfg, "F-safe"))
    if keeps_lane:
        assert m.max_lane_excursion_m == 0.0 and not m.spun
    else:
        assert m.max_lane_excursion_m > 1.0
