"""Figures of a campaign's Monte Carlo report: outcome rates with their intervals, distributions
of the graded outcomes, and heat maps over the grid (one panel per configuration).

Every figure reads the results table through :mod:`mufusion.campaign.stats`; nothing here
computes a statistic of its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from mufusion.campaign.report import CampaignResults
from mufusion.campaign.stats import (
    completed,
    graded_columns,
    graded_summary,
    outcome_columns,
    outcome_rates,
)
from mufusion.plots._common import CONFIG_COLORS

PANEL_IN = 3.2  # width and height of one panel [in]
DPI = 110


def _save(fig: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    return path


def _groups(table: pd.DataFrame) -> list[tuple[str, str]]:
    return list(dict.fromkeys(zip(table["scenario"], table["config"], strict=True)))


def _group_label(scenario: str, config: str, scenarios: int) -> str:
    return config if scenarios == 1 else f"{scenario}\n{config}"


def plot_outcome_rates(table: pd.DataFrame, path: Path) -> Path:
    """One panel per outcome: its rate per configuration with the Wilson 95 % interval."""
    rates = outcome_rates(table)
    outcomes = list(dict.fromkeys(rates["outcome"]))
    groups = _groups(table)
    scenarios = len({s for s, _ in groups})
    fig = Figure(figsize=(PANEL_IN * len(outcomes), PANEL_IN))
    axes = fig.subplots(1, len(outcomes), squeeze=False)[0]
    for ax, outcome in zip(axes, outcomes, strict=True):
        for i, (scenario, config) in enumerate(groups):
            r = rates[(rates["outcome"] == outcome) & (rates["scenario"] == scenario)
                      & (rates["config"] == config)].iloc[0]
            if r["runs"] == 0:
                continue
            err = [[100 * (r["rate"] - r["ci_low"])], [100 * (r["ci_high"] - r["rate"])]]
            ax.errorbar([i], [100 * r["rate"]], yerr=err, fmt="o", capsize=4,
                        color=CONFIG_COLORS.get(config, f"C{i % 10}"))
        ax.set_xticks(range(len(groups)),
                      [_group_label(s, c, scenarios) for s, c in groups])
        ax.set_ylim(-3, 103)
        ax.set_title(outcome)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("runs with the outcome [%] (Wilson 95 % CI)")
    return _save(fig, path)


def plot_distributions(table: pd.DataFrame, metrics: Sequence[str], path: Path) -> Path:
    """One panel per graded metric: a box plot per configuration (runs where it is defined)."""
    ok = completed(table)
    groups = _groups(table)
    scenarios = len({s for s, _ in groups})
    cols = min(4, len(metrics))
    rows = -(-len(metrics) // cols)
    fig = Figure(figsize=(PANEL_IN * cols, PANEL_IN * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax, metric in zip(axes, metrics, strict=False):
        data, labels = [], []
        for scenario, config in groups:
            sel = ok[(ok["scenario"] == scenario) & (ok["config"] == config)][metric]
            data.append(sel.dropna().to_numpy(dtype=float))
            labels.append(_group_label(scenario, config, scenarios))
        shown = [i for i, d in enumerate(data) if len(d)]
        if shown:
            ax.boxplot([data[i] for i in shown], positions=shown, widths=0.6)
        ax.set_xticks(range(len(labels)), labels, fontsize=8)
        ax.set_xlim(-0.6, len(labels) - 0.4)
        ax.set_title(metric, fontsize=9)
        ax.grid(axis="y", alpha=0.3)
    for ax in axes[len(metrics):]:
        ax.set_visible(False)
    return _save(fig, path)


def plot_heat_map(
    cells: pd.DataFrame, x: str, y: str | None, value: str, path: Path, *,
    title: str, vmin: float | None = None, vmax: float | None = None, percent: bool = False,
    feasibility: dict[tuple[object, object], str] | None = None,
) -> Path:
    """Heat maps of ``value`` over grid keys ``x`` and ``y``: one panel per configuration.

    Parameters
    ----------
    cells
        One row per (scenario, config, x[, y]) with the column ``value`` (e.g. from
        :func:`~mufusion.campaign.stats.outcome_rates` grouped by the grid keys).
    x, y
        Grid keys on the horizontal and vertical axis (``y`` may be ``None``: one row).
    value
        Column shown as colour and written in each cell.
    percent
        Show values ×100 with a ``%``.
    feasibility
        The physics oracle's class per ``(x, y)`` cell (``feasible``, ``marginal``,
        ``infeasible``; ``mixed`` where pooled variants differ): infeasible cells are hatched and
        the boundary of the feasible region is drawn as a thick white line.
    """
    panels = _groups(cells)
    xs = sorted(cells[x].unique(), key=_sort_key)
    ys = sorted(cells[y].unique(), key=_sort_key) if y else [None]
    finite = cells[value].to_numpy(dtype=float)
    finite = finite[np.isfinite(finite)]
    lo = vmin if vmin is not None else (finite.min() if len(finite) else 0.0)
    hi = vmax if vmax is not None else (finite.max() if len(finite) else 1.0)
    hi = hi if hi > lo else lo + 1.0
    cols = min(len(panels), 5)
    rows = -(-len(panels) // cols)
    fig = Figure(figsize=(0.6 * PANEL_IN * max(2, len(xs)) * cols / 2 + 1.0,
                          0.5 * PANEL_IN * max(2, len(ys)) * rows / 2 + 0.8),
                 layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    image = None
    scenarios = len({s for s, _ in panels})
    for ax, (scenario, config) in zip(axes, panels, strict=False):
        sel = cells[(cells["scenario"] == scenario) & (cells["config"] == config)]
        grid = np.full((len(ys), len(xs)), np.nan)
        for _, r in sel.iterrows():
            j = xs.index(r[x])
            i = ys.index(r[y]) if y else 0
            grid[i, j] = float(r[value])
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis",
                          vmin=lo, vmax=hi)
        for i in range(len(ys)):
            for j in range(len(xs)):
                v = grid[i, j]
                if np.isfinite(v):
                    text = f"{100 * v:.0f}%" if percent else f"{v:.3g}"
                    shade = "white" if (v - lo) / (hi - lo) < 0.6 else "black"
                    ax.text(j, i, text, ha="center", va="center", fontsize=8, color=shade)
        if feasibility:
            _draw_feasibility(ax, feasibility, xs, ys)
        ax.set_xticks(range(len(xs)), [str(v) for v in xs], fontsize=8)
        ax.set_yticks(range(len(ys)), [str(v) for v in ys] if y else [""], fontsize=8)
        ax.set_xlabel(x, fontsize=8)
        if y:
            ax.set_ylabel(y, fontsize=8)
        ax.set_title(config if scenarios == 1 else f"{scenario} / {config}", fontsize=9)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    if image is not None:
        bar = fig.colorbar(image, ax=axes[: len(panels)].tolist(), shrink=0.9)
        if percent:
            bar.ax.yaxis.set_major_formatter(lambda v, _pos: f"{100 * v:.0f}%")
    fig.suptitle(title, fontsize=10)
    return _save(fig, path)


def _draw_feasibility(
    ax: Axes, classes: dict[tuple[object, object], str], xs: list, ys: list
) -> None:
    """Hatch infeasible cells; outline the feasible region (edges where feasibility changes)."""
    def feasible(i: int, j: int) -> bool | None:
        if not (0 <= i < len(ys) and 0 <= j < len(xs)):
            return None
        return classes.get((xs[j], ys[i])) == "feasible"

    for i in range(len(ys)):
        for j in range(len(xs)):
            cls = classes.get((xs[j], ys[i]))
            if cls in ("infeasible", "marginal", "mixed"):
                ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, lw=0,
                                       hatch="///" if cls == "infeasible" else "..",
                                       edgecolor="0.85", gid=f"feasibility-{cls}"))
            here = feasible(i, j)
            for di, dj in ((0, 1), (1, 0)):
                there = feasible(i + di, j + dj)
                if there is None or there == here:
                    continue
                if dj:
                    ax.plot([j + 0.5, j + 0.5], [i - 0.5, i + 0.5], color="white", lw=2.5,
                            gid="feasibility-boundary")
                else:
                    ax.plot([j - 0.5, j + 0.5], [i + 0.5, i + 0.5], color="white", lw=2.5,
                            gid="feasibility-boundary")


def feasibility_cells(table: pd.DataFrame, x: str, y: str | None) -> dict[tuple[object, object],
                                                                            str]:
    """The oracle's class per ``(x, y)`` grid cell, pooled over the other grid keys."""
    if "feasibility" not in table.columns:
        return {}
    cells: dict[tuple[object, object], str] = {}
    keys = [x, *([y] if y else [])]
    for key, group in table.groupby(keys, dropna=False):
        values = set(group["feasibility"].dropna().astype(str))
        cell = key if isinstance(key, tuple) else (key,)
        cls = values.pop() if len(values) == 1 else "mixed"
        cells[(cell[0], cell[1] if y else None)] = cls
    return cells


def _sort_key(v: object) -> tuple[int, float, str]:
    if isinstance(v, bool | np.bool_):
        return (1, float(v), "")
    if isinstance(v, int | float | np.integer | np.floating):
        return (0, float(v), "")
    return (2, 0.0, str(v))


def campaign_figures(data: CampaignResults, out_dir: Path) -> dict[str, Path]:
    """Every figure of the campaign report; keys ``rates``, ``distributions`` and
    ``heatmap/<outcome or metric>`` (heat maps need at least one grid key)."""
    table = data.table
    figures: dict[str, Path] = {}
    if outcome_columns(table):
        figures["rates"] = plot_outcome_rates(table, out_dir / "rates.png")
    metrics = [m for m in graded_columns(table, data.grid) if completed(table)[m].notna().any()]
    if metrics:
        figures["distributions"] = plot_distributions(table, metrics,
                                                      out_dir / "distributions.png")
    if not data.grid:
        return figures
    x, y = data.grid[0], (data.grid[1] if len(data.grid) > 1 else None)
    by = ["scenario", "config", x, *([y] if y else [])]
    pooled = f" (pooled over {', '.join(data.grid[2:])})" if len(data.grid) > 2 else ""
    rates = outcome_rates(table, by=by)
    classes = feasibility_cells(table, x, y)
    for column, label in outcome_columns(table):
        cells = rates[rates["outcome"] == label]
        figures[f"heatmap/{column}"] = plot_heat_map(
            cells, x, y, "rate", out_dir / f"heatmap-{column}.png",
            title=f"{label} rate{pooled}", vmin=0.0, vmax=1.0, percent=True,
            feasibility=classes,
        )
    graded = graded_summary(table, by=by, grid=data.grid)
    for metric in metrics:
        cells = graded[graded["metric"] == metric]
        if "mean" not in cells.columns or cells["mean"].isna().all():
            continue
        figures[f"heatmap/{metric}"] = plot_heat_map(
            cells, x, y, "mean", out_dir / f"heatmap-{metric}.png",
            title=f"mean {metric}{pooled}", feasibility=classes,
        )
    return figures
