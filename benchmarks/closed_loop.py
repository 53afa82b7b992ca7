"""Closed-loop speed: real-time factor of the paper scenarios and where the time goes.

Run: ``python benchmarks/closed_loop.py [--repeat N] [--breakdown-runs M] [--configuration F]
[--blas-threads K] [--method product|paper]``.
For each paper scenario (``turn``: 12 s simulated, ``popup``: 6 s) one untimed run
compiles/loads the solver, then ``N`` timed runs give the real-time factor (simulated s / wall s
of ``run_scenario``, median and best) and the same against the process's CPU time, which other
jobs on a shared machine disturb far less than the wall clock (best: the least disturbed run).
``M`` more runs (default 1) with every component's methods wrapped in CPU-time accumulators
(``time.process_time``) give the breakdown by stage of the fastest of them (exclusive time: a
world call made from inside the planner counts for the world, not twice). The wrappers add about
a microsecond per call, so that run's own factor is printed too.
``--method paper`` runs the scenarios with the paper's method, as the reproduction does
(``mufusion.reproduction.variants.PAPER_METHOD``: no probing, lane recovery, curve speed
reference, stop-first, front-force rate or torque preview); the default is the product's
defaults. ``--blas-threads 1`` limits the BLAS thread pools to one thread (the fusion's small matrix
products gain nothing from threads on a busy 2-core machine). ``--set KEY=VALUE`` adds a
scenario override (repeatable), e.g. a longer camera range. Numbers go to docs/performance.md,
section "## Closed loop".
"""

from __future__ import annotations

import argparse
import functools
import json
import statistics
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from threadpoolctl import threadpool_limits

from mufusion.configurations import FrictionConfiguration
from mufusion.estimators import SensorModel
from mufusion.planner import TrackingController, TractionAdaptivePlanner
from mufusion.planner.acados_backend import AcadosBackend
from mufusion.reproduction.variants import PAPER_METHOD
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.sim.log import RunLog
from mufusion.sim.loop import ClosedLoop
from mufusion.sim.recorder import Recorder
from mufusion.sim.world import World
from mufusion.vehicle.plant import Plant

SCENARIOS = ("turn", "popup")
METHODS = {"product": (), "paper": PAPER_METHOD}
"""Scenario overrides per ``--method``: the product's defaults, or the paper's method."""
# The planner's time is split into its own Python, the acados backend's Python (writing the
# problem, reading the plan) and the acados solve itself (C).
STAGES = ("plant", "planner", "acados backend", "acados solve (C)", "controller",
          "estimation+fusion", "geometry/world", "logging", "loop/other", "setup")


class StageClock:
    """Exclusive wall time per stage: a call's time minus that of the timed calls inside it."""

    def __init__(self, clock: Callable[[], float] = time.process_time) -> None:
        self.clock = clock
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._children: list[float] = []

    def wrap(self, stage: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(fn)
        def timed(*args: Any, **kwargs: Any) -> Any:
            self._children.append(0.0)
            start = self.clock()
            try:
                return fn(*args, **kwargs)
            finally:
                elapsed = self.clock() - start
                inner = self._children.pop()
                self.seconds[stage] += elapsed - inner
                self.calls[stage] += 1
                if self._children:
                    self._children[-1] += elapsed

        return timed


def _public_methods(cls: type) -> Iterator[str]:
    """Names of the plain and static methods a class defines itself (not properties)."""
    for name, value in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(value, staticmethod) or callable(value):
            yield name


class _TimedSolver:
    """The generated acados solver with its ``solve`` timed (the other calls pass through)."""

    def __init__(self, solver: Any, clock: StageClock) -> None:
        self._solver = solver
        self.solve = clock.wrap("acados solve (C)", solver.solve)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._solver, name)


@contextmanager
def instrumented(clock: StageClock) -> Iterator[None]:
    """Wrap the components' methods with the clock for the duration of the block."""
    targets: list[tuple[type, str, str]] = [
        (Plant, "step", "plant"),
        (TractionAdaptivePlanner, "step", "planner"),
        (TrackingController, "command", "controller"),
        (ClosedLoop, "run", "loop/other"),
        (AcadosBackend, "solve", "acados backend"),
        (SensorModel, "frame", "estimation+fusion"),
    ]
    configurations = [FrictionConfiguration]
    while configurations:
        cls = configurations.pop()
        configurations.extend(cls.__subclasses__())
        if "step" in vars(cls):
            targets.append((cls, "step", "estimation+fusion"))
    targets += [(World, name, "geometry/world") for name in _public_methods(World)]
    targets += [(Recorder, name, "logging") for name in ("tick", "planning_step", "event")]
    targets += [(RunLog, "frame", "logging")]
    saved = [(cls, name, vars(cls)[name]) for cls, name, _ in targets]
    saved.append((AcadosBackend, "__init__", AcadosBackend.__init__))
    backend_init = AcadosBackend.__init__

    def timed_init(self: AcadosBackend, *args: Any, **kwargs: Any) -> None:
        backend_init(self, *args, **kwargs)
        for generated in self.solvers():
            generated.solver = _TimedSolver(generated.solver, clock)

    try:
        AcadosBackend.__init__ = timed_init  # type: ignore[method-assign]
        for cls, name, stage in targets:
            original = vars(cls)[name]
            if isinstance(original, staticmethod):
                setattr(cls, name, staticmethod(clock.wrap(stage, original.__func__)))
            else:
                setattr(cls, name, clock.wrap(stage, original))
        yield
    finally:
        for cls, name, original in saved:
            setattr(cls, name, original)


def _simulated_s(log: RunLog) -> float:
    return float(log.timeseries["t_s"].iloc[-1])


def measure(name: str, configuration: str, repeat: int, breakdown_runs: int = 1,
            method: str = "product", overrides: list[str] | None = None) -> dict[str, Any]:
    cfg = load_scenario(name, [*METHODS[method], *(overrides or [])])
    run_scenario(cfg, configuration)  # solver generated/compiled/loaded, caches warm
    wall_factors: list[float] = []
    cpu_factors: list[float] = []
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        log = run_scenario(cfg, configuration)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        wall_factors.append(_simulated_s(log) / wall)
        cpu_factors.append(_simulated_s(log) / cpu)
    clock, cpu = StageClock(), float("inf")
    for _ in range(breakdown_runs):
        trial = StageClock()
        with instrumented(trial):
            start = trial.clock()
            log = run_scenario(cfg, configuration)
            elapsed = trial.clock() - start
        if elapsed < cpu:
            clock, cpu = trial, elapsed
    clock.seconds["setup"] = cpu - sum(clock.seconds.values())
    return {
        "scenario": name,
        "configuration": configuration,
        "method": method,
        "simulated_s": _simulated_s(log),
        "realtime_factor_median": statistics.median(wall_factors),
        "realtime_factor_best": max(wall_factors),
        "cpu_realtime_factor_median": statistics.median(cpu_factors),
        "cpu_realtime_factor_best": max(cpu_factors),
        "instrumented_cpu_s": cpu,
        "instrumented_cpu_realtime_factor": _simulated_s(log) / cpu,
        "stage_ms": {stage: 1e3 * clock.seconds.get(stage, 0.0) for stage in STAGES},
        "stage_calls": {stage: clock.calls.get(stage, 0) for stage in STAGES},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per scenario (≥ 1)")
    parser.add_argument("--breakdown-runs", type=int, default=1,
                        help="instrumented runs; the fastest gives the breakdown (≥ 1)")
    parser.add_argument("--configuration", default="F", help="friction configuration")
    parser.add_argument("--blas-threads", type=int, default=None,
                        help="limit BLAS/OpenMP thread pools to this many threads (≥ 1)")
    parser.add_argument("--method", choices=sorted(METHODS), default="product",
                        help="the product's defaults or the paper's method (as reproduced)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a scenario override on top of the method's, as `mufusion run "
                             "--set` (repeatable), e.g. estimation.camera_range_m=120")
    args = parser.parse_args()
    if args.repeat < 1:
        raise ValueError(f"--repeat must be >= 1, got {args.repeat}")
    if args.breakdown_runs < 1:
        raise ValueError(f"--breakdown-runs must be >= 1, got {args.breakdown_runs}")
    if args.blas_threads is not None and args.blas_threads < 1:
        raise ValueError(f"--blas-threads must be >= 1, got {args.blas_threads}")
    for name in SCENARIOS:
        with threadpool_limits(limits=args.blas_threads):
            result = measure(name, args.configuration, args.repeat, args.breakdown_runs,
                             args.method, args.set)
        result["blas_threads"] = args.blas_threads
        cpu_ms = 1e3 * result["instrumented_cpu_s"]
        print(f"{name} ({args.configuration}, {args.method}, "
              f"{result['simulated_s']:.1f} s simulated): "
              f"real-time factor {result['realtime_factor_median']:.1f}x median, "
              f"{result['realtime_factor_best']:.1f}x best of {args.repeat} (wall clock); "
              f"{result['cpu_realtime_factor_median']:.1f}x median, "
              f"{result['cpu_realtime_factor_best']:.1f}x best on CPU time")
        print(f"  breakdown (fastest of {args.breakdown_runs} instrumented runs, "
              f"{cpu_ms:.0f} ms CPU, "
              f"{result['instrumented_cpu_realtime_factor']:.1f}x):")
        for stage in STAGES:
            ms = result["stage_ms"][stage]
            print(f"    {stage:18s} {ms:8.1f} ms  {100 * ms / cpu_ms:5.1f} %  "
                  f"({result['stage_calls'][stage]} calls)")
        print(json.dumps(result))


if __name__ == "__main__":
    main()
