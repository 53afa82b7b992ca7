"""Campaigns: many scenario variants × friction configurations, run in parallel processes.

A campaign is a list of :class:`RunSpec` (a scenario file or name, overrides and a configuration);
each run is independent and deterministic, so the same list gives the same logs on a laptop (a
process pool) or on a cluster (one :func:`run_spec` per job, e.g. ``mufusion run`` in an array job).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from mufusion.metrics import RunMetrics, attach_gt_comparison, compute_metrics
from mufusion.scenarios.config import load_scenario
from mufusion.scenarios.runner import planner_for, run_scenario


@dataclass(frozen=True)
class RunSpec:
    """One run of a campaign.

    Attributes
    ----------
    scenario
        Built-in scenario name or path of a TOML file.
    config
        Friction-estimation configuration: ``GT``, ``L``, ``P``, ``F`` or ``F-safe``.
    variant
        Label of the scenario variant (e.g. ``"paper μ = 1.0"``), used in tables and paths.
    overrides
        ``dotted.key=value`` overrides applied to the scenario file.
    """

    scenario: str
    config: str
    variant: str = "default"
    overrides: tuple[str, ...] = field(default_factory=tuple)

    @property
    def slug(self) -> str:
        safe = "".join(c if c.isalnum() else "-" for c in self.variant).strip("-").lower()
        return f"{self.scenario}-{safe}-{self.config}".replace("--", "-")


def run_spec(spec: RunSpec, out_root: Path) -> tuple[RunSpec, RunMetrics, Path]:
    """Run one spec, save its log under ``out_root/<slug>`` and return its metrics."""
    cfg = load_scenario(spec.scenario, list(spec.overrides))
    log = run_scenario(cfg, spec.config)
    directory = log.save(out_root / spec.slug)
    return spec, compute_metrics(log), directory


def run_campaign(
    specs: Sequence[RunSpec],
    out_root: Path,
    *,
    jobs: int | None = None,
    on_done: Callable[[RunSpec], None] | None = None,
) -> list[tuple[RunSpec, RunMetrics, Path]]:
    """Run every spec (in ``jobs`` worker processes) and return results in the order of ``specs``.

    Each run's ``utilization_vs_gt`` is filled in from the GT run of the same scenario and variant
    when the campaign contains one.

    Raises
    ------
    ValueError
        If ``jobs`` < 1 or a spec names an unknown scenario or configuration.
    """
    if jobs is not None and jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    for spec in specs:  # fail fast, before any process starts
        load_scenario(spec.scenario, list(spec.overrides))
    out_root.mkdir(parents=True, exist_ok=True)
    workers = min(jobs or os.cpu_count() or 1, len(specs)) or 1
    results: dict[RunSpec, tuple[RunSpec, RunMetrics, Path]] = {}
    failures: list[str] = []
    if workers == 1:
        for spec in specs:
            try:
                results[spec] = _run_reporting(spec, out_root)
            except RuntimeError as exc:
                failures.append(str(exc))
            if on_done:
                on_done(spec)
    else:
        # Generated solvers are compiled once, here, so that workers only load them.
        warm_up_solvers(specs)
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(_run_reporting, spec, out_root): spec for spec in specs}
            for fut in as_completed(futures):
                try:
                    results[futures[fut]] = fut.result()
                except RuntimeError as exc:
                    failures.append(str(exc))
                if on_done:
                    on_done(futures[fut])
    if failures:
        # Every other run has finished and is saved; report all failures at once.
        raise RuntimeError(f"{len(failures)} of {len(specs)} runs failed: " + "; ".join(failures))
    return _with_gt_comparison([results[s] for s in specs])


def _run_reporting(spec: RunSpec, out_root: Path) -> tuple[RunSpec, RunMetrics, Path]:
    # Exceptions cross the process boundary by pickling; some (LAPACK's, Cython's) cannot, so
    # a failure travels as a RuntimeError naming the run and the original error.
    try:
        return run_spec(spec, out_root)
    except Exception as exc:
        raise RuntimeError(f"{spec.slug}: {type(exc).__name__}: {exc}") from None


def warm_up_solvers(specs: Iterable[RunSpec]) -> None:
    """Build (or load from the cache) the planner of every vehicle the specs use."""
    seen = set()
    for spec in specs:
        cfg = load_scenario(spec.scenario, list(spec.overrides))
        key = (cfg.vehicle, cfg.planner.horizon_steps, cfg.planner.dt_s, cfg.planner.backend)
        if key not in seen:
            seen.add(key)
            planner_for(cfg)


def _with_gt_comparison(
    results: Iterable[tuple[RunSpec, RunMetrics, Path]],
) -> list[tuple[RunSpec, RunMetrics, Path]]:
    results = list(results)
    gt = {(s.scenario, s.variant): m for s, m, _ in results if s.config == "GT"}
    out = []
    for spec, metrics, directory in results:
        ref = gt.get((spec.scenario, spec.variant))
        out.append((spec, attach_gt_comparison(metrics, ref) if ref else metrics, directory))
    return out


PAPER_CONFIGS: tuple[str, ...] = ("GT", "L", "P", "F", "F-safe")


def reproduction_specs(include_car: bool = True) -> list[RunSpec]:
    """The runs behind ``mufusion reproduce``: both scenarios, every configuration.

    Truck at the paper's settings, the pop-up scenario also at the authors' own μ = 0.89, and
    (``include_car``) the same two scenarios with the passenger car.
    """
    variants: list[tuple[str, str, tuple[str, ...]]] = [
        ("turn", "paper", ()),
        ("popup", "paper mu=1.0", ()),
        ("popup", "authors mu=0.89", ("friction.mu=0.89",)),
    ]
    if include_car:
        variants += [
            ("turn", "car", ("vehicle=car",)),
            ("popup", "car", ("vehicle=car",)),
        ]
    return [
        RunSpec(scenario=name, config=config, variant=variant, overrides=overrides)
        for name, variant, overrides in variants
        for config in PAPER_CONFIGS
    ]
