"""Heteroscedastic GP fusion of friction estimates (paper Sec. III and Appendix A): the public
single-horizon API, :func:`fuse` and :class:`GPFusion`.

The prior is a GP over the progress s with a constant mean and a squared-exponential kernel; the
data are friction values with 95 % margins; the fused estimate is the lower edge of the posterior's
95 % band. Two modes:

* ``"paper"``: the paper's method, exact: Appendix A with the prior mean restored and the noise as
  a variance, every data point with its own independent error.
* ``"safe"`` (beyond the paper): see :mod:`mufusion.fusion.safe`.

Input is validated once, at these functions; :func:`fuse_validated` is the shared core that takes
validated types. ``GPFusion`` owns a :class:`~mufusion.fusion.engine.PosteriorEngine` (its
caches); :func:`fuse` uses one shared default engine, so repeated calls on a fixed grid reuse the
eigen-decomposition too (building an engine per call would pay it, ≈ 1 ms, every call).
"""

from __future__ import annotations

import numpy as np

from mufusion.fusion.assembly import DEFAULT_GRID_M
from mufusion.fusion.data import (
    FusedEstimate,
    FusionData,
    FusionMode,
    check_mode,
    check_positions,
    clip_single,
    validate_data,
)
from mufusion.fusion.engine import PosteriorEngine, noise_sd_of
from mufusion.fusion.prior import PAPER_PRIOR, Z95, GPPrior, check_prior
from mufusion.fusion.reports import ReportData
from mufusion.fusion.safe import safe_estimate
from mufusion.fusion.shared_fusion import fuse_shared

DEFAULT_ENGINE = PosteriorEngine(max_grids=16)
"""The engine behind :func:`fuse` and :func:`~mufusion.fusion.fuse_batch` (caches at most 16
position sets; ``DEFAULT_ENGINE.clear()`` frees them)."""


def fuse_validated(
    engine: PosteriorEngine,
    prior: GPPrior,
    data: FusionData,
    e: np.ndarray,
    mode: str,
    reports: ReportData | None = None,
) -> FusedEstimate:
    """The fused estimate from validated inputs (no checks: the public entry points did them).

    Without reports (None or none left) the result is the two-source fusion, bit for bit; with
    them, :func:`~mufusion.fusion.shared_fusion.fuse_shared` on top of it.
    """
    if reports is not None and reports.size:
        without = fuse_validated(engine, prior, data, e, mode)
        return fuse_shared(engine, prior, data, e, mode, reports, without)
    if data.s_m.size == 0:
        mean = np.full(e.size, prior.mean)
        std = np.full(e.size, prior.std)
        lower = mean - Z95 * std
        return FusedEstimate(e, mean, std, lower, clip_single(lower, prior.upper, data))
    resid = data.mu - prior.mean
    noise_sd = noise_sd_of(data.margin)
    mean, std = engine.latent(prior, data.s_m, e, resid, noise_sd)
    mean += prior.mean  # in place: the engine returns fresh arrays
    lower = std * -Z95
    lower += mean
    if mode == "paper":
        return FusedEstimate(e, mean, std, lower, clip_single(lower, prior.upper, data))
    return safe_estimate(engine, prior, data, e, resid, noise_sd, (mean, std, lower))


def fuse(
    s_m: np.ndarray,
    mu: np.ndarray,
    margin: np.ndarray,
    prior: GPPrior,
    s_eval_m: np.ndarray,
    *,
    groups: np.ndarray | None = None,
    mode: FusionMode = "paper",
    reports: ReportData | None = None,
) -> FusedEstimate:
    """Fuse friction estimates with heteroscedastic GP regression (paper Sec. III, App. A).

    Parameters
    ----------
    s_m
        Data positions ahead of the vehicle [m], shape ``(n,)``, any order, repeats allowed,
        within ``POSITION_RANGE_M`` (± 1000 km).
    mu
        Estimated friction at ``s_m`` [-], shape ``(n,)``, within ``MU_RANGE`` = [0, 2].
    margin
        95 % half-width of each estimate [-], shape ``(n,)`` or scalar, within ``MARGIN_RANGE`` =
        [0, 1]. The noise std is ``max(margin / 1.96, NOISE_STD_FLOOR)`` and enters ``K + Σ`` as a
        variance.
    prior
        The GP prior (mean, std, length scale; each range-checked when the prior is built).
    s_eval_m
        Evaluation positions [m], shape ``(m,)``, non-empty, within ``POSITION_RANGE_M``.
    groups
        Optional integer label per data point: points with one label are copies of one estimate
        and share its error (safe mode only; ignored by paper mode except for validation).
    mode
        ``"paper"`` (the paper's method) or ``"safe"`` (shared errors and hard bounds).
    reports
        Optional shared reports in the same frame as ``s_m``
        (:func:`~mufusion.fusion.reports.report_data`): a third source, used one-sidedly
        (:mod:`~mufusion.fusion.shared_fusion`, decision 0060). None or empty: the result is
        the two-source fusion's, bit for bit.

    Returns
    -------
    FusedEstimate
        Paper mode: the exact posterior ``mean = m0 + K⋆ᵀ (K + Σ)⁻¹ (y − m0)``, the latent std,
        ``lower = mean − 1.96 std`` and ``mu_hat = lower``. Safe mode: mean/std/lower of the
        posterior with grouped noise, and ``mu_hat`` = the paper-mode lower bound capped by the
        hard bounds (see ``docs/fusion.md``). With no data the prior is returned. In both modes
        ``mu_hat`` is finite and within ``[0, max(prior.upper, max(mu))]``.

    Raises
    ------
    ValueError
        If an array is not 1-D or a value is not finite or outside its declared range, lengths
        differ, ``s_eval_m`` is empty, ``prior`` is not a :class:`GPPrior`, ``groups`` has the
        wrong length or non-integer labels, ``mode`` is unknown, or ``reports`` is not a
        :class:`~mufusion.fusion.reports.ReportData`.

    Examples
    --------
    >>> est = fuse([0.0, 10.0], [0.4, 0.5], [0.025, 0.1], PAPER_PRIOR, [0.0, 10.0])
    >>> bool(est.mu_hat[0] < 0.4)
    True
    """
    prior = check_prior(prior)
    mode = check_mode(mode)
    # The data never leave this call: validated, but not wrapped in read-only views.
    data = FusionData._trusted(*validate_data(s_m, mu, margin, groups), read_only=False)
    e = check_positions("s_eval_m", s_eval_m)
    return fuse_validated(DEFAULT_ENGINE, prior, data, e, mode, check_reports(reports))


def check_reports(reports: object) -> ReportData | None:
    """``reports`` if it is None or a :class:`~mufusion.fusion.reports.ReportData`, else
    ValueError."""
    if reports is None or isinstance(reports, ReportData):
        return reports
    raise ValueError(f"reports must be a ReportData or None, got {type(reports).__name__}")


class GPFusion:
    """Fusion on a fixed prior and evaluation grid: the state kept between planning steps.

    It owns a :class:`~mufusion.fusion.engine.PosteriorEngine`, whose cached eigen-features for
    the data positions (they repeat every step on a fixed grid) make a step one small Cholesky
    factorization and two triangular solves.

    Parameters
    ----------
    prior
        The GP prior.
    s_eval_m
        Evaluation grid [m], shape ``(m,)``; None means 0, 1, …, 50 m (``DEFAULT_GRID_M``).
    mode
        ``"paper"`` or ``"safe"``.

    Raises
    ------
    ValueError
        If ``prior``, ``s_eval_m`` or ``mode`` is invalid.

    Examples
    --------
    >>> f = GPFusion(PAPER_PRIOR, np.arange(0.0, 51.0))
    >>> f.fuse([0.0], [0.4], [0.025]).mu_hat.shape
    (51,)
    """

    def __init__(
        self,
        prior: GPPrior = PAPER_PRIOR,
        s_eval_m: np.ndarray | None = None,
        mode: FusionMode = "paper",
    ) -> None:
        self.prior = check_prior(prior)
        grid = DEFAULT_GRID_M if s_eval_m is None else s_eval_m
        self.s_eval_m = check_positions("s_eval_m", grid)
        self.mode = check_mode(mode)
        self.engine = PosteriorEngine(max_grids=4)

    def __repr__(self) -> str:
        return f"<GPFusion mode={self.mode!r}, {self.s_eval_m.size} evaluation points>"

    def fuse(
        self,
        s_m: np.ndarray,
        mu: np.ndarray,
        margin: np.ndarray,
        groups: np.ndarray | None = None,
    ) -> FusedEstimate:
        """:func:`fuse` with this object's prior, grid and mode (same parameters and errors)."""
        return self.step(FusionData(s_m, mu, margin, groups))

    def step(self, data: FusionData, reports: ReportData | None = None) -> FusedEstimate:
        """Fuse one :class:`~mufusion.fusion.FusionData` (one planning step; validated when built),
        with optional shared reports in the same frame (:func:`fuse`'s ``reports``).

        Raises
        ------
        ValueError
            If ``data`` is not a :class:`~mufusion.fusion.FusionData` or ``reports`` not a
            :class:`~mufusion.fusion.reports.ReportData` or None.
        """
        if not isinstance(data, FusionData):
            raise ValueError(f"data must be a FusionData, got {type(data).__name__}")
        return fuse_validated(
            self.engine, self.prior, data, self.s_eval_m, self.mode, check_reports(reports)
        )
