"""Active friction probing in one run: what triggered it, what it cost, what it brought.

Three panels over time: speed (the probe's cost), realised front-tire utilisation against the
local estimator's threshold (the excitation), and μ̂ under the vehicle against the true μ (what the
planner gets). Probing intervals are shaded; the instants the local estimate is available are
marked.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mufusion.estimators import UTILIZATION_THRESHOLD
from mufusion.plots._common import config_name, require_logs, save_figure
from mufusion.sim.log import RunLog


def _intervals(t: np.ndarray, on: np.ndarray) -> list[tuple[float, float]]:
    spans, start = [], None
    for ti, flag in zip(t, on, strict=True):
        if flag and start is None:
            start = ti
        if not flag and start is not None:
            spans.append((start, ti))
            start = None
    if start is not None:
        spans.append((start, float(t[-1])))
    return spans


def plot_probing(log: RunLog, path: str | Path) -> Path:
    """Write the probing figure of ``log`` to ``path`` (PNG); returns the path.

    Raises
    ------
    ValueError
        If the log has no time series.
    """
    return save_figure(build_probing_figure(log), path)


def build_probing_figure(log: RunLog) -> Figure:
    """The probing figure of ``log`` (see the module docstring)."""
    (log,) = require_logs([log])
    ts, steps, est = log.timeseries, log.planning_steps, log.estimates
    t = ts["t_s"].to_numpy(float)
    probing = _intervals(t, (ts["control_mode"] == "probing").to_numpy())
    fig = Figure(figsize=(7.5, 6.0), layout="constrained")
    ax_v, ax_u, ax_mu = fig.subplots(3, 1, sharex=True)
    for ax in (ax_v, ax_u, ax_mu):
        for a, b in probing:
            ax.axvspan(a, b, color="tab:orange", alpha=0.25, lw=0, gid="probing")
    ax_v.plot(t, ts["speed_mps"], color="black", lw=1.4)
    ax_v.set_ylabel("speed [m/s]")
    ax_u.plot(t, ts["util_front"], color="tab:blue", lw=1.2, label="front utilisation")
    ax_u.axhline(UTILIZATION_THRESHOLD, color="0.4", ls="--", lw=1.0,
                 label="local estimator threshold")
    available = steps[steps["local_available"].astype(bool)]["t_s"].to_numpy(float)
    ax_u.plot(available, np.full(available.size, 1.02), "|", color="tab:green", ms=8,
              label="local estimate available", gid="local_available")
    ax_u.set_ylabel("utilisation [-]")
    ax_u.set_ylim(0.0, 1.08)
    ax_u.legend(loc="upper right", fontsize=7)
    under = est[est["s_ahead_m"] == 0.0]
    ahead = est[est["s_ahead_m"] == est["s_ahead_m"].max()]
    ax_mu.step(under["t_s"], under["mu_hat"], where="post", color="tab:purple",
               label="μ̂ under the vehicle")
    ax_mu.step(ahead["t_s"], ahead["mu_hat"], where="post", color="tab:purple", ls=":",
               label=f"μ̂ {ahead['s_ahead_m'].max():.0f} m ahead")
    ax_mu.plot(t, ts["mu_front"], color="black", lw=1.0, label="true μ (front axle)")
    ax_mu.set_ylabel("μ [-]")
    ax_mu.set_xlabel("time [s]")
    ax_mu.legend(loc="upper right", fontsize=7)
    speed = ts["speed_mps"].to_numpy(float)
    lost = sum(float(np.interp(a, t, speed) - np.interp(b, t, speed)) for a, b in probing)
    fig.suptitle(f"{config_name(log)}: friction probing "
                 f"({len(probing)} probe{'s' if len(probing) != 1 else ''}; shaded)", fontsize=10)
    ax_v.set_title(f"speed (the probes cost {lost:.2f} m/s)", fontsize=8)
    return fig
