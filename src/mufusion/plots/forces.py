"""Planned front tire forces against the force limits (the paper's Fig. 3k and Fig. 4k)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mufusion.plots._common import (
    check_time,
    config_color,
    config_name,
    plan_at,
    require_logs,
    save_figure,
)
from mufusion.sim.log import RunLog

_KN = 1e-3


def force_polygon_vertices(radius_n: float, sides: int) -> np.ndarray:
    """Vertices (sides, 2) of the regular polygon inscribed in a circle of ``radius_n``.

    The planner's friction constraint (paper Sec. III) replaces the friction circle by this
    polygon; the first vertex lies on the positive first axis.

    Raises
    ------
    ValueError
        If ``radius_n`` is negative or not finite, or ``sides`` < 3.
    """
    if not np.isfinite(radius_n) or radius_n < 0:
        raise ValueError(f"radius_n must be a finite force >= 0 N, got {radius_n}")
    if int(sides) != sides or sides < 3:
        raise ValueError(f"sides must be an integer >= 3, got {sides}")
    angles = 2 * np.pi * np.arange(int(sides)) / int(sides)
    return radius_n * np.column_stack([np.cos(angles), np.sin(angles)])


def build_forces_figure(logs: Sequence[RunLog], time_s: float) -> Figure:
    """The force-plane figure of :func:`plot_planned_forces`."""
    logs = require_logs(logs)
    for log in logs:
        check_time(log, time_s)
    fig = Figure(figsize=(9.0, 5.2), layout="constrained")
    ax = fig.subplots()
    circle = np.linspace(0.0, 2 * np.pi, 181)
    extent = 1.0
    for i, log in enumerate(logs):
        plan = plan_at(log, time_s)
        if plan.empty:
            continue
        color = config_color(log, i)
        name = config_name(log)
        fy, fx = plan["fyf_n"].to_numpy() * _KN, plan["fxf_n"].to_numpy() * _KN
        ax.plot(fy, fx, ls="none", marker="o", ms=4, color=color, gid="planned",
                label=f"{name}: planned forces (t = {float(plan['t_s'].iloc[0]):.2f} s)")
        # The tightest stage's polygon: the limit that binds the plan (λ μ̂ F_zf, paper (10)),
        # against the tightest physical limit over the same stages.
        tight = plan.iloc[int(np.argmin(plan["limit_front_n"].to_numpy()))]
        sides = log.meta.planner.polygon_sides
        poly = force_polygon_vertices(float(tight["limit_front_n"]), sides) * _KN
        closed = np.vstack([poly, poly[:1]])
        ax.plot(closed[:, 0], closed[:, 1], color=color, lw=1.3, gid="limit_polygon",
                label=f"{name}: tightest limit λμ̂F_zf (μ̂ = {float(tight['mu_hat']):.2f})")
        true_limits = (plan["mu_true"] * plan["fzf_n"]).to_numpy(dtype=float)
        j = int(np.argmin(true_limits))
        true_radius = float(true_limits[j]) * _KN
        ax.plot(true_radius * np.cos(circle), true_radius * np.sin(circle), color=color,
                lw=1.0, ls="--", gid="true_circle",
                label=f"{name}: tightest true limit μF_zf (μ = "
                f"{float(plan['mu_true'].iloc[j]):.2f})")
        extent = max(extent, true_radius, float(np.max(np.abs(poly))),
                      float(np.max(np.abs(np.concatenate([fy, fx])))))
    lim = 1.1 * extent
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal", adjustable="box")
    ax.axhline(0.0, color="0.8", lw=0.8)
    ax.axvline(0.0, color="0.8", lw=0.8)
    ax.set_xlabel("front lateral force F_yf [kN]")
    ax.set_ylabel("front longitudinal force F_xf [kN]")
    ax.set_title(f"Planned front tire forces, plan nearest t = {time_s:g} s", fontsize=10)
    # Outside the axes: the legend must never cover force points.
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    ax.grid(alpha=0.3)
    return fig


def plot_planned_forces(logs: Sequence[RunLog], time_s: float, path: str | Path) -> Path:
    """Planned front tire forces of each run's plan at ``time_s`` in the force plane.

    For each run: the planned (F_yf, F_xf) of every stage as points, the force-limit polygon
    (regular ``meta.planner.polygon_sides``-gon inscribed in the circle of radius ``limit_front_n``)
    of the stage with the smallest limit, and the true friction circle μ_gt F_zf of that stage
    dashed. Forces in kN.

    Parameters
    ----------
    logs : sequence of RunLog
        Runs of one scenario.
    time_s : float
        Instant [s]; the planning step nearest it is shown (paper: the comparison time).
    path : str or Path
        Output PNG file.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If ``logs`` is empty or ``time_s`` lies outside a run.
    """
    return save_figure(build_forces_figure(logs, time_s), path)
