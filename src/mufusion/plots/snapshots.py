"""Top-view snapshots of runs at chosen positions (the paper's Fig. 3a-h and Fig. 4a-h)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mufusion.plots._common import (
    FRICTION_NORM,
    POSITION_TOLERANCE_M,
    config_color,
    config_name,
    draw_obstacles,
    draw_plan,
    draw_road,
    draw_vehicle,
    plan_at,
    require_logs,
    row_at_position,
    save_figure,
    start_s,
)
from mufusion.sim.log import RunLog

# Smallest half-width of a panel [m]: keeps the lanes readable when the plan is short.
_MIN_HALF_WINDOW_M = 12.0
# Height / width of every panel: one shape for the whole grid, wide because roads run mostly
# along the direction of travel.
_PANEL_ASPECT = 0.65
_MARGIN_M = 3.0


def _snapshot_row(logs: list[RunLog], log: RunLog, position_m: float) -> int:
    """Row of ``log`` nearest ``position_m``; its last row if the run ended before it.

    A run that stops early (a collision ends it) still gets a panel showing its final state, as
    long as another run reaches the position; a position no run reaches is an error.
    """
    try:
        return row_at_position(log, position_m)
    except ValueError:
        if position_m < 0 or not any(_reaches(other, position_m) for other in logs):
            raise
        return len(log.timeseries) - 1


def _reaches(log: RunLog, position_m: float) -> bool:
    travelled = float(log.timeseries["s_m"].max()) - start_s(log)
    return position_m <= travelled + POSITION_TOLERANCE_M


def build_snapshots_figure(logs: Sequence[RunLog], positions_m: Sequence[float]) -> Figure:
    """The snapshot grid (rows = runs, columns = positions); see :func:`plot_snapshots`."""
    logs = require_logs(logs)
    positions = [float(p) for p in positions_m]
    if not positions:
        raise ValueError("positions_m must hold at least one position [m], got none")
    rows = [[_snapshot_row(logs, log, p) for p in positions] for log in logs]

    n_rows, n_cols = len(logs), len(positions)
    fig = Figure(figsize=(3.4 * n_cols + 1.0, 3.4 * _PANEL_ASPECT * n_rows + 0.9),
                 layout="constrained")
    axes = fig.subplots(n_rows, n_cols, squeeze=False)
    surface = None
    for r, log in enumerate(logs):
        ts = log.timeseries
        color = config_color(log, r)
        for c, position in enumerate(positions):
            ax = axes[r][c]
            row = ts.iloc[rows[r][c]]
            t = float(row["t_s"])
            plan = plan_at(log, t)
            points = np.array([[row["x_m"], row["y_m"]]], dtype=float)
            if not plan.empty:
                points = np.vstack([points, plan[["x_m", "y_m"]].to_numpy(dtype=float)])
            lo, hi = points.min(axis=0), points.max(axis=0)
            centre = 0.5 * (lo + hi)
            half_x = max(_MIN_HALF_WINDOW_M, 0.5 * float(hi[0] - lo[0]) + _MARGIN_M,
                         (0.5 * float(hi[1] - lo[1]) + _MARGIN_M) / _PANEL_ASPECT)
            half_y = _PANEL_ASPECT * half_x
            drawn = draw_road(ax, log.meta, (centre[0], centre[1]), float(np.hypot(half_x, half_y)))
            surface = surface if drawn is None else drawn
            draw_obstacles(ax, log.meta, t)
            draw_plan(ax, plan, color)
            draw_vehicle(ax, log.meta, row, color)
            ax.set_xlim(centre[0] - half_x, centre[0] + half_x)
            ax.set_ylim(centre[1] - half_y, centre[1] + half_y)
            ax.set_aspect("equal", adjustable="box")
            tag = " (collision)" if bool(row.get("in_collision", False)) else ""
            ended = float(row["s_m"]) - start_s(log)
            if position > ended + POSITION_TOLERANCE_M:
                tag += f"\n(run ended at {ended:.0f} m)"
            ax.set_title(f"{config_name(log)}, s = {position:g} m{tag}", fontsize=10,
                         color="darkred" if tag else "black")
            ax.tick_params(labelsize=7)
            if r == n_rows - 1:
                ax.set_xlabel("x [m]", fontsize=8)
            if c == 0:
                ax.set_ylabel("y [m]", fontsize=8)
    if surface is not None:
        bar = fig.colorbar(surface, ax=axes, shrink=0.8, pad=0.01, aspect=30)
        bar.set_label("true friction μ [-]")
        bar.mappable.set_norm(FRICTION_NORM)
    with_obstacles = any(log.meta.obstacles for log in logs)
    fig.suptitle("Top view: vehicle, planned trajectory (line with markers)"
                 + (", obstacle (red)" if with_obstacles else ""), fontsize=10)
    return fig


def plot_snapshots(logs: Sequence[RunLog], positions_m: Sequence[float], path: str | Path) -> Path:
    """Top views of each run at chosen positions, like the paper's Fig. 3a-h / 4a-h.

    Each panel shows the road around the vehicle (ego and opposing lane, surface coloured by the
    true friction), the obstacle if it is active, the vehicle's footprint at the logged tick whose
    progress is nearest the position, and the plan made nearest that instant.

    Parameters
    ----------
    logs : sequence of RunLog
        One row of panels per run (the paper: L vs F for the turn, P vs F for the pop-up).
    positions_m : sequence of float
        Progress from the run's start ``s - meta.start_s_m`` [m], one column each
        (paper: turn 0, 15, 30, 55 m; pop-up 0, 2, 18, 40 m).
    path : str or Path
        Output PNG file.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If ``logs`` or ``positions_m`` is empty, or a position lies outside the travelled range
        of every run. A run that ended before a position others reach is shown at its last
        logged tick, tagged "(run ended at ... m)".
    """
    return save_figure(build_snapshots_figure(logs, positions_m), path)
