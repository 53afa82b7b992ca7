"""Stand-alone demonstration of the GP fusion (the paper's Fig. 2), without a closed-loop run.

A vehicle approaches a low-μ section: dry road (μ = 0.8) under it and snow/ice (μ = 0.3) from
25 m ahead, with the tires excited enough for the local estimate to be available. One fused
configuration step is computed per fusion mode (paper and safe) and drawn: the prior's 95 %
band, the input data with their margins (local and camera apart), the posterior mean and 95 %
band, the fused estimate μ̂ handed to the planner and the true μ.

The figure is built on :class:`matplotlib.figure.Figure` directly, so it needs no display and
no global pyplot state (the Agg canvas renders it).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from mufusion.configurations import FrictionEstimate, make_configuration
from mufusion.estimators import CAMERA_RANGE_M
from mufusion.fusion import LOCAL_GROUP, PAPER_PRIOR, Z95, FusionData
from mufusion.plots._common import save_figure

FUSION_DEMO_MODES: tuple[str, ...] = ("paper", "safe", "both")
_MODE_CONFIGURATION = {"paper": "F", "safe": "F-safe"}
# The same colours in both panels, so that one legend serves both (panel titles name the mode).
_POSTERIOR_COLOR = "tab:blue"
_MU_HAT_COLOR = "#08306b"


def demo_estimates(
    *,
    modes: tuple[str, ...] = ("paper", "safe"),
    mu_before: float = 0.8,
    mu_after: float = 0.3,
    change_ahead_m: float = 25.0,
    utilization: float = 0.7,
    s_max_m: float = 60.0,
    ds_m: float = 1.0,
    local_error: str = "none",
    predictive_error: str = "none",
    seed: int = 0,
) -> dict[str, tuple[np.ndarray, FrictionEstimate]]:
    """One fused estimate per mode for the demo road: ``{mode: (mu_true, estimate)}``.

    Parameters are those of :func:`fusion_demo_figure`. Raises ``ValueError`` on a bad value.
    """
    if not (math.isfinite(s_max_m) and s_max_m > 0.0):
        raise ValueError(f"s_max_m must be finite and > 0 m, got {s_max_m!r}")
    if not (math.isfinite(ds_m) and 0.0 < ds_m <= s_max_m):
        raise ValueError(f"ds_m must be in (0, s_max_m] = (0, {s_max_m}] m, got {ds_m!r}")
    if not (math.isfinite(change_ahead_m) and change_ahead_m >= 0.0):
        raise ValueError(f"change_ahead_m must be finite and ≥ 0 m, got {change_ahead_m!r}")
    s = np.arange(0.0, s_max_m + 0.5 * ds_m, ds_m)
    mu_true = np.where(s < change_ahead_m, float(mu_before), float(mu_after))
    out = {}
    for mode in modes:
        conf = make_configuration(
            _MODE_CONFIGURATION[mode],
            local_error=local_error,
            predictive_error=predictive_error,
            rng=np.random.default_rng(seed),
        )
        out[mode] = (mu_true, conf.step(s, mu_true, utilization))
    return out


def _local_mask(data: FusionData) -> np.ndarray:
    """Which fusion input points came from the local estimate (the rest are the camera's)."""
    return np.asarray(data.groups) == LOCAL_GROUP


def _draw_panel(ax: Axes, mode: str, mu_true: np.ndarray, est: FrictionEstimate, prior) -> None:
    s = est.s_m
    fused, data = est.fused, est.data
    if fused is None or data is None:
        raise ValueError("the demonstration needs a fused configuration (F or F-safe)")
    prior_mean, prior_std = float(prior.mean), float(prior.std)
    ax.axhspan(prior_mean - Z95 * prior_std, prior_mean + Z95 * prior_std, color="0.85",
               lw=0, label="prior 95 % band", gid="prior")
    ax.axhline(prior_mean, color="0.6", lw=1.0, ls=":", label="prior mean")
    mean, std = np.asarray(fused.mean), np.asarray(fused.std)
    ax.fill_between(s, mean - Z95 * std, mean + Z95 * std, color=_POSTERIOR_COLOR,
                    alpha=0.22, lw=0, label="posterior 95 % band", gid="posterior_band")
    ax.plot(s, mean, color=_POSTERIOR_COLOR, lw=1.2, label="posterior mean", gid="posterior_mean")
    local = _local_mask(data)
    ds, dmu, dm = (np.asarray(a, dtype=float) for a in (data.s_m, data.mu, data.margin))
    if np.any(~local):
        ax.errorbar(ds[~local], dmu[~local], yerr=dm[~local], fmt="o", ms=3, color="0.25",
                    ecolor="0.55", lw=0.6, capsize=2, label="camera estimate ± margin",
                    gid="camera")
    if np.any(local):
        ax.errorbar(ds[local], dmu[local], yerr=dm[local], fmt="D", ms=4, color="tab:red",
                    ecolor="tab:red", lw=1.0, capsize=2, label="local estimate ± margin",
                    gid="local")
    ax.step(s, mu_true, where="post", color="black", lw=1.4, ls="--", label="true μ",
            gid="true")
    ax.plot(s, est.mu_hat, color=_MU_HAT_COLOR, lw=2.8, label="fused estimate μ̂ (to the planner)",
            gid="mu_hat")
    if s[-1] > CAMERA_RANGE_M:
        ax.axvline(CAMERA_RANGE_M, color="0.3", lw=0.8, ls="-.", label="camera range")
    ax.set_title(f"{_MODE_CONFIGURATION[mode]} ({mode} fusion)", fontsize=10)
    ax.set_xlabel("distance ahead s [m]")
    ax.set_xlim(float(s[0]), float(s[-1]))
    ax.set_ylim(-0.1, 1.25)
    ax.grid(alpha=0.3)


def build_fusion_demo_figure(mode: str = "both", **kwargs) -> Figure:
    """The figure of :func:`fusion_demo_figure` (same parameters, without the path)."""
    if mode not in FUSION_DEMO_MODES:
        raise ValueError(f"mode must be one of {list(FUSION_DEMO_MODES)}, got {mode!r}")
    modes = ("paper", "safe") if mode == "both" else (mode,)
    estimates = demo_estimates(modes=modes, **kwargs)
    fig = Figure(figsize=(5.2 * len(modes) + 0.8, 4.9), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(modes), sharey=True))
    for ax, m in zip(axes, modes, strict=True):
        mu_true, est = estimates[m]
        _draw_panel(ax, m, mu_true, est, PAPER_PRIOR)
    axes[0].set_ylabel("friction coefficient μ [-]")
    mu_true = estimates[modes[0]][0]
    fig.suptitle(
        "GP fusion of camera and local friction estimates approaching a low-μ section "
        f"(μ {mu_true[0]:g} → {mu_true[-1]:g})",
        fontsize=11,
    )
    # One legend below the panels: it must never cover the bands or the data.
    handles, labels = axes[-1].get_legend_handles_labels()
    for ax in axes[:-1]:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8)
    return fig


def fusion_demo_figure(
    out_path: str | Path,
    *,
    mode: str = "both",
    mu_before: float = 0.8,
    mu_after: float = 0.3,
    change_ahead_m: float = 25.0,
    utilization: float = 0.7,
    s_max_m: float = 60.0,
    ds_m: float = 1.0,
    local_error: str = "none",
    predictive_error: str = "none",
    seed: int = 0,
) -> Path:
    """Write the fusion demonstration figure (cf. the paper's Fig. 2) as a PNG.

    Parameters
    ----------
    out_path : str or Path
        Output file (parent directories are created).
    mode : {"paper", "safe", "both"}
        Fusion mode(s) to draw; ``"both"`` draws the two side by side.
    mu_before, mu_after : float
        True μ before and after the change [-]; must lie in the camera's classes.
    change_ahead_m : float
        Distance ahead of the vehicle where μ changes [m].
    utilization : float
        Tire-force utilization [-]; above 0.5 the local estimate is available.
    s_max_m, ds_m : float
        Extent and spacing of the grid ahead [m]; beyond the camera's 50 m there is no data.
    local_error, predictive_error : {"none", "worst_over", "worst_under", "random"}
        Error models of the emulated estimators.
    seed : int
        Seed of the generator used by ``"random"`` error models.

    Returns
    -------
    Path
        ``out_path``.

    Raises
    ------
    ValueError
        If ``mode`` is unknown or another argument is out of range.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = fusion_demo_figure(pathlib.Path(tmp) / "fusion.png", mode="paper")
    ...     path.stat().st_size > 0
    True
    """
    return save_figure(build_fusion_demo_figure(mode, mu_before=mu_before, mu_after=mu_after,
                                                change_ahead_m=change_ahead_m,
                                                utilization=utilization, s_max_m=s_max_m,
                                                ds_m=ds_m, local_error=local_error,
                                                predictive_error=predictive_error, seed=seed),
                       out_path)
