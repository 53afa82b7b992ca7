"""A campaign's results: one row per run (its parameters, then its metrics or its error), as
``summary.json`` and as one tidy table, ``results.parquet`` + ``results.csv``.

>>> import pandas as pd                                             # doctest: +SKIP
>>> table = pd.read_parquet("results/campaign/results.parquet")     # doctest: +SKIP
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import pandas as pd

from mufusion.campaign.specs import RunSpec
from mufusion.campaign.storage import atomic_write, atomic_write_text
from mufusion.configurations import Configuration
from mufusion.metrics import RunMetrics, attach_gt_comparison

SUMMARY_FILE = "summary.json"
TABLE_FILE = "results.parquet"
CSV_FILE = "results.csv"
# The parameter columns, in this order; the grid keys follow, then the metrics.
PARAMETER_COLUMNS = ("run", "index", "scenario", "variant", "config", "seed")
STATUS_COLUMNS = ("error", "log")
# A grid key that clashes with another column is stored as "grid.<key>".
GRID_PREFIX = "grid."


@dataclass(frozen=True)
class RunResult:
    """One finished run: its spec, its seed, and its metrics or its error.

    Attributes
    ----------
    spec
        The run.
    seed
        The seed it ran with (the scenario's ``seed`` field).
    metrics
        Its metrics, ``utilization_vs_gt`` filled in when the campaign has the variant's GT run;
        ``None`` if the run failed.
    error
        Why the run failed, ``None`` if it completed.
    directory
        Its run directory (``None`` if it failed).
    resumed
        Whether it was found complete on disk instead of being run now.
    """

    spec: RunSpec
    seed: int
    metrics: RunMetrics | None
    error: str | None
    directory: Path | None
    resumed: bool = False


def metric_names() -> list[str]:
    """The metric columns, in :class:`~mufusion.metrics.RunMetrics` order."""
    return [f.name for f in fields(RunMetrics)]


def with_gt_comparison(results: Iterable[RunResult]) -> list[RunResult]:
    """Fill in each run's comparison with the GT run of the same scenario, variant and seed."""
    results = list(results)
    gt = {
        _variant_key(r.spec): r.metrics
        for r in results
        if r.spec.config == Configuration.GT.value and r.metrics is not None
    }
    out = []
    for r in results:
        ref = gt.get(_variant_key(r.spec))
        if r.metrics is not None and ref is not None:
            r = RunResult(r.spec, r.seed, attach_gt_comparison(r.metrics, ref), r.error,
                          r.directory, r.resumed)
        out.append(r)
    return out


def _variant_key(spec: RunSpec) -> tuple[str, tuple[str, ...]]:
    return spec.scenario, tuple(spec.all_overrides)


def grid_columns(results: Iterable[RunResult]) -> dict[str, str]:
    """Grid key → its column name (the key, or ``grid.<key>`` where it clashes)."""
    taken = {*PARAMETER_COLUMNS, *STATUS_COLUMNS, *metric_names()}
    keys: dict[str, None] = {}
    for r in results:
        keys.update((k, None) for k, _ in r.spec.grid)
    return {k: (GRID_PREFIX + k if k in taken else k) for k in keys}


def result_rows(results: Sequence[RunResult], out: Path | None = None) -> list[dict[str, Any]]:
    """One flat row per run: parameters, each grid key, ``error``, ``log``, then the metrics.

    ``log`` is relative to ``out`` when given (the campaign's output directory).
    """
    columns = grid_columns(results)
    rows = []
    for r in results:
        log = r.directory
        if log is not None and out is not None:
            log = log.relative_to(out) if log.is_relative_to(out) else log
        row: dict[str, Any] = {
            "run": r.spec.name,
            "index": r.spec.index,
            "scenario": r.spec.scenario,
            "variant": r.spec.variant,
            "config": r.spec.config,
            "seed": r.seed,
            **{columns[k]: v for k, v in r.spec.grid},
            "error": r.error,
            "log": None if log is None else str(log),
        }
        if r.metrics is not None:
            row.update(r.metrics.to_dict())
        rows.append(row)
    return rows


def results_table(rows: Sequence[Mapping[str, Any]]) -> pd.DataFrame:
    """The rows as a DataFrame whose columns Parquet can store (mixed-type columns as text)."""
    table = pd.DataFrame.from_records(list(rows))
    for column in table.columns:
        kinds = {type(v) for v in table[column] if v is not None and not pd.isna(v)}
        if str in kinds and len(kinds) > 1:
            table[column] = [None if v is None else str(v) for v in table[column]]
    return table


def write_results(
    out: Path,
    results: Sequence[RunResult],
    info: Mapping[str, Any],
    *,
    partial: bool,
    pending: int = 0,
) -> Path:
    """Write ``summary.json``, ``results.parquet`` and ``results.csv`` into ``out`` atomically.

    Parameters
    ----------
    out
        The campaign's output directory.
    results
        Finished runs (completed or failed), in campaign order.
    info
        Extra top-level entries of ``summary.json`` (campaign file, shard, engine, elapsed time).
    partial
        Whether the campaign was interrupted (``pending`` runs did not run).

    Returns
    -------
    Path
        The ``summary.json`` written.
    """
    rows = result_rows(results, out)
    failed = sum(r.error is not None for r in results)
    summary = {
        **info,
        "partial": partial,
        "completed": len(results) - failed,
        "failed": failed,
        "pending": pending,
        "grid_columns": list(grid_columns(results).values()),
        "runs": rows,
    }
    table = results_table(rows)
    atomic_write(out / TABLE_FILE, lambda tmp: table.to_parquet(tmp, index=False))
    atomic_write(out / CSV_FILE, lambda tmp: table.to_csv(tmp, index=False))
    return atomic_write_text(out / SUMMARY_FILE, json.dumps(summary, indent=2))
