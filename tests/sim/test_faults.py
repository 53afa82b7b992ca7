"""Injected faults: each is logged, the loop reacts as documented, and no run loses its log."""

from __future__ import annotations

import numpy as np
import pytest

from factories import run_meta
from mufusion.configurations import make_estimator
from mufusion.metrics import compute_metrics
from mufusion.planner import PlannerConfig, TrackingController, TractionAdaptivePlanner
from mufusion.planner.safety import SafetySettings
from mufusion.road import FrictionMap, straight_road
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.sim.faults import Fault
from mufusion.sim.loop import ClosedLoop, LoopRates
from mufusion.sim.world import World
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.plant import Plant, initial_state

# Closed-loop runs of several seconds each: outside the fast subset (pytest -m 'not slow').
pytestmark = pytest.mark.slow


def _popup(*faults: str, duration_s: float = 2.5, config: str = "F", extra=()):
    overrides = [f"duration_s={duration_s}", *extra]
    if faults:
        overrides.append(f"faults=[{', '.join(faults)}]")
    return run_scenario(load_scenario("popup", overrides), config)


def _events(log, kind: str):
    ev = log.events
    return ev[ev["kind"] == kind]


def test_nan_estimate_once_is_replaced_and_the_planner_never_sees_it() -> None:
    log = _popup('{kind="estimate_nan", start_s=1.0, duration_s=0.1}')
    steps = log.planning_steps
    hit = steps[np.isclose(steps["t_s"], 1.0)]
    assert hit["estimate_source"].tolist() == ["last_valid"]
    assert hit["estimate_age_s"].iloc[0] == pytest.approx(0.1)
    # Within two planning steps everything is back to normal: current estimate, no fallback.
    after = steps[steps["t_s"] >= 1.1 - 1e-9]
    assert (after["estimate_source"] == "current").all()
    assert not after["fallback"].any()
    assert np.isfinite(log.plans["mu_hat"]).all()
    m = compute_metrics(log)
    assert m.faults_injected == 1 and m.estimate_fallbacks == 1 and not m.minimal_risk


def test_stale_estimate_is_handled_like_a_missing_one() -> None:
    # A 0.5 s delay exceeds the 0.35 s the loop accepts: last valid estimate while it is young
    # enough, then the friction floor.
    log = _popup('{kind="estimate_delay", start_s=0.5, duration_s=1.0, delay_s=0.5}')
    steps = log.planning_steps
    during = steps[(steps["t_s"] >= 0.5 - 1e-9) & (steps["t_s"] < 1.5 - 1e-9)]
    assert set(during["estimate_source"]) == {"last_valid", "floor"}
    floor = during[during["estimate_source"] == "floor"]
    assert len(floor) >= 5
    est = log.estimates
    floor_rows = est[est["t_s"].isin(floor["t_s"])]
    np.testing.assert_allclose(floor_rows["mu_hat"], 0.1)
    assert (steps[steps["t_s"] >= 1.5 - 1e-9]["estimate_source"] == "current").all()


def test_shorter_delay_than_the_limit_passes_through_as_delayed() -> None:
    log = _popup('{kind="estimate_delay", start_s=0.5, duration_s=0.5, delay_s=0.2}')
    steps = log.planning_steps
    during = steps[(steps["t_s"] >= 0.5 - 1e-9) & (steps["t_s"] < 1.0 - 1e-9)]
    assert set(during["estimate_source"]) == {"delayed"}
    np.testing.assert_allclose(during["estimate_age_s"], 0.2, atol=1e-9)


def test_solver_failure_escalates_to_the_minimal_risk_manoeuvre_after_k_steps() -> None:
    log = _popup('{kind="solver_failure", start_s=0.5, duration_s=5.0}', duration_s=3.0,
                 extra=["safety.max_consecutive_fallbacks=4"])
    mrm = _events(log, "minimal_risk")
    # Failures at 0.5, 0.6, 0.7, 0.8 s: the fourth in a row triggers the manoeuvre.
    assert mrm["t_s"].tolist() == pytest.approx([0.8])
    ts = log.timeseries
    assert (ts[ts["t_s"] > 0.8 + 1e-9]["control_mode"] == "minimal_risk").all()
    # Braking in lane: the speed falls, the vehicle stays on the road.
    late = ts[ts["t_s"] > 1.5]
    assert late["speed_mps"].iloc[-1] < ts["speed_mps"].iloc[0] - 3.0
    m = compute_metrics(log)
    assert m.minimal_risk and m.minimal_risk_at_s == pytest.approx(0.8)
    assert m.fallbacks >= 20


@pytest.mark.parametrize("kind", ["camera_dropout", "camera_nan"])
def test_camera_faults_leave_fusion_without_predictive_data(kind: str) -> None:
    log = _popup(f'{{kind="{kind}", start_s=0.5, duration_s=0.5}}', duration_s=1.2)
    est = log.estimates
    during = est[(est["t_s"] >= 0.5 - 1e-9) & (est["t_s"] < 1.0 - 1e-9)]
    before = est[est["t_s"] < 0.5 - 1e-9]
    # No camera point beyond the local estimate's reach (5 m) while the camera is out.
    assert not during[during["s_ahead_m"] >= 5.0]["data_mu"].notna().any()
    assert before[before["s_ahead_m"] >= 5.0]["data_mu"].notna().any()
    assert not compute_metrics(log).collision or kind == "camera_nan"


def test_local_dropout_keeps_the_local_estimator_from_measuring() -> None:
    log = _popup('{kind="local_dropout", start_s=0.0, duration_s=3.0}', duration_s=2.0)
    assert not log.planning_steps["local_available"].any()
    normal = _popup(duration_s=2.0)
    assert normal.planning_steps["local_available"].any()


class _Raising:
    """A friction source that works, then raises from ``fail_at`` steps on."""

    channels = frozenset()

    def __init__(self, fail_at: int) -> None:
        self.calls = 0
        self.fail_at = fail_at

    def step(self, frame):
        self.calls += 1
        if self.calls > self.fail_at:
            raise RuntimeError("sensor bus down")
        return np.full(frame.s_ahead_m.shape, 0.8)


class _RaisingPlanner(TractionAdaptivePlanner):
    def __init__(self, fail_after: int) -> None:
        super().__init__(TRUCK, PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45))
        self.count, self.fail_after = 0, fail_after

    def step(self, *args, **kwargs):
        self.count += 1
        if self.count > self.fail_after:
            raise FloatingPointError("boom")
        return super().step(*args, **kwargs)


def _loop(friction=None, planner=None, safety: SafetySettings | None = None):
    road = straight_road(400.0, friction=FrictionMap.uniform(0.8))
    world = World(road, to_planner_obstacle=lambda o: o)
    planner = planner or TractionAdaptivePlanner(
        TRUCK, PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45))
    return ClosedLoop(
        world=world, params=TRUCK,
        plant=Plant(TRUCK, initial_state(TRUCK, 30.0, 0.0, 0.0, 15.0)),
        planner=planner, controller=TrackingController(TRUCK, planner.config),
        friction=friction or make_estimator("GT"), rates=LoopRates(),
        reference_speed_mps=15.0, lane_bounds_m=(-0.45, 0.45), meta=run_meta(),
        safety=safety or SafetySettings(),
    )


def test_a_friction_source_that_raises_ends_in_the_minimal_risk_manoeuvre_with_its_log() -> None:
    # One call in the warm-up, then t = 0, 0.1, ...: the ninth call (t = 0.7 s) raises.
    log = _loop(friction=_Raising(fail_at=8)).run(2.0, warmup_steps=2)
    errors = _events(log, "friction_source_error")
    assert len(errors) >= 1 and "sensor bus down" in errors["detail"].iloc[0]
    assert _events(log, "minimal_risk")["t_s"].tolist() == pytest.approx([0.7])
    assert log.timeseries["t_s"].iloc[-1] == pytest.approx(2.0)  # the run went on
    assert (log.planning_steps[log.planning_steps["t_s"] > 0.65]["mode"] == "minimal_risk").all()
    # Braking in lane at half the floor friction (0.5 · 0.1 g ≈ 0.5 m/s²): slow, but braking.
    ts = log.timeseries
    at_mrm = float(ts[ts["t_s"] <= 0.7 + 1e-9]["speed_mps"].iloc[-1])
    assert ts["speed_mps"].iloc[-1] < at_mrm - 0.5
    assert ts["d_m"].abs().max() < 0.5


def test_a_planner_that_raises_is_survived_and_escalates() -> None:
    planner = _RaisingPlanner(fail_after=5)
    log = _loop(planner=planner, safety=SafetySettings(max_consecutive_fallbacks=3)).run(
        2.0, warmup_steps=2)
    assert len(_events(log, "planner_error")) >= 3
    m = compute_metrics(log)
    assert m.minimal_risk and m.component_errors >= 3 and not m.collision
    assert log.timeseries["t_s"].iloc[-1] == pytest.approx(2.0)
    assert log.timeseries["speed_mps"].iloc[-1] < log.timeseries["speed_mps"].iloc[0]


def test_bad_faults_and_settings_are_rejected_up_front() -> None:
    with pytest.raises(ValueError, match="delay_s must be > 0"):
        Fault("estimate_delay", 1.0, 1.0)
    with pytest.raises(ValueError, match="kind must be one of"):
        Fault("gremlins", 1.0, 1.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="max_consecutive_fallbacks"):
        SafetySettings(max_consecutive_fallbacks=0)
    with pytest.raises(ValueError, match=r"faults\.0\.start_s must be before duration_s"):
        load_scenario("popup", ['faults=[{kind="camera_nan", start_s=7, duration_s=1}]'])


def test_a_friction_source_that_raises_from_its_first_call_still_gives_a_run() -> None:
    # The warm-up's estimate is the source's first call: a plug-in estimator broken from the
    # start used to end the run there, before its first tick, with an empty time series.
    log = _loop(friction=_Raising(fail_at=0)).run(2.0, warmup_steps=2)
    assert _events(log, "loop_error").empty
    assert len(_events(log, "friction_source_error")) >= 1
    assert _events(log, "minimal_risk")["t_s"].iloc[0] == pytest.approx(0.0)
    assert log.timeseries["t_s"].iloc[-1] == pytest.approx(2.0)
    assert compute_metrics(log).minimal_risk


def test_a_planner_that_raises_in_the_warm_up_is_survived() -> None:
    log = _loop(planner=_RaisingPlanner(fail_after=0),
                safety=SafetySettings(max_consecutive_fallbacks=3)).run(2.0, warmup_steps=2)
    assert _events(log, "loop_error").empty
    assert len(_events(log, "planner_error")) >= 1
    assert log.timeseries["t_s"].iloc[-1] == pytest.approx(2.0)
    assert compute_metrics(log).minimal_risk
