"""Calibration figure of the fusion: over-estimate rate and lower-bound coverage vs distance ahead.

Reads a :class:`~mufusion.fusion.calibration.CalibrationResult` (no simulation). Built on
:class:`matplotlib.figure.Figure` directly: no display, no global pyplot state.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from mufusion.fusion.calibration import CalibrationResult
from mufusion.plots._common import CONFIG_COLORS, save_figure

# The fused configurations' colours: paper mode is F, safe mode is F-safe.
_MODE_STYLE = {
    "paper": {"color": CONFIG_COLORS["F"], "label": "F (paper mode)"},
    "safe": {"color": CONFIG_COLORS["F-safe"], "label": "F-safe (safe mode)"},
}


def build_calibration_figure(result: CalibrationResult) -> Figure:
    """Two panels over the distance ahead [m], both fusion modes in each.

    Left: the share of horizons with μ̂ > μ_gt. Right: the empirical coverage of the posterior
    lower bound ``mean − 1.96 std`` (share of horizons with lower ≤ μ_gt), with the nominal
    one-sided 97.5 % level drawn.

    Parameters
    ----------
    result
        The calibration to draw.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        If ``result`` is not a :class:`CalibrationResult`.
    """
    if not isinstance(result, CalibrationResult):
        raise ValueError(f"result must be a CalibrationResult, got {type(result).__name__}")
    fig = Figure(figsize=(10.0, 4.0), layout="constrained")
    over_ax, cover_ax = fig.subplots(1, 2, sharex=True)
    s = result.s_ahead_m
    for mode, style in _MODE_STYLE.items():
        cal = result.mode(mode)
        over_ax.plot(s, 100.0 * cal.over_estimate_rate_by_s, **style)
        cover_ax.plot(s, 100.0 * cal.lower_coverage_by_s, **style)
    over_ax.set_title("μ̂ above the true μ")
    over_ax.set_ylabel("share of horizons [%]")
    over_ax.set_ylim(bottom=-1.0)  # a rate of exactly 0 stays visible above the axis
    cover_ax.axhline(
        100.0 * result.nominal_coverage, color="black", linestyle="--",
        label=f"nominal {100.0 * result.nominal_coverage:.1f} % (one-sided)",
    )
    cover_ax.set_title("coverage of the posterior lower bound")
    cover_ax.set_ylabel("share of horizons with lower ≤ μ_gt [%]")
    cover_ax.set_ylim(0.0, 100.0)
    for ax in (over_ax, cover_ax):
        ax.set_xlabel("distance ahead s [m]")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower left", fontsize="small")
    fig.suptitle(f"Fusion calibration over {result.n_horizons:,} random horizons")
    return fig


def calibration_figure(result: CalibrationResult, path: str | Path) -> Path:
    """Draw :func:`build_calibration_figure` and write it to ``path`` (PNG); returns the path.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from mufusion.fusion.calibration import calibrate_fusion
    >>> res = calibrate_fusion(np.random.default_rng(0), n_horizons=50)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     calibration_figure(res, pathlib.Path(tmp) / "c.png").suffix
    '.png'
    """
    return save_figure(build_calibration_figure(result), path)
