"""Figures of a fleet run (issue 40): the fused band with shared reports, and vehicle 1 against
vehicle N."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mufusion.estimators.shared import FrictionReport
from mufusion.fusion import Z95
from mufusion.plots._common import (
    check_time,
    config_name,
    nearest_step_time,
    require_logs,
    save_figure,
)
from mufusion.sim.log import RunLog


def _step(log: RunLog, time_s: float):
    check_time(log, time_s)
    est = log.estimates
    if est.empty or not est["mean"].notna().any():
        raise ValueError(f"log of {config_name(log)!r} has no posterior: a fused configuration "
                         "is needed")
    t_step = nearest_step_time(est, time_s)
    return est[est["t_s"] == t_step].sort_values("s_ahead_m"), t_step


def build_band_figure(
    log: RunLog, time_s: float, reports: Sequence[FrictionReport] = ()
) -> Figure:
    """The fused band of one planning step over the road's s, with the reports received (their
    95 % bounds as error bars, at their reported positions)."""
    (log,) = require_logs([log])
    est, t_step = _step(log, time_s)
    s = est["s_m"].to_numpy(dtype=float)
    mean, std = est["mean"].to_numpy(dtype=float), est["std"].to_numpy(dtype=float)
    fig = Figure(figsize=(7.5, 4.6), layout="constrained")
    ax = fig.subplots()
    ax.fill_between(s, mean - Z95 * std, mean + Z95 * std, color="tab:blue", alpha=0.2, lw=0,
                    label="posterior 95 % band")
    ax.plot(s, mean, color="tab:blue", lw=1.2, label="posterior mean")
    ax.plot(s, est["mu_hat"], color="tab:red", lw=1.8, label="μ̂ (planner)")
    ax.plot(s, est["mu_true"], color="black", lw=1.2, ls="--", label="true μ")
    ax.errorbar(s, est["data_mu"], yerr=est["data_margin"], fmt="none", color="tab:green",
                alpha=0.35, label="own data ± margin")
    near = [r for r in reports if s[0] - 5.0 <= r.s_m <= s[-1] + 5.0]
    if near:
        rs = np.array([r.s_m for r in near])
        mu = np.array([r.mu for r in near])
        lo = np.array([r.mu - r.lower_mu for r in near])
        hi = np.array([r.upper_mu - r.mu for r in near])
        ax.errorbar(rs, mu, yerr=[lo, hi], fmt="o", ms=3, color="tab:orange", alpha=0.8,
                    label=f"reports ({len(near)}, at creation)")
    ax.set_xlabel("s along the road [m]")
    ax.set_ylabel("μ [-]")
    ax.set_title(f"{config_name(log)}: fused estimate at t = {t_step:.1f} s")
    ax.legend(fontsize=8, loc="lower left")
    return fig


def plot_band(
    log: RunLog, time_s: float, path: str | Path, reports: Sequence[FrictionReport] = ()
) -> Path:
    """Write :func:`build_band_figure` to ``path``."""
    return save_figure(build_band_figure(log, time_s, reports), path)


def build_first_last_figure(first: RunLog, last: RunLog, time_s: float) -> Figure:
    """Vehicle 1 against vehicle N: μ̂ at one planning step over s, speed and lateral offset over
    s (each vehicle's whole run)."""
    logs = require_logs([first, last])
    fig = Figure(figsize=(7.5, 7.0), layout="constrained")
    ax_mu, ax_v, ax_d = fig.subplots(3, 1)
    for log, label, color in zip(logs, ("vehicle 1", "vehicle N"), ("tab:gray", "tab:red"),
                                 strict=True):
        est, t_step = _step(log, time_s)
        ax_mu.plot(est["s_m"], est["mu_hat"], color=color, lw=1.6,
                   label=f"{label}: μ̂ at t = {t_step:.1f} s")
        ts = log.timeseries
        ax_v.plot(ts["s_m"], ts["speed_mps"], color=color, lw=1.4, label=label)
        ax_d.plot(ts["s_m"], ts["d_m"], color=color, lw=1.4, label=label)
    est, _ = _step(logs[0], time_s)
    ax_mu.plot(est["s_m"], est["mu_true"], color="black", ls="--", lw=1.0, label="true μ")
    ax_mu.set_ylabel("μ [-]")
    ax_v.set_ylabel("speed [m/s]")
    ax_d.set_ylabel("lateral offset d [m]")
    ax_d.set_xlabel("s along the road [m]")
    for ax in (ax_mu, ax_v, ax_d):
        ax.legend(fontsize=8)
    ax_mu.set_title(f"{config_name(logs[1])}: vehicle 1 against vehicle N")
    return fig


def plot_first_last(first: RunLog, last: RunLog, time_s: float, path: str | Path) -> Path:
    """Write :func:`build_first_last_figure` to ``path``."""
    return save_figure(build_first_last_figure(first, last, time_s), path)
