"""Shared pieces of the run figures: log look-ups, road drawing, vehicle footprints.

Everything here reads a :class:`~mufusion.sim.log.RunLog` (see the log schema in
``mufusion.sim.log``); nothing touches the live simulator. Figures are built on
:class:`matplotlib.figure.Figure` directly, so no global pyplot state and no display are needed.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
from matplotlib.colors import LinearSegmentedColormap, Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from mufusion.configurations import Configuration
from mufusion.sim.log import RunLog
from mufusion.sim.records import ObstacleTrace, RunMeta

# One colour per configuration, the same in every figure.
CONFIG_COLORS: dict[str, str] = {
    Configuration.GT: "black",
    Configuration.L: "tab:orange",
    Configuration.P: "tab:green",
    Configuration.F: "tab:blue",
    Configuration.F_SAFE: "tab:purple",
    Configuration.F_SHARED: "tab:cyan",
    Configuration.F_SAFE_SHARED: "tab:pink",
}
# Colour scale of the road surface: low μ (ice, snow) pale, dry asphalt (μ ≈ 1) grey; kept apart
# from the configuration colours so vehicles and plans stay visible on any surface.
FRICTION_CMAP = LinearSegmentedColormap.from_list("friction", ["#eef5fc", "#9fb3c8", "#4d4d4d"])
FRICTION_NORM = Normalize(vmin=0.0, vmax=1.1)
# Tolerance on a requested time or position beyond the logged range [s] / [m]: half a planning
# step / a short distance, so that "the end of the run" is still accepted after rounding.
TIME_TOLERANCE_S = 0.05
POSITION_TOLERANCE_M = 1.0


def require_logs(logs: Sequence[RunLog]) -> list[RunLog]:
    """Return ``logs`` as a list; raise if there is none or one has no time series."""
    logs = list(logs)
    if not logs:
        raise ValueError("logs must hold at least one RunLog, got an empty sequence")
    for i, log in enumerate(logs):
        if log.timeseries.empty:
            raise ValueError(f"logs[{i}] has no timeseries rows: nothing to plot")
    return logs


def config_name(log: RunLog) -> str:
    """The configuration's short name of a run ("GT", …, "F-safe", or a plug-in's name)."""
    return log.meta.configuration


def config_color(log: RunLog, index: int) -> str:
    """Colour of a run's configuration (a plug-in's: the ``index``-th of matplotlib's cycle)."""
    builtin = log.meta.builtin
    return CONFIG_COLORS[builtin] if builtin is not None else f"C{index % 10}"


def start_s(log: RunLog) -> float:
    """The paper's "s = 0": the vehicle's initial progress [m]."""
    return log.meta.start_s_m


def check_time(log: RunLog, time_s: float, name: str = "time_s") -> None:
    """Raise ``ValueError`` if ``time_s`` lies outside the logged run."""
    t = log.timeseries["t_s"].to_numpy(dtype=float)
    lo, hi = float(t[0]), float(t[-1])
    if not np.isfinite(time_s) or time_s < lo - TIME_TOLERANCE_S or time_s > hi + TIME_TOLERANCE_S:
        raise ValueError(
            f"{name} must lie within the run of {config_name(log)!r}, [{lo:.2f}, {hi:.2f}] s; "
            f"got {time_s}"
        )


def row_at_position(log: RunLog, position_m: float) -> int:
    """Index of the time-series row whose progress ``s - start_s_m`` is nearest ``position_m``.

    Raises
    ------
    ValueError
        If ``position_m`` lies outside the travelled range by more than ``POSITION_TOLERANCE_M``.
    """
    travelled = log.timeseries["s_m"].to_numpy(dtype=float) - start_s(log)
    lo, hi = float(np.min(travelled)), float(np.max(travelled))
    if (
        not np.isfinite(position_m)
        or position_m < lo - POSITION_TOLERANCE_M
        or position_m > hi + POSITION_TOLERANCE_M
    ):
        raise ValueError(
            f"position must lie within the distance travelled by {config_name(log)!r}, "
            f"[{lo:.1f}, {hi:.1f}] m from the start; got {position_m}"
        )
    return int(np.argmin(np.abs(travelled - position_m)))


def nearest_step_time(table: pd.DataFrame, time_s: float) -> float | None:
    """The planning-step start time in ``table`` (plans or estimates) nearest ``time_s``."""
    if table.empty:
        return None
    times = table["t_s"].unique()
    return float(times[int(np.argmin(np.abs(times - time_s)))])


def plan_at(log: RunLog, time_s: float) -> pd.DataFrame:
    """Stages of the plan made nearest ``time_s``, ordered by stage; empty if no plan was logged."""
    plans = log.plans
    t_step = nearest_step_time(plans, time_s)
    if t_step is None:
        return plans
    return plans[plans["t_s"] == t_step].sort_values("k")


def footprint_xy(
    x_m: float, y_m: float, psi_rad: float, length_m: float, width_m: float
) -> np.ndarray:
    """Corners (4, 2) [m] of a rectangle of the given size centred at (x, y) with heading psi."""
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float) * [length_m, width_m] / 2
    c, s = np.cos(psi_rad), np.sin(psi_rad)
    rot = np.array([[c, -s], [s, c]])
    return half @ rot.T + [x_m, y_m]


def _road_arrays(meta: RunMeta) -> tuple[np.ndarray, ...]:
    road = meta.road
    return tuple(np.asarray(a, dtype=float) for a in (road.s_m, road.x_m, road.y_m, road.psi_rad))


def lane_width(meta: RunMeta) -> float:
    """Lane width [m] of the run's road."""
    return meta.road.lane_width_m


def opposing_width(meta: RunMeta) -> float:
    """Width [m] of the run's opposing lane (the ego lane's unless the road says otherwise)."""
    opposing = meta.road.opposing_lane_width_m
    return meta.road.lane_width_m if opposing is None else opposing


def friction_at(meta: RunMeta, s_m: np.ndarray) -> np.ndarray:
    """True μ at progress ``s_m``: piecewise constant, each sample holding until the next."""
    s_ref = np.asarray(meta.road.s_m, dtype=float)
    mu = np.asarray(meta.road.mu, dtype=float)
    idx = np.clip(np.searchsorted(s_ref, s_m, side="right") - 1, 0, len(mu) - 1)
    return mu[idx]


def _offset(meta: RunMeta, d_m: float, keep: np.ndarray) -> np.ndarray:
    _s, x, y, psi = _road_arrays(meta)
    # Left normal of the centreline: d is positive to the left (log schema).
    return np.column_stack([x[keep] - d_m * np.sin(psi[keep]), y[keep] + d_m * np.cos(psi[keep])])


def draw_road(ax: Axes, meta: RunMeta, centre_xy: tuple[float, float], radius_m: float):
    """Draw both lanes near ``centre_xy``: surface coloured by true μ, edges and centre marking.

    Returns the surface collection (the mappable for a μ colorbar).
    """
    s, x, y, _ = _road_arrays(meta)
    w = lane_width(meta)
    near = np.hypot(x - centre_xy[0], y - centre_xy[1]) <= radius_m + 2 * w
    # Widen the selection by one sample each side so the surface reaches the window edge.
    keep = np.convolve(near, np.ones(3), mode="same") > 0
    if keep.sum() < 2:
        return None
    right = _offset(meta, -w / 2, keep)
    left = _offset(meta, w / 2 + opposing_width(meta), keep)
    quads = [
        np.array([right[i], right[i + 1], left[i + 1], left[i]]) for i in range(len(right) - 1)
    ]
    s_kept = s[keep]
    mu = friction_at(meta, 0.5 * (s_kept[:-1] + s_kept[1:]))
    surface = PolyCollection(
        quads, array=mu, cmap=FRICTION_CMAP, norm=FRICTION_NORM, edgecolors="face",
        linewidths=0.3, zorder=0,
    )
    ax.add_collection(surface)
    ax.plot(right[:, 0], right[:, 1], color="0.25", lw=1.2, zorder=1)
    ax.plot(left[:, 0], left[:, 1], color="0.25", lw=1.2, zorder=1)
    if opposing_width(meta) > 0.0:  # a one-way road has no centre marking
        centre = _offset(meta, w / 2, keep)
        ax.plot(centre[:, 0], centre[:, 1], color="gold", lw=1.3, ls=(0, (4, 4)), zorder=1)
    return surface


def obstacle_corners_xy(meta: RunMeta, obstacle: ObstacleTrace, time_s: float) -> np.ndarray:
    """Cartesian corners (4, 2) [m] of ``obstacle`` where it is at ``time_s`` [s].

    A static obstacle's are the logged ones; a moving one is placed on the logged road samples
    (interpolated) at :meth:`~mufusion.sim.records.ObstacleTrace.s_at_time`, aligned with the
    road there.
    """
    if obstacle.speed_mps == 0.0:
        return np.column_stack([obstacle.corners_x_m, obstacle.corners_y_m])
    s, x, y, psi = _road_arrays(meta)
    s_now = float(obstacle.s_at_time(time_s))
    psi_now = float(np.interp(s_now, s, np.unwrap(psi)))
    cx = float(np.interp(s_now, s, x)) - obstacle.d_m * np.sin(psi_now)
    cy = float(np.interp(s_now, s, y)) + obstacle.d_m * np.cos(psi_now)
    return footprint_xy(cx, cy, psi_now, obstacle.length_m, obstacle.width_m)


def draw_obstacles(ax: Axes, meta: RunMeta, time_s: float) -> int:
    """Draw the obstacles active at ``time_s``, where they are then; returns how many."""
    drawn = 0
    for obstacle in meta.obstacles:
        if obstacle.appear_time_s is not None and time_s + 1e-9 < obstacle.appear_time_s:
            continue
        corners = obstacle_corners_xy(meta, obstacle, time_s)
        ax.add_patch(
            Polygon(corners, closed=True, facecolor="tab:red", edgecolor="darkred", lw=1.0,
                    zorder=3, gid="obstacle")
        )
        drawn += 1
    return drawn


def draw_vehicle(ax: Axes, meta: RunMeta, row: pd.Series, color: str) -> Polygon:
    """Draw the vehicle footprint of one time-series row."""
    corners = footprint_xy(
        float(row["x_m"]), float(row["y_m"]), float(row["psi_rad"]),
        meta.vehicle.length_m, meta.vehicle.width_m,
    )
    patch = Polygon(corners, closed=True, facecolor=color, edgecolor="black", lw=1.0,
                    alpha=0.9, zorder=5, gid="footprint")
    ax.add_patch(patch)
    return patch


def draw_plan(ax: Axes, plan: pd.DataFrame, color: str) -> None:
    """Draw a planned trajectory (Cartesian points of its stages) as a line with markers."""
    if plan.empty:
        return
    ax.plot(plan["x_m"], plan["y_m"], color=color, lw=1.5, marker="o", ms=3.5, mec="white",
            mew=0.5, zorder=4, gid="plan")


def save_figure(fig: Figure, path: str | Path, dpi: int = 110) -> Path:
    """Write ``fig`` to ``path`` (PNG unless the suffix says otherwise); returns the path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi)
    return out
