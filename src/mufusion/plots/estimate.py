"""The fused friction estimate of one planning step (the paper's Fig. 2, 3l and 4l)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mufusion.fusion import Z95
from mufusion.plots._common import (
    check_time,
    config_name,
    nearest_step_time,
    require_logs,
    save_figure,
)
from mufusion.sim.log import RunLog


def build_estimate_figure(log: RunLog, time_s: float) -> Figure:
    """The figure of :func:`plot_fused_estimate`."""
    (log,) = require_logs([log])
    check_time(log, time_s)
    estimates = log.estimates
    if estimates.empty or "mean" not in estimates or not estimates["mean"].notna().any():
        raise ValueError(
            f"log of {config_name(log)!r} has no posterior (estimates.mean is empty or NaN): "
            "plot_fused_estimate needs a fused configuration (F or F-safe)"
        )
    t_step = nearest_step_time(estimates, time_s)
    est = estimates[estimates["t_s"] == t_step].sort_values("s_ahead_m")
    s = est["s_ahead_m"].to_numpy(dtype=float)
    mean, std = est["mean"].to_numpy(dtype=float), est["std"].to_numpy(dtype=float)

    fig = Figure(figsize=(7.5, 4.8), layout="constrained")
    ax = fig.subplots()
    ax.fill_between(s, mean - Z95 * std, mean + Z95 * std, color="tab:blue", alpha=0.2,
                    lw=0, label="posterior 95 % band (mean ± 1.96 std)")
    ax.plot(s, mean, color="tab:blue", lw=1.4, label="posterior mean", gid="mean")
    ax.step(s, est["mu_true"], where="post", color="black", lw=1.6, label="true μ", gid="true")
    ax.plot(s, est["mu_hat"], color="tab:red", lw=1.8, ls="--", label="μ̂ used by the planner",
            gid="mu_hat")
    data = est[np.isfinite(est["data_mu"].to_numpy(dtype=float))]
    if not data.empty:
        ax.errorbar(data["s_ahead_m"], data["data_mu"], yerr=data["data_margin"], fmt="o",
                    color="0.2", ms=3.5, capsize=2, lw=0.9, label="input data ± margin",
                    gid="data")
    ax.set_xlabel("distance ahead of the vehicle [m]")
    ax.set_ylabel("friction coefficient μ [-]")
    ax.set_ylim(0.0, 1.3)
    ax.set_xlim(float(s.min()), float(s.max()))
    ax.set_title(f"Fused friction estimate, {config_name(log)}, planning step at "
                 f"t = {t_step:.2f} s", fontsize=10)
    # Below the axes: the legend must never cover the band or the data.
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3)
    ax.grid(alpha=0.3)
    return fig


def plot_fused_estimate(log: RunLog, time_s: float, path: str | Path) -> Path:
    """The fused friction estimate of the planning step nearest ``time_s``.

    Shows against the distance ahead: the true μ, the fusion input data with error bars
    (``data_mu ± data_margin``), the posterior mean and its 95 % band (mean ± 1.96 std) and the
    μ̂ handed to the planner.

    Parameters
    ----------
    log : RunLog
        A fused configuration's run (its estimates table carries the posterior).
    time_s : float
        Instant [s]; the planning step nearest it is shown.
    path : str or Path
        Output PNG file.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If ``time_s`` lies outside the run or the log has no posterior (not a fused run).
    """
    return save_figure(build_estimate_figure(log, time_s), path)
