"""Fusion calibration without a closed loop: how often does μ̂ exceed the true μ, and by how much?

Random horizons are drawn as the configurations F and F-safe see them (paper Sec. IV-B): a
surface layout on the grid 0, 1, …, 50 m ahead with 0–3 changes of the paper's classes
(:data:`~mufusion.estimators.PAPER_CLASSES`), one true μ per class segment drawn within its
class, the camera (:func:`~mufusion.estimators.predictive_estimate`'s error model ``"random"``:
one error per class segment, uniform within the class margin; vectorized here over the horizons,
equal to ``predictive_estimate`` row by row for the same draws, which a test checks), and the
local estimate present or absent, its error uniform within ±0.025 (Table I). The inputs are
assembled as the configurations do (:func:`~mufusion.fusion.assemble_inputs_batch`, which equals
``assemble_inputs`` row by row; default s_l) and fused in both modes with
:func:`~mufusion.fusion.fuse_batch`. Every error lies within its declared margin, which is the
premise of safe mode's guarantee, so safe mode must show no over-estimate at all.

The result, per distance ahead and overall: the rate of μ̂ > μ_gt, the mean and the
5th-percentile shortfall μ_gt − μ̂ (negative: over-estimate), and the coverage of the posterior
lower bound ``mean − 1.96 std`` (its nominal one-sided level is 97.5 %).

This module lives in the configurations layer because it needs the estimators' class table and
error models, which the fusion layer must not import.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from mufusion.estimators import (
    LOCAL_MAX_ERROR,
    PAPER_CLASSES,
    SurfaceClass,
    classify,
    validate_classes,
)
from mufusion.estimators.errors import signed_error
from mufusion.fusion.assembly import DEFAULT_GRID_M, assemble_inputs_batch
from mufusion.fusion.batch import fuse_batch
from mufusion.fusion.data import MODES, FusionMode
from mufusion.fusion.prior import PAPER_PRIOR, GPPrior

NOMINAL_COVERAGE = 0.975
"""One-sided level of the posterior lower bound ``mean − 1.96 std`` [-] (Φ(1.96))."""

DEFAULT_HORIZONS = 100_000
"""Horizons drawn by ``mufusion calibrate`` unless told otherwise."""

MAX_CLASS_CHANGES = 3
"""Class changes per horizon are drawn uniformly from 0, 1, …, this."""

LOCAL_PRESENT_PROBABILITY = 0.5
"""Probability that the local estimate is available on a horizon [-]."""

_MODES: tuple[FusionMode, ...] = tuple(cast(FusionMode, m) for m in MODES)
_CHUNK = 5_000  # horizons per fuse_batch call: bounds the (B, r, r) arrays of the batch path


@dataclass(frozen=True)
class ModeCalibration:
    """Calibration of one fusion mode; every ``*_by_s`` array has one value per distance ahead.

    Attributes
    ----------
    mode
        ``"paper"`` or ``"safe"``.
    over_estimate_rate_by_s, over_estimate_rate
        Share of horizons with μ̂ > μ_gt [-] per distance ahead, and over all distances.
    mean_shortfall_by_s, mean_shortfall
        Mean of μ_gt − μ̂ [-] (positive: conservative).
    p05_shortfall_by_s, p05_shortfall
        5th percentile of μ_gt − μ̂ [-] (the worst 5 %; negative: over-estimate).
    lower_coverage_by_s, lower_coverage
        Share of horizons with ``lower <= μ_gt`` [-]: the empirical coverage of the posterior
        lower bound (paper mode: the paper's posterior; safe mode: the grouped-noise one).
    max_over_estimate
        Largest μ̂ − μ_gt over all horizons and distances [-].
    """

    mode: str
    over_estimate_rate_by_s: np.ndarray
    mean_shortfall_by_s: np.ndarray
    p05_shortfall_by_s: np.ndarray
    lower_coverage_by_s: np.ndarray
    over_estimate_rate: float
    mean_shortfall: float
    p05_shortfall: float
    lower_coverage: float
    max_over_estimate: float

    def to_dict(self) -> dict[str, object]:
        """JSON-ready values (arrays as lists)."""
        return {
            name: (value.tolist() if isinstance(value, np.ndarray) else value)
            for name, value in self.__dict__.items()
        }


@dataclass(frozen=True)
class CalibrationResult:
    """Fusion calibration over random horizons (see the module docstring).

    Attributes
    ----------
    n_horizons
        Number of horizons drawn.
    s_ahead_m
        Distances ahead of the vehicle [m], shape ``(m,)``.
    nominal_coverage
        Nominal one-sided level of the posterior lower bound [-] (0.975).
    local_present_share
        Share of the horizons on which the local estimate was available [-].
    class_changes_mean
        Mean number of class changes per horizon [-].
    paper, safe
        Calibration of each fusion mode.
    """

    n_horizons: int
    s_ahead_m: np.ndarray
    nominal_coverage: float
    local_present_share: float
    class_changes_mean: float
    paper: ModeCalibration
    safe: ModeCalibration

    def mode(self, name: str) -> ModeCalibration:
        """The calibration of mode ``name`` (``"paper"`` or ``"safe"``)."""
        if name not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {name!r}")
        return self.paper if name == "paper" else self.safe

    def to_dict(self) -> dict[str, object]:
        """JSON-ready values (arrays as lists)."""
        return {
            "n_horizons": self.n_horizons,
            "s_ahead_m": self.s_ahead_m.tolist(),
            "nominal_coverage": self.nominal_coverage,
            "local_present_share": self.local_present_share,
            "class_changes_mean": self.class_changes_mean,
            "paper": self.paper.to_dict(),
            "safe": self.safe.to_dict(),
        }


@dataclass(frozen=True)
class CalibrationHorizons:
    """Horizons to calibrate on: the true μ on the grid and the estimators' outputs.

    Attributes
    ----------
    s_ahead_m
        Grid of distances ahead [m], shape ``(m,)``.
    mu_gt
        True μ [-], shape ``(B, m)``, in (0, 2].
    camera_mu, camera_margin
        Camera report and class margin [-], shape ``(B, m)`` (NaN where the camera sees nothing).
    local_mu
        Local estimate [-], shape ``(B,)``; NaN where it is unavailable.
    n_changes
        Class changes per horizon, shape ``(B,)`` (reported only).

    Raises
    ------
    ValueError
        If the shapes disagree or ``mu_gt`` is not finite and in (0, 2].
    """

    s_ahead_m: np.ndarray
    mu_gt: np.ndarray
    camera_mu: np.ndarray
    camera_margin: np.ndarray
    local_mu: np.ndarray
    n_changes: np.ndarray

    def __post_init__(self) -> None:
        s = np.asarray(self.s_ahead_m, dtype=float)
        gt = np.asarray(self.mu_gt, dtype=float)
        if s.ndim != 1 or gt.ndim != 2 or gt.shape[1] != s.size or gt.shape[0] < 1:
            raise ValueError(
                f"mu_gt must have shape (B, {s.size}) with B >= 1, got {gt.shape}"
            )
        for name in ("camera_mu", "camera_margin"):
            if np.shape(getattr(self, name)) != gt.shape:
                raise ValueError(f"{name} must have shape {gt.shape}")
        for name in ("local_mu", "n_changes"):
            if np.shape(getattr(self, name)) != gt.shape[:1]:
                raise ValueError(f"{name} must have shape {gt.shape[:1]}")
        if not (np.isfinite(gt).all() and (gt > 0.0).all() and (gt <= 2.0).all()):
            raise ValueError("mu_gt must be finite and in (0, 2]")


def draw_horizons(
    rng: np.random.Generator,
    n_horizons: int,
    classes: Sequence[SurfaceClass] = PAPER_CLASSES,
    s_ahead_m: np.ndarray = DEFAULT_GRID_M,
) -> CalibrationHorizons:
    """Draw random horizons (see the module docstring) from ``rng``.

    Raises
    ------
    ValueError
        If ``rng`` is not a Generator, ``n_horizons`` not an integer >= 1, or ``classes`` bad.
    """
    _check_rng_and_count(rng, n_horizons)
    table = validate_classes(classes)
    s = np.asarray(s_ahead_m, dtype=float)
    n = int(n_horizons)
    k = len(table)
    lows = np.array([c.mu_low for c in table])
    # μ_gt within the class and within its margin: the open dry class is drawn up to its
    # value + margin (1.0), the top the camera's 95 % interval covers.
    tops = np.array([min(c.mu_high, c.value + c.margin) for c in table])
    n_changes = rng.integers(0, MAX_CLASS_CHANGES + 1, n)
    change_m = np.sort(rng.uniform(s[0], s[-1], (n, MAX_CLASS_CHANGES)), axis=1)
    # Unused change positions move past the grid, so a horizon has exactly n_changes changes.
    change_m[np.arange(MAX_CLASS_CHANGES)[None, :] >= n_changes[:, None]] = np.inf
    n_seg = MAX_CLASS_CHANGES + 1
    # Consecutive segments differ in class (a change of μ within one class is invisible to the
    # camera and is no class change).
    seg_class = np.empty((n, n_seg), dtype=np.int64)
    seg_class[:, 0] = rng.integers(0, k, n)
    for j in range(1, n_seg):
        seg_class[:, j] = (seg_class[:, j - 1] + rng.integers(1, k, n)) % k
    seg_mu = rng.uniform(lows[seg_class], tops[seg_class])
    segment = (s[None, :, None] >= change_m[:, None, :]).sum(axis=2)  # (n, m)
    mu_gt = np.take_along_axis(seg_mu, segment, axis=1)
    present = rng.uniform(size=n) < LOCAL_PRESENT_PROBABILITY
    local_error = signed_error("random", np.full(n, LOCAL_MAX_ERROR), rng)
    local_mu = np.where(present, mu_gt[:, 0] + local_error, np.nan)
    unit_error = rng.uniform(-1.0, 1.0, (n, n_seg))
    camera_mu, camera_margin = camera_random(mu_gt, unit_error, table)
    return CalibrationHorizons(s, mu_gt, camera_mu, camera_margin, local_mu, n_changes)


def camera_random(
    mu_gt: np.ndarray, unit_error: np.ndarray, classes: tuple[SurfaceClass, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """The camera's report and margin under the ``"random"`` error model, for ``B`` horizons.

    Row ``b`` equals :func:`~mufusion.estimators.predictive_estimate` on ``mu_gt[b]`` (all in
    range) when its generator draws ``unit_error[b, :k]`` for the row's ``k`` class segments:
    the report is ``max(μ_gt + e · margin, 0)`` with one unit error ``e`` per contiguous segment.
    """
    idx = classify(mu_gt, classes)
    change = np.zeros(idx.shape, dtype=bool)
    change[:, 1:] = idx[:, 1:] != idx[:, :-1]
    segment = np.cumsum(change, axis=1)
    margin = np.array([c.margin for c in classes])[idx]
    report = mu_gt + np.take_along_axis(unit_error, segment, axis=1) * margin
    return np.maximum(report, 0.0), margin


def _fuse_mode(
    h: CalibrationHorizons, rows: slice, prior: GPPrior, mode: FusionMode
) -> tuple[np.ndarray, np.ndarray]:
    """μ̂ and the posterior lower bound, shape ``(B, m)``, of some horizons in one mode."""
    s = h.s_ahead_m
    data = assemble_inputs_batch(
        s, h.camera_mu[rows], h.camera_margin[rows], local_mu=h.local_mu[rows], mode=mode
    )
    est = fuse_batch(data.s_m, data.mu, data.margin, prior, s, groups=data.groups, mode=mode)
    return est.mu_hat, est.lower


def _summarise(
    mode: str, mu_gt: np.ndarray, mu_hat: np.ndarray, lower: np.ndarray
) -> ModeCalibration:
    shortfall = mu_gt - mu_hat
    over = shortfall < 0.0
    covered = lower <= mu_gt
    return ModeCalibration(
        mode=mode,
        over_estimate_rate_by_s=over.mean(axis=0),
        mean_shortfall_by_s=shortfall.mean(axis=0),
        p05_shortfall_by_s=np.percentile(shortfall, 5.0, axis=0),
        lower_coverage_by_s=covered.mean(axis=0),
        over_estimate_rate=float(over.mean()),
        mean_shortfall=float(shortfall.mean()),
        p05_shortfall=float(np.percentile(shortfall, 5.0)),
        lower_coverage=float(covered.mean()),
        max_over_estimate=float(-shortfall.min()),
    )


def _check_rng_and_count(rng: object, n_horizons: object) -> None:
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if (
        isinstance(n_horizons, bool)
        or not isinstance(n_horizons, int | np.integer)
        or n_horizons < 1
    ):
        raise ValueError(f"n_horizons must be an integer >= 1, got {n_horizons!r}")


def calibrate_horizons(
    horizons: CalibrationHorizons, prior: GPPrior = PAPER_PRIOR
) -> CalibrationResult:
    """Fuse given horizons in both modes and summarise (see the module docstring).

    Parameters
    ----------
    horizons
        The horizons, e.g. from :func:`draw_horizons` or a hand-built worst case.
    prior
        The fusion's GP prior; default the paper's.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    ValueError
        If ``horizons`` or ``prior`` has the wrong type, or the fusion rejects an input.
    """
    if not isinstance(horizons, CalibrationHorizons):
        raise ValueError(
            f"horizons must be CalibrationHorizons, got {type(horizons).__name__}"
        )
    if not isinstance(prior, GPPrior):
        raise ValueError(f"prior must be a GPPrior, got {type(prior).__name__}")
    n = horizons.mu_gt.shape[0]
    fused: dict[FusionMode, tuple[list[np.ndarray], list[np.ndarray]]] = {
        mode: ([], []) for mode in _MODES
    }
    for start in range(0, n, _CHUNK):
        rows = slice(start, min(start + _CHUNK, n))
        for mode in _MODES:
            mu_hat, lower = _fuse_mode(horizons, rows, prior, mode)
            fused[mode][0].append(mu_hat)
            fused[mode][1].append(lower)
    summary = {
        mode: _summarise(mode, horizons.mu_gt, np.concatenate(hats), np.concatenate(lows))
        for mode, (hats, lows) in fused.items()
    }
    return CalibrationResult(
        n_horizons=n,
        s_ahead_m=np.array(horizons.s_ahead_m, dtype=float),
        nominal_coverage=NOMINAL_COVERAGE,
        local_present_share=float((~np.isnan(horizons.local_mu)).mean()),
        class_changes_mean=float(np.mean(horizons.n_changes)),
        paper=summary["paper"],
        safe=summary["safe"],
    )


def calibrate_fusion(
    rng: np.random.Generator,
    *,
    n_horizons: int = DEFAULT_HORIZONS,
    classes: Sequence[SurfaceClass] = PAPER_CLASSES,
    prior: GPPrior = PAPER_PRIOR,
) -> CalibrationResult:
    """Calibrate both fusion modes on random horizons (see the module docstring).

    Parameters
    ----------
    rng
        Source of all randomness (layouts, true μ, estimator errors, local availability).
    n_horizons
        Number of horizons, ``>= 1`` (``mufusion calibrate`` draws 100 000).
    classes
        Camera class table; default the paper's.
    prior
        The fusion's GP prior; default the paper's.

    Returns
    -------
    CalibrationResult
        Per distance ahead (0, 1, …, 50 m) and overall, for both modes.

    Raises
    ------
    ValueError
        If ``rng`` is not a :class:`numpy.random.Generator`, ``n_horizons`` is not an integer
        ``>= 1``, or ``classes`` / ``prior`` is invalid.

    Examples
    --------
    >>> res = calibrate_fusion(np.random.default_rng(0), n_horizons=200)
    >>> res.safe.over_estimate_rate, res.s_ahead_m.size
    (0.0, 51)
    """
    return calibrate_horizons(draw_horizons(rng, n_horizons, classes), prior)
