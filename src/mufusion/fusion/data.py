"""Fusion data and result types, the declared physical ranges, and the checks at the boundary.

Every public entry point (:func:`~mufusion.fusion.fuse`, :func:`~mufusion.fusion.fuse_batch`,
:class:`~mufusion.fusion.GPFusion`, :func:`~mufusion.fusion.assemble_inputs`) validates its input
once, here, into a :class:`FusionData`; the posterior engine and safe mode take validated types
and check nothing again.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Literal, cast

import numpy as np

logger = logging.getLogger(__name__)

FusionMode = Literal["paper", "safe"]
MODES: tuple[str, ...] = ("paper", "safe")

MU_RANGE = (0.0, 2.0)
"""Allowed friction value of a datum [-], inclusive. 0: the camera emulation clips a report that
its error would push below 0 to 0 (``mufusion.estimators.predictive``); 2: above any tyre-road
pair (racing slicks on dry asphalt reach ≈ 1.7)."""

MARGIN_RANGE = (0.0, 1.0)
"""Allowed 95 % half-width of a datum [-], inclusive. A margin of 1 around any μ in ``MU_RANGE``
already covers the whole physical range; a larger one says nothing more."""

POSITION_RANGE_M = (-1e6, 1e6)
"""Allowed data and evaluation positions [m], inclusive (± 1000 km along the road). Keeps
(s − s')² / ℓ² finite for every allowed length scale."""

NOISE_STD_FLOOR = 1e-3
"""Minimum noise std of a datum in the GP [-] (a 95 % margin of 0.00196).

The noise std is ``max(margin / 1.96, NOISE_STD_FLOOR)``. Why: with zero or tiny margins,
near-duplicate positions make K + Σ singular and the posterior mean explodes (two points 1e-6 m
apart with margins 1e-12 gave μ̂ of ± 1e6). With the floor, the smallest eigenvalue of K + Σ is at
least 1e-6 and the largest at most n · std² ≤ n (``PRIOR_STD_RANGE``), so the condition number
is at most 1 + 1e6 · n. It is also 1e-3 of the widest allowed prior std, which keeps the
eigen-feature path exact for every allowed prior. It sits far below every estimator's margin
(local 0.025, classes 0.1–0.2): results with real estimators do not change. Safe mode's hard
bounds ``y − margin`` keep the declared margins."""


@dataclass(frozen=True)
class FusedEstimate:
    """Fused friction estimate over the evaluation positions.

    Attributes
    ----------
    s_m
        Evaluation positions ahead of the vehicle [m], shape ``(m,)``.
    mean
        Posterior mean η⋆ of μ [-], shape ``(m,)`` (``(B, m)`` from :func:`fuse_batch`).
    std
        Posterior std σ⋆ of the latent μ (no noise added) [-].
    lower
        ``mean − 1.96 · std`` [-].
    mu_hat
        The estimate given to the planner [-]: ``lower`` in paper mode, capped by the hard bounds
        in safe mode; in both modes kept within the band ``[0, max(prior.upper, max(mu))]``
        (``docs/fusion.md``, "Declared ranges and the μ̂ band").
    """

    s_m: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    lower: np.ndarray
    mu_hat: np.ndarray


def band_top(prior_upper: float, mu_max: float) -> float:
    """Top of the μ̂ band [-]: the prior's upper 95 % edge or the largest datum, the larger."""
    return max(prior_upper, mu_max)


def clip_single(mu_hat: np.ndarray, prior_upper: float, data: FusionData) -> np.ndarray:
    """:func:`clip_to_band` for one horizon; the data's largest value is looked up only when μ̂
    exceeds the prior's upper edge (rare), since the band's top is at least that edge."""
    if np.maximum.reduce(mu_hat) > prior_upper:
        return clip_to_band(mu_hat, band_top(prior_upper, data.mu_max))
    return np.maximum(mu_hat, 0.0)


def clip_to_band(mu_hat: np.ndarray, top: float | np.ndarray) -> np.ndarray:
    """μ̂ kept within the band ``[0, top]`` (a new array); ``top`` a scalar or ``(B, 1)``.

    0 from below: μ > 0 physically, so a negative lower bound carries no information and 0 is
    still a lower bound. ``top`` from above: a lower bound on μ above both the prior's band and
    every datum comes from the squared-exponential GP overshooting where the data change faster
    than ℓ allows (a sharp class change, or contradicting data closer than ℓ, where it rings);
    capping it only lowers μ̂ and is logged as a warning.
    """
    if np.ndim(top) == 0:
        exceeded = bool(np.maximum.reduce(mu_hat, axis=None) > top)
    else:
        exceeded = bool((mu_hat > top).any())
    if exceeded:
        logger.warning(
            "fused lower bound above the band top at %d point(s) (max %.4g): capped; the GP "
            "overshoots where the data change faster than its length scale allows",
            int(np.count_nonzero(mu_hat > top)),
            float(np.max(mu_hat)),
        )
        mu_hat = np.minimum(mu_hat, top)
    return np.maximum(mu_hat, 0.0)


def _range_error(name: str, arr: np.ndarray, bounds: tuple[float, float], unit: str) -> None:
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    lo, hi = bounds
    got = f"got values from {float(arr.min())!r} to {float(arr.max())!r}"
    raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}]{unit}, {got}")


def check_range(
    name: str, arr: np.ndarray, bounds: tuple[float, float], unit: str = ""
) -> tuple[float, float]:
    """Smallest and largest element of a non-empty ``arr``; ValueError naming ``name`` if one is
    outside ``bounds`` (inclusive) or not finite (NaN propagates through the reductions)."""
    lo_v = float(np.minimum.reduce(arr, axis=None))
    hi_v = float(np.maximum.reduce(arr, axis=None))
    if not (bounds[0] <= lo_v and hi_v <= bounds[1]):
        _range_error(name, arr, bounds, unit)
    return lo_v, hi_v


def check_abs(name: str, arr: np.ndarray, bound: float, unit: str = "") -> None:
    """ValueError naming ``name`` unless every element is finite and ``|x| <= bound``.

    Fast path for 1-D arrays: ``x · x <= bound²`` implies it (max |x| ≤ ‖x‖₂) and is one BLAS
    call; NaN, inf and overflow all fail it, and only then is the exact check run.
    """
    if arr.ndim == 1 and arr.dot(arr) <= bound * bound:
        return
    if not np.maximum.reduce(np.abs(arr), axis=None) <= bound:
        _range_error(name, arr, (-bound, bound), unit)


def check_mode(mode: object) -> FusionMode:
    """``mode`` if it is one of :data:`MODES`, else ValueError."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    return cast(FusionMode, mode)


def check_positions(name: str, value: object) -> np.ndarray:
    """A non-empty, 1-D, read-only float array of positions within ``POSITION_RANGE_M``."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    check_abs(name, arr, POSITION_RANGE_M[1], " m")
    arr = arr.view()  # a new view: marking it read-only leaves the caller's array alone
    arr.setflags(write=False)
    return arr


def check_groups(groups: object, shape: tuple[int, ...]) -> np.ndarray:
    """Integer group labels of the given shape (any integers; floats only if integral)."""
    raw = np.asarray(groups)
    if raw.shape != shape:
        raise ValueError(f"groups must have one label per data point {shape}, got {raw.shape}")
    if raw.size and not np.issubdtype(raw.dtype, np.integer):
        as_float = np.asarray(raw, dtype=float)
        if not (np.isfinite(as_float).all() and np.array_equal(as_float, np.round(as_float))):
            raise ValueError("groups must be integer labels")
        raw = as_float
    return raw.astype(np.int64, copy=False)


@dataclass(frozen=True)
class FusionData:
    """Fusion input data: positions, friction values, 95 % margins and optional group labels.

    Attributes
    ----------
    s_m
        Data positions ahead of the vehicle [m], shape ``(n,)``, any order, repeats allowed,
        within ``POSITION_RANGE_M``.
    mu
        Friction values [-], shape ``(n,)``, within ``MU_RANGE`` = [0, 2].
    margin
        95 % half-widths [-], shape ``(n,)`` (a scalar is broadcast), within ``MARGIN_RANGE`` =
        [0, 1]. The GP's noise std is ``max(margin / 1.96, NOISE_STD_FLOOR)``.
    groups
        Integer labels, shape ``(n,)``, or None (every point its own estimate). Points with one
        label are copies of one estimate and share its error (safe mode): ``LOCAL_GROUP`` for the
        local estimate, ``1, 2, …`` for class segments in :func:`assemble_inputs`.

    Raises
    ------
    ValueError
        If an array is not 1-D, the lengths differ, a value is not finite or outside its declared
        range, or a group label is not an integer (the message names the field and the range).

    Examples
    --------
    >>> FusionData([0.0, 10.0], [0.4, 0.5], 0.1).margin.tolist()
    [0.1, 0.1]
    """

    s_m: np.ndarray
    mu: np.ndarray
    margin: np.ndarray
    groups: np.ndarray | None = None

    def __post_init__(self) -> None:
        s, y, m, grp = validate_data(self.s_m, self.mu, self.margin, self.groups)
        _store(self, s, y, m, grp, read_only=True)

    @classmethod
    def _trusted(
        cls,
        s: np.ndarray,
        y: np.ndarray,
        m: np.ndarray,
        groups: np.ndarray | None,
        *,
        read_only: bool = True,
    ) -> FusionData:
        """Build from arrays a public entry point has already validated (no second check).

        ``read_only=False`` skips the read-only views, for data that never leave the call.
        """
        obj = object.__new__(cls)
        _store(obj, s, y, m, groups, read_only=read_only)
        return obj

    @property
    def mu_max(self) -> float:
        """Largest friction value of the data [-] (0 without data); the top of the μ̂ band."""
        return float(np.maximum.reduce(self.mu)) if self.mu.size else 0.0


def validate_data(
    s_m: object, mu: object, margin: object, groups: object
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """The checks of :class:`FusionData`, returning float arrays (a scalar margin broadcast)."""
    s = np.asarray(s_m, dtype=float)
    y = np.asarray(mu, dtype=float)
    m = np.asarray(margin, dtype=float)
    if m.ndim == 0 and s.ndim == 1:
        m = np.full(s.size, float(m))
    for name, arr in (("s_m", s), ("mu", y), ("margin", m)):
        if arr.ndim != 1:
            raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    n = s.size
    if y.size != n or m.size != n:
        raise ValueError(
            f"s_m, mu and margin must have equal lengths, got {n}, {y.size} and {m.size}"
        )
    grp = None if groups is None else check_groups(groups, (n,))
    if n:
        check_abs("s_m", s, POSITION_RANGE_M[1], " m")
        # μ in [0, 2] and margin in [0, 1] in two reductions (2·margin ≤ 2 is exact); only on
        # failure are they checked one by one, to name the field.
        if not (
            np.minimum.reduce(np.minimum(y, m)) >= 0.0
            and np.maximum.reduce(np.maximum(y, m + m)) <= 2.0
        ):
            check_range("mu", y, MU_RANGE)
            check_range("margin", m, MARGIN_RANGE)
    return s, y, m, grp


def _store(
    obj: FusionData,
    s: np.ndarray,
    y: np.ndarray,
    m: np.ndarray,
    grp: np.ndarray | None,
    *,
    read_only: bool,
) -> None:
    for name, arr in (("s_m", s), ("mu", y), ("margin", m), ("groups", grp)):
        if arr is not None and read_only:
            arr = arr.view()  # a new view: read-only without touching the caller's array
            arr.setflags(write=False)
        object.__setattr__(obj, name, arr)
