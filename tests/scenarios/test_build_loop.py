"""build_loop assembles a scenario's loop around a friction source of your own: it reads the
sensor frame and the vehicle's signals, is labelled by its name, and its faults are survived."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.configurations import FrictionEstimator
from mufusion.configurations.plugins import PluginError
from mufusion.estimators import SensorFrame, VehicleSignals
from mufusion.planner import TrackingController, TractionAdaptivePlanner
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import WARMUP_PLANNING_STEPS, build_loop

DURATION_S = 0.6


class Watching(FrictionEstimator):
    """Records what it is given; μ̂ = the slip report minus its margin."""

    def __init__(self, fail_after: int | None = None) -> None:
        self.frames: list[SensorFrame] = []
        self.signals: list[VehicleSignals] = []
        self.fail_after = fail_after

    def observe(self, signals: VehicleSignals) -> None:
        self.signals.append(signals)

    def step(self, frame: SensorFrame) -> np.ndarray:
        self.frames.append(frame)
        if self.fail_after is not None and len(self.frames) > self.fail_after:
            raise RuntimeError("estimator diverged")
        return np.full(frame.s_ahead_m.shape, frame.slip.mu - frame.slip.margin)


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("popup", [f"duration_s={DURATION_S}"])


def test_a_source_of_your_own_reads_frames_and_signals_and_labels_the_run(scenario) -> None:
    source = Watching()
    loop = build_loop(scenario, friction=source)
    log = loop.run(DURATION_S, warmup_steps=WARMUP_PLANNING_STEPS)
    assert log.meta.configuration == "Watching" and log.meta.builtin is None
    assert len(log.planning_steps) == len(source.frames) - 1  # one warm-up frame first
    rates = loop.rates
    # Every plant step's signals, stamped with the step's end, over the whole run.
    times = np.array([s.t_s for s in source.signals])
    assert np.allclose(times, np.arange(1, times.size + 1) / rates.plant_hz)
    assert times[-1] >= DURATION_S
    first = source.signals[0]
    # Rolling freely at the start: the wheel-speed sensors agree with the speed over ground.
    assert first.wheel_speed_front_radps * first.wheel_radius_m == pytest.approx(
        first.speed_x_mps, rel=0.02)
    # A frame's signals are those of the latest plant step before it.
    later = source.frames[-1]
    assert later.signals is not None and later.signals.t_s == pytest.approx(later.t_s)
    assert source.frames[0].signals is None  # the warm-up, before any plant step


def test_a_source_that_raises_during_the_run_is_survived_and_logged(scenario) -> None:
    log = build_loop(scenario, friction=Watching(fail_after=3)).run(
        DURATION_S, warmup_steps=WARMUP_PLANNING_STEPS)
    kinds = list(log.frame("events")["kind"])
    assert "friction_source_error" in kinds and "minimal_risk" in kinds
    assert "loop_error" not in kinds
    assert log.timeseries["t_s"].iloc[-1] == pytest.approx(DURATION_S)


def test_a_source_of_your_own_may_not_take_a_builtin_label(scenario) -> None:
    class Impostor(Watching):
        name = "F"  # type: ignore[assignment]

    with pytest.raises(ValueError, match="labelled 'F', a built-in configuration's name"):
        build_loop(scenario, friction=Impostor())


class CountingController(TrackingController):
    """The package's controller, counting its commands (a controller plug-in)."""

    commands = 0

    def command(self, *args, **kwargs):
        type(self).commands += 1
        return super().command(*args, **kwargs)


class NotAPlanner:
    def step(self, *args, **kwargs):
        return None


def test_a_controller_plugin_named_by_import_path_drives_and_is_recorded(scenario) -> None:
    spec = f"{__name__}:CountingController"
    CountingController.commands = 0
    loop = build_loop(scenario, friction="GT", controller=spec)
    log = loop.run(DURATION_S, warmup_steps=WARMUP_PLANNING_STEPS)
    assert isinstance(loop.controller, CountingController)
    assert CountingController.commands == len(log.timeseries)
    assert log.meta.controller_plugin == spec and log.meta.planner_plugin is None


def test_a_planner_plugin_without_its_protocol_is_refused_naming_it(scenario) -> None:
    spec = f"{__name__}:NotAPlanner"
    with pytest.raises(PluginError, match=f"'{spec}' is not a planner: NotAPlanner has no "
                                          "callable restore"):
        build_loop(scenario, planner=spec)


class OlderPlanner(TractionAdaptivePlanner):
    """The package's planner behind the protocol's step before ``unseen_road`` existed."""

    steps = 0

    def step(self, x0, t_s, curvature_of_s, mu_hat_of_s, obstacles=(), mode="cruise",
             reference_speed_mps=10.0, reference_d_m=0.0, lane_d_min_m=None, lane_d_max_m=None,
             front_force_n=None, longitudinal_forces_n=None):
        type(self).steps += 1
        return super().step(x0, t_s, curvature_of_s, mu_hat_of_s, obstacles, mode,
                            reference_speed_mps, reference_d_m, lane_d_min_m, lane_d_max_m,
                            front_force_n, longitudinal_forces_n)


@pytest.mark.parametrize("friction, told", [("F-safe", True), ("F", False)])
def test_a_planner_without_unseen_road_still_plans_and_the_log_says_what_it_ignores(
        scenario, friction, told) -> None:
    OlderPlanner.steps = 0
    log = build_loop(scenario, friction=friction, planner=f"{__name__}:OlderPlanner").run(
        DURATION_S, warmup_steps=WARMUP_PLANNING_STEPS)
    kinds = list(log.frame("events")["kind"])
    assert OlderPlanner.steps >= len(log.planning_steps) > 0
    assert "planner_error" not in kinds and "minimal_risk" not in kinds
    assert kinds.count("unseen_road_ignored") == (1 if told else 0)


def test_the_log_names_the_solver_the_planner_ran(scenario, monkeypatch) -> None:
    """A planner configured for acados that cannot load it runs the CasADi reference: the run's
    metadata and its metrics say which one ran, not which one was configured."""
    from mufusion.metrics import compute_metrics
    from mufusion.planner import acados_backend

    loop = build_loop(scenario, friction="GT")
    assert loop.meta.planner_backend == "AcadosBackend"

    def unavailable(*args, **kwargs):
        raise OSError("libacados.so: cannot open shared object file")

    monkeypatch.setattr(acados_backend.AcadosBackend, "__init__", unavailable)
    loop = build_loop(scenario, friction="GT")
    assert scenario.planner.backend == "acados"
    assert loop.meta.planner_backend == "CasadiBackend"
    log = loop.run(0.2, warmup_steps=1)
    assert compute_metrics(log).planner_backend == "CasadiBackend"
