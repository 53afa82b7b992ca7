"""The Monte Carlo page of a campaign (``mufusion campaign-report``): outcome rates with Wilson
95 % intervals, each configuration against GT run by run, distributions of the graded outcomes
and the figures, as Markdown and HTML.

The numbers come from :mod:`mufusion.campaign.stats`; the figures are drawn by
:mod:`mufusion.plots.campaign` and passed in by path, so this module never imports plots.
"""

from __future__ import annotations

import json
import math
import os
import shlex
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import markdown
import pandas as pd

from mufusion.campaign.results import CSV_FILE, SUMMARY_FILE, TABLE_FILE
from mufusion.campaign.stats import (
    CONFIDENCE,
    REFERENCE,
    graded_summary,
    outcome_rates,
    paired_against_reference,
    worse_than_reference,
)
from mufusion.campaign.storage import atomic_write_text
from mufusion.scenarios.feasibility import FeasibilityClass


@dataclass(frozen=True)
class CampaignResults:
    """A finished campaign as read from its output directory.

    Attributes
    ----------
    directory
        The campaign's ``--out``.
    table
        The results table (one row per run).
    grid
        Columns of ``table`` that hold grid keys, in campaign order.
    name, campaign_file, shard, engine
        Provenance from ``summary.json``.
    partial
        Whether the campaign was interrupted.
    pending
        Runs that did not run (partial campaigns).
    elapsed_s
        Wall-clock time of the (last) campaign call.
    """

    directory: Path
    table: pd.DataFrame
    grid: tuple[str, ...]
    name: str
    campaign_file: str
    shard: str
    engine: str
    partial: bool
    pending: int
    elapsed_s: float | None


def load_campaign_results(directory: Path) -> CampaignResults:
    """Read a campaign's ``summary.json`` and results table.

    Raises
    ------
    ValueError
        If ``directory`` holds no campaign summary or table, or the table has no runs.
    """
    summary_file = directory / SUMMARY_FILE
    if not summary_file.is_file():
        raise ValueError(f"{str(directory)!r} holds no campaign results (no {SUMMARY_FILE})")
    try:
        summary = json.loads(summary_file.read_text())
    except json.JSONDecodeError as err:
        raise ValueError(f"{str(summary_file)!r} is not valid JSON: {err}") from None
    if (directory / TABLE_FILE).is_file():
        table = pd.read_parquet(directory / TABLE_FILE)
    elif (directory / CSV_FILE).is_file():
        table = pd.read_csv(directory / CSV_FILE)
    else:
        raise ValueError(f"{str(directory)!r} has no {TABLE_FILE} or {CSV_FILE}")
    if table.empty:
        raise ValueError(f"{str(directory)!r}: the campaign has no finished runs to report")
    return CampaignResults(
        directory=directory,
        table=table,
        grid=tuple(c for c in summary.get("grid_columns", []) if c in table.columns),
        name=str(summary.get("name", "campaign")),
        campaign_file=str(summary.get("campaign", "")),
        shard=str(summary.get("shard", "0/1")),
        engine=str(summary.get("engine", "pool")),
        partial=bool(summary.get("partial", False)),
        pending=int(summary.get("pending", 0)),
        elapsed_s=summary.get("elapsed_s"),
    )


def _num(v: Any, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return f"{v:.{digits}g}" if isinstance(v, float) else str(v)


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header),
            *("| " + " | ".join(r) + " |" for r in rows), ""]


def _rate_cell(r: pd.Series) -> str:
    """``rate [low, high] (k/n)`` in percent, ``–`` without runs."""
    if r["runs"] == 0:
        return "–"
    return (f"{100 * r['rate']:.0f} % [{100 * r['ci_low']:.0f}, {100 * r['ci_high']:.0f}] "
            f"({r['count']}/{r['runs']})")


def rates_markdown(rates: pd.DataFrame) -> list[str]:
    """Rates as one table per scenario: configurations × outcomes, ``rate [low, high] (k/n)``."""
    lines: list[str] = []
    for scenario, group in rates.groupby("scenario", sort=False):
        outcomes = list(dict.fromkeys(group["outcome"]))
        configs = list(dict.fromkeys(group["config"]))
        rows = []
        for config in configs:
            cells = [config]
            for outcome in outcomes:
                r = group[(group["config"] == config) & (group["outcome"] == outcome)].iloc[0]
                cells.append(_rate_cell(r))
            failed = int(group[group["config"] == config]["failed"].iloc[0])
            cells.append(str(failed))
            rows.append(cells)
        lines += [f"**{scenario}**", "", *_table(["config", *outcomes, "failed runs"], rows)]
    return lines


def rates_by_class_markdown(table: pd.DataFrame) -> list[str]:
    """Rates per scenario, oracle class and configuration (``[]`` without a ``feasibility``
    column or with a single class): the issue's acceptance is per class (GT must not fail where
    physics allows), and pooled rates mix the classes."""
    if "feasibility" not in table.columns:
        return []
    classes = table["feasibility"].dropna()
    if classes.nunique() < 2:
        return []
    rates = outcome_rates(table, by=("scenario", "feasibility", "config"))
    lines = ["### By the oracle's class", "",
             "The same rates within each feasibility class of `mufusion.scenarios.feasibility` "
             "(docs/feasibility.md).", ""]
    for scenario, group in rates.groupby("scenario", sort=False):
        outcomes = list(dict.fromkeys(group["outcome"]))
        keys = sorted(
            dict.fromkeys(zip(group["feasibility"], group["config"], strict=True)),
            key=lambda k: _class_rank(k[0]),
        )
        rows = []
        for cls, config in keys:
            sub = group[(group["feasibility"] == cls) & (group["config"] == config)]
            cells = [str(cls), str(config)]
            for outcome in outcomes:
                cells.append(_rate_cell(sub[sub["outcome"] == outcome].iloc[0]))
            rows.append(cells)
        lines += [f"**{scenario}**", "", *_table(["class", "config", *outcomes], rows)]
    return lines


CLASS_ORDER = tuple(c.value for c in sorted(FeasibilityClass, key=lambda c: -c.rank))
"""The oracle's classes in the order tables list them: feasible, marginal, infeasible."""
MAX_LISTED_RUNS = 30
"""At most this many runs are listed one by one under "Against GT" (the largest failures)."""


def _class_rank(cls: object) -> tuple[int, str]:
    return (CLASS_ORDER.index(str(cls)) if str(cls) in CLASS_ORDER else len(CLASS_ORDER),
            str(cls))


def _magnitude(outcome: str, value: float) -> str:
    """How far a failing run went: a lane excursion in cm, an impact speed in m/s."""
    if not math.isfinite(value):
        return "–"
    return f"{100 * value:.1f} cm" if outcome == "lane exit" else f"{value:.1f} m/s"


def against_reference_markdown(table: pd.DataFrame, reference: str = REFERENCE) -> list[str]:
    """Each configuration against the reference on the same variants and starts (``[]`` without
    both): the pair counts with the sign test, then the runs that fail where the reference does
    not, largest first, in centimetres (lane) or m/s (impact)."""
    classes = "feasibility" in table.columns and table["feasibility"].notna().any()
    by = ("scenario", "feasibility", "config") if classes else ("scenario", "config")
    paired = paired_against_reference(table, reference, by=by)
    if paired.empty:
        return []
    lines = [f"## Against {reference}, run by run", "",
             f"Each run is paired with the {reference} run of the same variant and start. "
             f"*worse*: it fails and {reference} does not; *better*: {reference} fails and it "
             "does not; *p*: two-sided sign test on worse against better.", ""]
    for scenario, group in paired.groupby("scenario", sort=False):
        if classes:
            group = group.sort_values("feasibility", key=lambda c: c.map(_class_rank),
                                      kind="stable")
        rows = [[*([str(r["feasibility"])] if classes else []), str(r["config"]),
                 str(r["outcome"]), str(r["pairs"]), str(r["worse"]), str(r["better"]),
                 str(r["both"]), _num(r["p_value"], 2)] for _, r in group.iterrows()]
        header = [*(["class"] if classes else []), "config", "outcome", "pairs", "worse",
                  "better", "both", "p"]
        lines += [f"**{scenario}**", "", *_table(header, rows)]
    worse = worse_than_reference(table, reference)
    if worse.empty:
        return lines
    shown = worse.head(MAX_LISTED_RUNS)  # by outcome, the largest failure first
    more = len(worse) - len(shown)
    lines += [f"Runs that fail where {reference} does not ({len(worse)}"
              + (f"; the first {len(shown)}" if more else "") + f"); *{reference}'s margin*: "
              f"its smallest lane margin (lane exit) or clearance (collision) on the same start.",
              ""]
    rows = [[str(r["scenario"]), *([str(r["feasibility"])] if classes else []),
             str(r["config"]), f"`{r['variant']}`", str(r["seed"]), str(r["outcome"]),
             _magnitude(str(r["outcome"]), r["magnitude"]),
             "–" if not math.isfinite(r["reference_margin"])
             else f"{100 * r['reference_margin']:.1f} cm"] for _, r in shown.iterrows()]
    header = ["scenario", *(["class"] if classes else []), "config", "variant", "seed",
              "outcome", "how far", f"{reference}'s margin"]
    return lines + _table(header, rows)


def graded_markdown(graded: pd.DataFrame) -> list[str]:
    """One table per scenario and graded metric: configurations × distribution statistics."""
    lines: list[str] = []
    stats = ["count", "mean", "std", "min", "p5", "median", "p95", "max"]
    for (scenario, metric), group in graded.groupby(["scenario", "metric"], sort=False):
        if not group["count"].any():
            continue
        rows = [[str(r["config"]), *(_num(r.get(s)) for s in stats)]
                for _, r in group.iterrows()]
        lines += [f"**{scenario}: `{metric}`**", "", *_table(["config", *stats], rows)]
    return lines


def report_markdown(data: CampaignResults, figures: Mapping[str, Path], base: Path) -> str:
    """The report as Markdown; figure paths are written relative to ``base``."""
    rates = outcome_rates(data.table)
    graded = graded_summary(data.table, grid=data.grid)
    table = data.table
    failed = int(table["error"].notna().sum()) if "error" in table.columns else 0
    seeds = table.groupby(["scenario", "variant", "config"])["seed"].nunique()
    md = [f"# Campaign report: {data.name}", ""]
    md += [f"{len(table)} runs ({failed} failed) from `{data.campaign_file}`, shard {data.shard}, "
           f"engine {data.engine}; {int(seeds.max())} seed(s) per variant and configuration; "
           f"grid: {', '.join(f'`{g}`' for g in data.grid) or 'none'}; "
           f"wall-clock time {_num(data.elapsed_s)} s.", ""]
    if data.partial:
        md += [f"**Partial campaign:** it was interrupted and {data.pending} runs did not run; "
               "the numbers below cover the finished runs only.", ""]
    md += ["## Outcome rates", "",
           f"Share of completed runs with each outcome, with its Wilson score interval at "
           f"{100 * CONFIDENCE:.0f} % confidence (rate [low, high] (runs with it / runs)).", ""]
    md += rates_markdown(rates)
    md += _figure_lines(figures, "rates", base)
    md += rates_by_class_markdown(table)
    md += against_reference_markdown(table)
    md += ["## Graded outcomes", "",
           "Distribution over the runs where the metric is defined (e.g. clearance only for runs "
           "that passed the obstacle); p5/p95 are the 5th and 95th percentiles.", ""]
    md += _figure_lines(figures, "distributions", base)
    md += graded_markdown(graded)
    heat = [k for k in figures if k.startswith("heatmap/")]
    if heat:
        md += ["## Over the grid", "",
               "One panel per configuration; each cell pools the runs (seeds, and grid keys not "
               "on the axes) of that grid point.", ""]
        for key in heat:
            md += _figure_lines(figures, key, base)
    rerun = f"mufusion campaign {shlex.quote(data.campaign_file)} --out DIR"
    md += ["## Reproduce", "", f"`{rerun}` then `mufusion campaign-report DIR`; the table is "
           "`pandas.read_parquet('DIR/results.parquet')`.", ""]
    return "\n".join(md)


def _figure_lines(figures: Mapping[str, Path], key: str, base: Path) -> list[str]:
    if key not in figures:
        return []
    rel = os.path.relpath(figures[key], base)
    return [f"![{key}]({Path(rel).as_posix()})", ""]


_HTML = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ font-family: sans-serif; max-width: 70em; margin: 2em auto; padding: 0 1em; }}
table {{ border-collapse: collapse; margin-bottom: 1em; }}
th, td {{ border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }}
th:first-child, td:first-child {{ text-align: left; }}
img {{ max-width: 100%; }}
</style></head><body>
{body}
</body></html>
"""


def write_campaign_report(
    data: CampaignResults, figures: Mapping[str, Path], out_dir: Path
) -> tuple[Path, Path]:
    """Write ``report.md`` and ``report.html`` into ``out_dir`` (atomically).

    Returns
    -------
    tuple of Path
        The Markdown and the HTML file.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    md = report_markdown(data, figures, out_dir)
    body = markdown.markdown(md, extensions=["tables"])
    page = _HTML.format(title=f"Campaign report: {data.name}", body=body)
    return (atomic_write_text(out_dir / "report.md", md),
            atomic_write_text(out_dir / "report.html", page))
