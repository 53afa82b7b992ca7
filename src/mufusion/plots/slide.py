"""The slide mechanism over time (paper Sec. IV-C, the turn): why a run leaves its lane, or not.

Four panels against time, one line per run:

1. the executed planned front force over the true friction circle, ``|F_f| / (μ_gt F_z)`` of
   each plan's first stage (1 = the physical limit; above it the plan asks for grip the road
   does not have);
2. the realised front-tire utilisation (saturated at 0.98);
3. the lateral deviation ``d`` of the centre of gravity, with the lane's room for a centred
   vehicle and the ego/opposing lane boundary;
4. the body slip angle.

A vertical dotted line marks when each run's local estimate first became available. The numbers
behind the figure are :func:`mufusion.reproduction.slide.slide_diagnosis`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from matplotlib.figure import Figure

from mufusion.plots._common import config_color, config_name, require_logs, save_figure
from mufusion.reproduction.slide import SATURATION, executed_stage, slide_diagnosis
from mufusion.sim.log import RunLog


def build_slide_figure(logs: Sequence[RunLog], title: str = "") -> Figure:
    """The four-panel figure of :func:`plot_slide`."""
    logs = require_logs(logs)
    fig = Figure(figsize=(8.5, 8.0), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    ax_plan, ax_util, ax_d, ax_beta = axes
    for i, log in enumerate(logs):
        color, name = config_color(log, i), config_name(log)
        ts = log.timeseries
        stage = executed_stage(log)
        ax_plan.step(stage["t_s"], stage["planned_ratio"], where="post", color=color, lw=1.5,
                     label=name)
        ax_util.plot(ts["t_s"], ts["util_front"], color=color, lw=1.3, label=name)
        ax_d.plot(ts["t_s"], ts["d_m"], color=color, lw=1.5, label=name)
        ax_beta.plot(ts["t_s"], ts["body_slip_rad"], color=color, lw=1.3, label=name)
        available = slide_diagnosis(log).local_available_t_s
        if available is not None:
            for ax in axes:
                ax.axvline(available, color=color, lw=1.0, ls=":")
    ax_plan.axhline(1.0, color="tab:red", lw=1.0, ls="--", label="true limit μ_gt F_z")
    ax_util.axhline(SATURATION, color="tab:red", lw=1.0, ls="--", label=f"{SATURATION} (saturated)")
    meta = logs[0].meta
    w, room = meta.road.lane_width_m, 0.5 * (meta.road.lane_width_m - meta.vehicle.width_m)
    ax_d.axhline(w / 2, color="0.3", lw=1.0, ls="--", label="ego / opposing lane boundary")
    ax_d.axhspan(-room, room, color="0.85", alpha=0.6, label="room of a centred, aligned body")
    ax_plan.set_ylabel("planned |F_f| / (μ_gt F_z)")
    ax_util.set_ylabel("realised front\nutilisation")
    ax_d.set_ylabel("d [m] (left +)")
    ax_beta.set_ylabel("body slip [rad]")
    ax_beta.set_xlabel("time t [s] (dotted: local estimate available)")
    if title:
        ax_plan.set_title(title, fontsize=10)
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return fig


def plot_slide(logs: Sequence[RunLog], path: str | Path, title: str = "") -> Path:
    """Write the slide-mechanism figure of ``logs`` (runs of one scenario) to ``path``.

    Parameters
    ----------
    logs : sequence of RunLog
        Runs to draw, e.g. L and GT of one turn variant.
    path : str or Path
        Output PNG file.
    title : str
        Title above the first panel.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If ``logs`` is empty or a run has no time series.
    """
    return save_figure(build_slide_figure(logs, title), path)
