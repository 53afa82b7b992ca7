"""Lateral offset and speed along the road (the paper's Fig. 3i-j and Fig. 4i-j)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from mufusion.plots._common import (
    config_color,
    config_name,
    lane_width,
    opposing_width,
    require_logs,
    save_figure,
    start_s,
)
from mufusion.sim.log import RunLog


def build_traces_figure(logs: Sequence[RunLog]) -> Figure:
    """The two-panel figure of :func:`plot_lateral_and_speed`."""
    logs = require_logs(logs)
    fig = Figure(figsize=(8.5, 5.2), layout="constrained")
    ax_d, ax_v = fig.subplots(2, 1, sharex=True)
    for i, log in enumerate(logs):
        ts = log.timeseries
        s = ts["s_m"].to_numpy(dtype=float) - start_s(log)
        kwargs = {"color": config_color(log, i), "lw": 1.6, "label": config_name(log), "gid": "run"}
        ax_d.plot(s, ts["d_m"], **kwargs)
        ax_v.plot(s, ts["speed_mps"], **kwargs)

    meta = logs[0].meta
    w = lane_width(meta)
    edge = w / 2 + opposing_width(meta)
    ax_d.axhline(-w / 2, color="0.3", lw=1.0, ls="-")
    ax_d.axhline(w / 2, color="0.3", lw=1.0, ls="--")
    ax_d.axhline(edge, color="0.3", lw=1.0, ls="-")
    ax_d.axhline(0.0, color="0.7", lw=0.8, ls=":")
    # Label the boundaries at the right edge, inside the axes, so they never collide with data.
    for level, text in ((-w / 2, "ego lane edge"), (w / 2, "ego / opposing lane boundary"),
                        (edge, "road edge")):
        ax_d.annotate(text, xy=(1.0, level), xycoords=("axes fraction", "data"),
                      xytext=(-3, 2), textcoords="offset points", ha="right", va="bottom",
                      fontsize=7, color="0.3")

    obstacles = meta.obstacles
    s0 = start_s(logs[0])
    t_end = max(float(log.timeseries["t_s"].iloc[-1]) for log in logs)
    for j, obstacle in enumerate(obstacles):
        length, width = obstacle.length_m, obstacle.width_m
        s_rel = obstacle.s_m - s0
        # A moving obstacle sweeps its stretch of road over the run: drawn hatched, from where
        # it starts to where it is at the run's end (its start marked as the position).
        s_end = float(obstacle.s_at_time(t_end)) - s0
        low, high = min(s_rel, s_end) - length / 2, max(s_rel, s_end) + length / 2
        ax_d.add_patch(
            Rectangle((low, obstacle.d_m - width / 2), high - low, width,
                      facecolor="tab:red", alpha=0.35, edgecolor="darkred",
                      hatch="//" if obstacle.speed_mps else None,
                      label="obstacle (s-d footprint)" if j == 0 else None)
        )
        ax_v.axvline(s_rel, color="tab:red", lw=1.0, ls="--",
                     label="obstacle position" if j == 0 else None)

    ax_d.set_ylabel("distance to lane centre d [m]")
    lowest = min(float(log.timeseries["d_m"].min()) for log in logs)
    highest = max(float(log.timeseries["d_m"].max()) for log in logs)
    ax_d.set_ylim(min(-w, lowest - 0.5), max(2 * w, highest + 0.5))
    ax_d.set_title("Lateral offset (left positive)", fontsize=10)
    # Legends outside the axes, so they never cover a trace.
    ax_d.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax_v.set_ylabel("speed [m/s]")
    ax_v.set_xlabel("progress s from start [m]")
    ax_v.set_title("Speed", fontsize=10)
    if obstacles:
        ax_v.legend(handles=[h for h in ax_v.get_lines() if h.get_gid() != "run"], fontsize=8,
                    loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    for ax in (ax_d, ax_v):
        ax.grid(alpha=0.3)
    return fig


def plot_lateral_and_speed(logs: Sequence[RunLog], path: str | Path) -> Path:
    """Distance to the lane centre and speed vs progress, one line per run.

    The lateral panel marks the ego-lane edge (d = -w/2), the boundary to the opposing lane
    (d = w/2) and the road edge (d = 3w/2); with obstacles, their footprint in the s-d plane and
    their position on the speed panel.

    Parameters
    ----------
    logs : sequence of RunLog
        Runs of one scenario (all configurations; they share the road of ``logs[0]``).
    path : str or Path
        Output PNG file.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If ``logs`` is empty or a run has no time series.
    """
    return save_figure(build_traces_figure(logs), path)
