"""Campaigns: many scenario variants × friction configurations, run in parallel processes.

A campaign is a list of :class:`RunSpec` (a scenario file or name, overrides and a configuration);
each run is independent and deterministic, so the same list gives the same logs on a laptop (a
process pool) or on a cluster (one :func:`run_spec` per job, e.g. ``mufusion run`` in an array job).
"""

from __future__ import annotations

import itertools
import os
import sys
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from mufusion.configurations import CONFIGURATION_NAMES
from mufusion.metrics import RunMetrics, attach_gt_comparison, compute_metrics
from mufusion.scenarios.loading import load_scenario
from mufusion.scenarios.runner import planner_for, run_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


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


PAPER_CONFIGS: tuple[str, ...] = CONFIGURATION_NAMES


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


class CampaignFile(BaseModel):
    """A campaign as a TOML file: scenarios × configurations × the product of a parameter grid.

    Example::

        name = "friction sweep"
        scenarios = ["popup"]
        configs = ["GT", "P", "F", "F-safe"]
        overrides = ["duration_s=4"]          # applied to every run
        [grid]                                # every combination becomes one variant
        "friction.mu" = [0.7, 0.8, 0.9, 1.0]
        "obstacle.distance_m" = [18.0, 20.0, 25.0]
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str = "campaign"
    scenarios: list[str] = Field(min_length=1)
    configs: list[str] = Field(default_factory=lambda: list(PAPER_CONFIGS), min_length=1)
    overrides: list[str] = Field(default_factory=list)
    grid: dict[str, list[bool | int | float | str]] = Field(default_factory=dict)

    @field_validator("configs")
    @classmethod
    def _known_configs(cls, v: list[str]) -> list[str]:
        unknown = [c for c in v if c not in PAPER_CONFIGS]
        if unknown:
            raise ValueError(f"unknown configs {unknown}; allowed: {list(PAPER_CONFIGS)}")
        return v

    @field_validator("grid")
    @classmethod
    def _non_empty_axes(cls, v: dict[str, list]) -> dict[str, list]:
        empty = [k for k, values in v.items() if not values]
        if empty:
            raise ValueError(f"grid axes {empty} have no values")
        return v


def load_campaign(path: str | Path) -> CampaignFile:
    """Read and validate a campaign file.

    Raises
    ------
    ValueError
        If the file is missing, not TOML, or a field is invalid (the message names it).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"campaign file {str(path)!r} does not exist")
    try:
        raw = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"campaign file {str(path)!r} is not valid TOML: {err}") from None
    try:
        return CampaignFile.model_validate(raw)
    except ValidationError as err:
        problems = "; ".join(
            f"{'.'.join(str(p) for p in e['loc']) or '(top level)'}: {e['msg']}"
            for e in err.errors()
        )
        raise ValueError(f"invalid campaign {str(path)!r}: {problems}") from None


def campaign_specs(
    campaign: CampaignFile, *, shard: int = 0, shards: int = 1
) -> list[RunSpec]:
    """The runs of ``campaign`` that belong to shard ``shard`` of ``shards``.

    A variant (scenario × one grid point) is never split: its GT run, which the others are
    compared with, stays in the same shard. Variants are dealt round-robin, so shards of one
    campaign partition it and each can run as one job of a cluster array.

    Raises
    ------
    ValueError
        If ``shards`` < 1, ``shard`` is not in [0, shards), or a grid key or value is invalid for
        a scenario (checked before anything runs).
    """
    if shards < 1 or not 0 <= shard < shards:
        raise ValueError(f"shard must be in [0, shards) with shards >= 1, got {shard}/{shards}")
    keys = list(campaign.grid)
    points = list(itertools.product(*(campaign.grid[k] for k in keys))) or [()]
    variants = [
        (scenario, tuple(f"{k}={_toml_value(v)}" for k, v in zip(keys, point, strict=True)))
        for scenario in campaign.scenarios
        for point in points
    ]
    specs = []
    for i, (scenario, grid_overrides) in enumerate(variants):
        overrides = (*campaign.overrides, *grid_overrides)
        load_scenario(scenario, list(overrides))  # fail before anything runs
        if i % shards != shard:
            continue
        label = ", ".join(grid_overrides) or "default"
        specs += [
            RunSpec(scenario=scenario, config=c, variant=label, overrides=overrides)
            for c in campaign.configs
        ]
    return specs


def _toml_value(v: bool | int | float | str) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return v
    return repr(v)
