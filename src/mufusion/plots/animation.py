"""An animated top view of one run (GIF)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter
from matplotlib.cm import ScalarMappable
from matplotlib.figure import Figure

from mufusion.plots._common import (
    FRICTION_CMAP,
    FRICTION_NORM,
    config_color,
    config_name,
    draw_obstacles,
    draw_plan,
    draw_road,
    draw_vehicle,
    plan_at,
    require_logs,
)
from mufusion.sim.log import RunLog

MAX_FRAMES = 60
# Half-width of the view that follows the vehicle [m]; the view centre leads the vehicle so the
# plan ahead stays in sight.
_HALF_WINDOW_M = 22.0
_LEAD_M = 12.0


def frame_rows(n_rows: int, max_frames: int = MAX_FRAMES) -> np.ndarray:
    """Indices of the time-series rows shown, evenly spread, first and last included."""
    count = min(n_rows, max_frames)
    return np.unique(np.round(np.linspace(0, n_rows - 1, count)).astype(int))


def _mu_hat_ahead(log: RunLog, time_s: float) -> float | None:
    plan = plan_at(log, time_s)
    if plan.empty or "mu_hat" not in plan:
        return None
    return float(np.nanmin(plan["mu_hat"].to_numpy(dtype=float)))


def animate_run(log: RunLog, path: str | Path, fps: int = 10) -> Path:
    """Write an animated GIF of a run: a top view that follows the vehicle.

    Each frame shows the road coloured by the true friction, the vehicle footprint, the plan
    made nearest that instant, active obstacles, and a text box with time, speed and the
    smallest μ̂ over the plan ahead. At most ``MAX_FRAMES`` (60) frames, evenly spread.

    Parameters
    ----------
    log : RunLog
        The run.
    path : str or Path
        Output GIF file.
    fps : int
        Frames per second of the GIF, 1..60.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If the log has no time series or ``fps`` is out of range.
    """
    (log,) = require_logs([log])
    if int(fps) != fps or not 1 <= fps <= 60:
        raise ValueError(f"fps must be an integer in [1, 60], got {fps}")
    ts = log.timeseries
    rows = frame_rows(len(ts))
    color = config_color(log, 0)
    name = config_name(log)

    # A fixed layout: re-solving a constrained layout on every frame would dominate the run time.
    fig = Figure(figsize=(4.6, 4.0))
    ax = fig.add_axes((0.14, 0.12, 0.66, 0.8))
    bar = fig.colorbar(ScalarMappable(norm=FRICTION_NORM, cmap=FRICTION_CMAP),
                       cax=fig.add_axes((0.84, 0.12, 0.03, 0.8)))
    bar.set_label("true μ [-]", fontsize=8)
    bar.ax.tick_params(labelsize=7)

    # The axes are set up once and each frame replaces only what it drew: clearing the axes
    # rebuilt every tick and re-placed the title at every frame, two thirds of the GIF's time.
    ax.set_aspect("equal", adjustable="box")
    ax.tick_params(labelsize=7)
    ax.set_xlabel("x [m]", fontsize=8)
    ax.set_ylabel("y [m]", fontsize=8)

    def draw(frame: int) -> list:
        for artist in [*ax.lines, *ax.patches, *ax.collections, *ax.texts]:
            artist.remove()
        row = ts.iloc[int(rows[frame])]
        t = float(row["t_s"])
        psi = float(row["psi_rad"])
        cx = float(row["x_m"]) + _LEAD_M * np.cos(psi)
        cy = float(row["y_m"]) + _LEAD_M * np.sin(psi)
        draw_road(ax, log.meta, (cx, cy), _HALF_WINDOW_M * np.sqrt(2))
        draw_obstacles(ax, log.meta, t)
        draw_plan(ax, plan_at(log, t), color)
        draw_vehicle(ax, log.meta, row, color)
        ax.set_xlim(cx - _HALF_WINDOW_M, cx + _HALF_WINDOW_M)
        ax.set_ylim(cy - _HALF_WINDOW_M, cy + _HALF_WINDOW_M)
        collision = " (collision)" if bool(row.get("in_collision", False)) else ""
        # At the axes' top edge (where it lands anyway without decorations above the axes):
        # a title placed by hand is not re-positioned against the tick labels at every draw.
        ax.set_title(f"{name}{collision}", fontsize=9, color="darkred" if collision else "black",
                     y=1.0)
        mu_hat = _mu_hat_ahead(log, t)
        lines = [f"t = {t:.1f} s", f"v = {float(row['speed_mps']):.1f} m/s"]
        if mu_hat is not None:
            lines.append(f"min μ̂ ahead = {mu_hat:.2f}")
        ax.text(0.02, 0.98, "\n".join(lines), transform=ax.transAxes, va="top", ha="left",
                fontsize=7, bbox={"boxstyle": "round", "facecolor": "white", "alpha": 0.85})
        return []

    anim = FuncAnimation(fig, draw, frames=len(rows), blit=False)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    anim.save(out, writer=PillowWriter(fps=int(fps)), dpi=90)
    return out
