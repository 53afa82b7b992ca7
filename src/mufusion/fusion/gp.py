"""Heteroscedastic GP fusion of friction estimates (paper Sec. III and Appendix A).

The prior is a GP over the progress s with a constant mean and a squared-exponential kernel; the
data are friction values with 95 % margins; the fused estimate is the lower edge of the posterior's
95 % band. Two modes:

* ``"paper"``: the paper's method, exact: Appendix A with the prior mean restored and the noise as
  a variance, every data point with its own independent error.
* ``"safe"`` (beyond the paper): points that are copies of one estimate share one error (a
  correlated noise block per group), and μ̂ is capped by the hard bound ``y − margin`` each
  estimate implies, so that μ̂ never exceeds the true μ at a data point when every error is within
  its margin. See ``docs/fusion.md`` for the proof sketch.

Speed: the prior's eigen-features on the data and evaluation positions depend only on the prior
and the positions, which repeat from one planning step to the next; they are cached
(``_features_cached``), so a step solves a 16 × 16 system (51-point grid, ℓ = 15 m) through
SciPy's LAPACK. Tiny margins or positions that are not low rank use the dense Cholesky of
``K + Σ`` (``_posterior``, kernel blocks cached too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Literal

import numpy as np
from scipy import linalg
from scipy.linalg import blas, lapack

if TYPE_CHECKING:
    from mufusion.fusion.assembly import FusionData

Z95 = 1.96
"""Two-sided 95 % quantile of the standard normal: margin = Z95 · std (paper Sec. III)."""

FusionMode = Literal["paper", "safe"]
MODES: tuple[str, ...] = ("paper", "safe")

SHARED_ERROR_FRACTION = 0.999
"""Safe mode: share of a point's noise variance that is common to its group [-].

The rest (0.1 %) is independent per point. It keeps ``K + Σ`` well conditioned when a group has
many close points (the squared-exponential ``K`` alone is numerically singular there), and it makes
a one-point group identical to the paper's independent noise.
"""

_JITTER_START = 1e-12  # relative to the prior variance; only used when Cholesky fails
_JITTER_MAX = 1e-4
_SAME_S_TOL_M = 1e-9  # two positions closer than this are the same point [m]
# Feature (low-rank) path: prior eigen-directions below this share of the largest eigenvalue are
# dropped; the squared-exponential K is numerically singular there anyway (its eigenvalues decay
# like a Gaussian), so the result equals the dense Cholesky one to ~1e-13.
_EIG_TOL = 1e-15
# ... and it is used only when every noise variance is at least this share of the prior variance
# (zero or tiny margins make I + Φᵀ Σ⁻¹ Φ ill-conditioned: the dense path with jitter handles them).
_FEATURE_MIN_NOISE = 1e-6


@dataclass(frozen=True)
class GPPrior:
    """GP prior f(s) ~ GP(mean, k) with k(s, s') = std² exp(−(s − s')² / (2 ℓ²)) (eq. 5).

    Attributes
    ----------
    mean
        Constant prior mean η of μ [-].
    std
        Prior standard deviation σ_f of μ [-], > 0.
    length_scale_m
        Squared-exponential length scale ℓ [m], > 0.

    Raises
    ------
    ValueError
        If a field is not finite, or std or length_scale_m is not > 0.

    Examples
    --------
    >>> p = GPPrior.from_interval(0.1, 1.0, 15.0)
    >>> round(p.mean, 3), round(p.std, 4)
    (0.55, 0.2296)
    """

    mean: float
    std: float
    length_scale_m: float

    def __post_init__(self) -> None:
        for name in ("mean", "std", "length_scale_m"):
            value = getattr(self, name)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"GPPrior.{name} must be a finite number, got {value!r}") from None
            if not math.isfinite(value):
                raise ValueError(f"GPPrior.{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)
        if self.std <= 0.0:
            raise ValueError(f"GPPrior.std must be > 0, got {self.std!r}")
        if self.length_scale_m <= 0.0:
            raise ValueError(f"GPPrior.length_scale_m must be > 0 m, got {self.length_scale_m!r}")

    @classmethod
    def from_interval(cls, low: float, high: float, length_scale_m: float) -> GPPrior:
        """Prior whose 95 % band is ``[low, high]`` (paper Sec. III: [0.1, 1.0]).

        Parameters
        ----------
        low, high
            Band edges of μ [-], ``low < high``.
        length_scale_m
            Kernel length scale ℓ [m], > 0.

        Returns
        -------
        GPPrior
            ``mean = (low + high) / 2``, ``std = (high − low) / (2 · 1.96)``.

        Raises
        ------
        ValueError
            If ``low`` or ``high`` is not finite or ``low >= high``, or ``length_scale_m`` is bad.
        """
        low, high = float(low), float(high)
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(
                f"GPPrior.from_interval needs finite low < high, got low={low!r}, high={high!r}"
            )
        return cls(0.5 * (low + high), 0.5 * (high - low) / Z95, length_scale_m)

    @property
    def variance(self) -> float:
        """Prior variance σ_f² [-]."""
        return self.std * self.std

    def kernel(self, a_m: np.ndarray, b_m: np.ndarray) -> np.ndarray:
        """Squared-exponential covariance matrix k(a_i, b_j) (eq. 5), shape ``(len(a), len(b))``."""
        a = np.asarray(a_m, dtype=float).reshape(-1, 1)
        b = np.asarray(b_m, dtype=float).reshape(1, -1)
        d = (a - b) / self.length_scale_m
        return self.variance * np.exp(-0.5 * d * d)


PAPER_LENGTH_SCALE_M = 15.0
"""Kernel length scale ℓ [m]: the authors' value in their code (the paper does not state it)."""

PAPER_PRIOR = GPPrior.from_interval(0.1, 1.0, PAPER_LENGTH_SCALE_M)
"""The paper's prior: [0.1, 1.0] is its 95 % band (Sec. III); ℓ = 15 m."""


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
        The estimate given to the planner [-]: ``lower`` in paper mode; capped by the hard
        bounds in safe mode.
    """

    s_m: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    lower: np.ndarray
    mu_hat: np.ndarray


# ---------------------------------------------------------------------------------------------
# Validation
# ---------------------------------------------------------------------------------------------


def _as_1d(name: str, value: object, *, allow_empty: bool = True) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if not allow_empty and arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    # Fast screen: any NaN or inf makes the sum non-finite; only then look closer.
    if not math.isfinite(float(np.add.reduce(arr))) and not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


def _check_prior(prior: object) -> GPPrior:
    if not isinstance(prior, GPPrior):
        raise ValueError(f"prior must be a GPPrior, got {type(prior).__name__}")
    return prior


def _check_mode(mode: object) -> str:
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    return str(mode)


def _check_groups(groups: object, n: int) -> np.ndarray | None:
    if groups is None:
        return None
    raw = np.asarray(groups)
    if raw.ndim != 1 or raw.shape[0] != n:
        raise ValueError(f"groups must have one label per data point ({n}), got shape {raw.shape}")
    if n and not np.issubdtype(raw.dtype, np.integer):
        as_float = np.asarray(raw, dtype=float)
        if not (np.isfinite(as_float).all() and np.array_equal(as_float, np.round(as_float))):
            raise ValueError("groups must be integer labels")
        raw = as_float.astype(np.int64)
    return raw.astype(np.int64, copy=False)


def _check_data(
    s_m: object, mu: object, margin: object
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = np.asarray(s_m, dtype=float)
    y = np.asarray(mu, dtype=float)
    m = np.asarray(margin, dtype=float)
    if m.ndim == 0 and s.ndim == 1:
        m = np.full(s.size, float(m))
    for name, arr in (("s_m", s), ("mu", y), ("margin", m)):
        if arr.ndim != 1:
            raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if y.size != s.size or m.size != s.size:
        raise ValueError(
            f"s_m, mu and margin must have equal lengths, got {s.size}, {y.size} and {m.size}"
        )
    # Fast screen: any NaN or inf makes the sum non-finite; only then look closer.
    if not math.isfinite(float(np.add.reduce(s) + np.add.reduce(y) + np.add.reduce(m))):
        for name, arr in (("s_m", s), ("mu", y), ("margin", m)):
            if not np.isfinite(arr).all():
                raise ValueError(f"{name} must be finite (no NaN or inf)")
    if s.size and np.minimum.reduce(m) < 0.0:
        raise ValueError("margin must be >= 0 (a 95 % half-width of μ)")
    return s, y, m


# ---------------------------------------------------------------------------------------------
# Cached kernel blocks and the Cholesky core
# ---------------------------------------------------------------------------------------------


@lru_cache(maxsize=64)
def _kernel_blocks_cached(
    prior: GPPrior, s_bytes: bytes, e_bytes: bytes
) -> tuple[np.ndarray, np.ndarray]:
    s = np.frombuffer(s_bytes, dtype=float)
    e = np.frombuffer(e_bytes, dtype=float)
    kxx = prior.kernel(s, s)
    kxe = prior.kernel(s, e)
    kxx.setflags(write=False)
    kxe.setflags(write=False)
    return kxx, kxe


def _kernel_blocks(prior: GPPrior, s: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """K(x, x) and K(x, x⋆); cached on the positions because they repeat across planning steps."""
    return _kernel_blocks_cached(prior, s.tobytes(), e.tobytes())


@dataclass(frozen=True)
class _Features:
    """Eigen-features of the prior on fixed data and evaluation positions (cached per grid)."""

    phi_x: np.ndarray  # (n, r) features at the data points, K(x, x) ≈ Φ_x Φ_xᵀ
    phi_e: np.ndarray  # (m, r) features at the evaluation points
    phi_e_t: np.ndarray  # (r, m) the same, transposed, Fortran order
    eye: np.ndarray  # (r, r) identity, Fortran order (the prior term of M)
    rest_e: np.ndarray  # (m,) prior variance in the dropped directions (≈ 1e-16)


@lru_cache(maxsize=64)
def _features_cached(prior: GPPrior, s_bytes: bytes, e_bytes: bytes) -> _Features | None:
    s = np.frombuffer(s_bytes, dtype=float)
    e = np.frombuffer(e_bytes, dtype=float)
    z = np.concatenate([s, e])
    # SciPy's LAPACK, as everywhere here (see _posterior_features on mixing BLAS libraries).
    lam, vec = linalg.eigh(prior.kernel(z, z))
    keep = lam > _EIG_TOL * lam[-1]
    r = int(keep.sum())
    if 2 * r > s.size:
        return None  # not low rank here: the dense Cholesky path is as fast
    phi = vec[:, keep] * np.sqrt(lam[keep])
    # Fortran order: the BLAS calls below take them without a copy.
    phi_x = np.asfortranarray(phi[: s.size])
    phi_e = np.asfortranarray(phi[s.size :])
    rest_e = np.maximum(prior.variance - np.einsum("ij,ij->i", phi_e, phi_e), 0.0)
    phi_e_t = np.asfortranarray(phi_e.T)
    eye = np.eye(r, order="F")
    feats = _Features(phi_x=phi_x, phi_e=phi_e, phi_e_t=phi_e_t, eye=eye, rest_e=rest_e)
    for arr in (phi_x, phi_e, phi_e_t, rest_e, eye):
        arr.setflags(write=False)
    return feats


def _posterior_features(
    feats: _Features,
    noise_sd: np.ndarray,
    resid: np.ndarray,
    shared: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Posterior by Bayesian linear regression on the prior's eigen-features (exact to ~1e-13).

    f = Φ w with w ~ N(0, I) and K = Φ Φᵀ (eigen-decomposition of the prior on data and evaluation
    points); y − m0 = Φ_x w + G u + ε, with u ~ N(0, I) one shared error per group (columns
    ``shared``, safe mode) and ε ~ N(0, diag(noise_sd²)). Then with Ψ = [Φ_x, G]:
    M = I + Ψᵀ Σ⁻¹ Ψ = L Lᵀ, mean = Φ_e M⁻¹ Ψᵀ Σ⁻¹ (y − m0), var = diag((Φ_e, 0) M⁻¹ (Φ_e, 0)ᵀ).

    All products go through SciPy's BLAS (the library of the LAPACK calls) and stay below
    OpenBLAS's multithreading thresholds: alternating NumPy's and SciPy's OpenBLAS, or a threaded
    product, let idle worker threads compete for the cores, which made this ~15 µs step take
    milliseconds on a busy two-core machine.
    """
    phi_x, phi_e_t, rest_e = feats.phi_x, feats.phi_e_t, feats.rest_e
    r = phi_x.shape[1]
    psi = phi_x if shared is None else np.asfortranarray(np.concatenate([phi_x, shared], axis=1))
    k = psi.shape[1]
    inv_sd = 1.0 / noise_sd
    scaled = psi * inv_sd[:, None]  # Σ^(-1/2) Ψ
    # M = I + Ψᵀ Σ⁻¹ Ψ (lower triangle; dsyrk adds onto a copy of I) = L Lᵀ.
    eye = feats.eye if k == r else np.eye(k, order="F")
    m = blas.dsyrk(1.0, scaled, beta=1.0, c=eye, trans=1, lower=1)
    chol, info = lapack.dpotrf(m, lower=1, clean=1, overwrite_a=1)
    if info != 0:
        return None
    # z = L⁻¹ Ψᵀ Σ⁻¹ (y − m0) and X_e = L⁻¹ (Φ_e, 0)ᵀ; then mean = X_eᵀ z
    # (= Φ_e M⁻¹ Ψᵀ Σ⁻¹ (y − m0)) and var = column sums of X_e².
    z, info = lapack.dtrtrs(
        chol, blas.dgemv(1.0, scaled, resid * inv_sd, trans=1), lower=1, overwrite_b=1
    )
    if info != 0:
        return None
    if k == r:
        rhs = phi_e_t
    else:
        rhs = np.zeros((k, phi_e_t.shape[1]), order="F")
        rhs[:r] = phi_e_t
    x_e, info = lapack.dtrtrs(chol, rhs, lower=1)
    if info != 0:
        return None
    offset = blas.dgemv(1.0, x_e, z, trans=1)
    x_e *= x_e
    var = blas.dgemv(1.0, x_e, np.ones(k), trans=1)
    var += rest_e
    return offset, np.sqrt(var)


def _latent_posterior(
    prior: GPPrior,
    s: np.ndarray,
    e: np.ndarray,
    margin: np.ndarray,
    resid: np.ndarray,
    groups: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Posterior mean offset and latent std at ``e``; independent noise, or shared per group."""
    sd = margin / Z95
    noise_sd = sd
    shared = None
    if groups is not None:
        labels, index = np.unique(groups, return_inverse=True)
        if 2 * labels.size <= s.size:
            # One N(0, 1) latent per group scaled by sqrt(ρ) σ_i carries the shared error.
            shared = np.zeros((s.size, labels.size))
            shared[np.arange(s.size), index] = math.sqrt(SHARED_ERROR_FRACTION) * sd
            noise_sd = math.sqrt(1.0 - SHARED_ERROR_FRACTION) * sd
    if groups is None or shared is not None:
        if np.minimum.reduce(noise_sd) >= math.sqrt(_FEATURE_MIN_NOISE) * prior.std:
            feats = _features_cached(prior, s.tobytes(), e.tobytes())
            if feats is not None:
                out = _posterior_features(feats, noise_sd, resid, shared)
                if out is not None:
                    return out
    kxx, kxe = _kernel_blocks(prior, s, e)
    cov = _noise_independent(margin) if groups is None else _noise_grouped(margin, groups)
    return _posterior(kxx, kxe, cov, resid, prior)


def _posterior(
    kxx: np.ndarray,
    kxe: np.ndarray,
    noise_cov: np.ndarray,
    resid: np.ndarray,
    prior: GPPrior,
) -> tuple[np.ndarray, np.ndarray]:
    """Posterior mean offset and latent std at the evaluation points (eqs. 7–8, prior mean added
    back by the caller)."""
    a = kxx + noise_cov
    chol = _robust_cholesky(a, prior.variance)
    # Alg. 2.1 (Rasmussen & Williams): V = L⁻¹ K(x, x⋆), z = L⁻¹ (y − m0);
    # mean offset = Vᵀ z, var = k(x⋆, x⋆) − colsum(V²).
    rhs = np.empty((kxe.shape[0], kxe.shape[1] + 1), order="F")
    rhs[:, :-1] = kxe
    rhs[:, -1] = resid
    w, info = lapack.dtrtrs(chol, rhs, lower=1, overwrite_b=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"triangular solve failed (info={info})")
    v = w[:, :-1]
    offset = blas.dgemv(1.0, v, w[:, -1], trans=1)
    var = prior.variance - np.einsum("ij,ij->j", v, v)
    np.maximum(var, 0.0, out=var)
    return offset, np.sqrt(var)


def _robust_cholesky(a: np.ndarray, scale: float) -> np.ndarray:
    """Lower Cholesky factor of the SPD matrix ``a``; adds diagonal jitter only if LAPACK fails.

    Raises
    ------
    numpy.linalg.LinAlgError
        If even a jitter of 1e-4 · prior variance does not make ``a`` positive definite.
    """
    chol, info = lapack.dpotrf(a, lower=1, clean=0)
    if info == 0:
        return chol
    n = a.shape[0]
    jitter = _JITTER_START * scale
    while jitter <= _JITTER_MAX * scale:
        chol, info = lapack.dpotrf(a + jitter * np.eye(n), lower=1, clean=0)
        if info == 0:
            return chol
        jitter *= 10.0
    raise np.linalg.LinAlgError(
        "K + Σ is not positive definite even with jitter; zero-margin data that contradict each "
        "other at (nearly) the same position cannot be fused"
    )


def _noise_independent(margin: np.ndarray) -> np.ndarray:
    sd = margin / Z95
    return np.diag(sd * sd)


def _noise_grouped(margin: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Σ with one shared error per group: Σ_ij = ρ σ_i σ_j for i ≠ j in a group, σ_i² on the
    diagonal (ρ = SHARED_ERROR_FRACTION)."""
    sd = margin / Z95
    same = groups[:, None] == groups[None, :]
    cov = SHARED_ERROR_FRACTION * np.outer(sd, sd) * same
    np.fill_diagonal(cov, sd * sd)
    return cov


def _hard_bound_envelope(
    s: np.ndarray, y: np.ndarray, margin: np.ndarray, s_eval: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Guaranteed lower bound on μ at the evaluation points, and a mask of points outside the data.

    At a data position the bound is ``max(y − margin)`` over all estimates there (each one alone
    is a valid bound when its error is within its margin). Strictly between two data positions
    it is the smaller of the two neighbours' bounds; outside the data it holds the nearest end's
    bound (the caller also caps it there by the GP).
    """
    lo = y - margin
    order = np.lexsort((-lo, s))  # by s, then the largest bound first
    s_sorted = s[order]
    lo_sorted = lo[order]
    first = np.ones(s_sorted.size, dtype=bool)
    first[1:] = np.diff(s_sorted) > _SAME_S_TOL_M
    us = s_sorted[first]
    ub = lo_sorted[first]
    idx = np.searchsorted(us, s_eval)
    left = np.maximum(idx - 1, 0)
    right = np.minimum(idx, us.size - 1)
    at_left = np.abs(s_eval - us[left]) <= _SAME_S_TOL_M
    at_right = np.abs(s_eval - us[right]) <= _SAME_S_TOL_M
    bound = np.minimum(ub[left], ub[right])
    bound = np.where(at_right, ub[right], bound)
    bound = np.where(at_left, ub[left], bound)
    outside = ((s_eval < us[0]) | (s_eval > us[-1])) & ~(at_left | at_right)
    return bound, outside


# ---------------------------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------------------------


def fuse(
    s_m: np.ndarray,
    mu: np.ndarray,
    margin: np.ndarray,
    prior: GPPrior,
    s_eval_m: np.ndarray,
    *,
    groups: np.ndarray | None = None,
    mode: FusionMode = "paper",
) -> FusedEstimate:
    """Fuse friction estimates with heteroscedastic GP regression (paper Sec. III, App. A).

    Parameters
    ----------
    s_m
        Data positions ahead of the vehicle [m], shape ``(n,)``, any order, repeats allowed.
    mu
        Estimated friction at ``s_m`` [-], shape ``(n,)``.
    margin
        95 % half-width of each estimate [-], ``>= 0``, shape ``(n,)`` or scalar. The noise std is
        ``margin / 1.96`` and enters ``K + Σ`` as a variance.
    prior
        The GP prior (mean, std, length scale).
    s_eval_m
        Evaluation positions [m], shape ``(m,)``, non-empty.
    groups
        Optional integer label per data point: points with one label are copies of one estimate
        and share its error (safe mode only; ignored by paper mode except for validation).
    mode
        ``"paper"`` (the paper's method) or ``"safe"`` (shared errors and hard bounds; see module
        docstring).

    Returns
    -------
    FusedEstimate
        Paper mode: the exact posterior ``mean = m0 + K⋆ᵀ (K + Σ)⁻¹ (y − m0)``, the latent std,
        ``lower = mean − 1.96 std`` and ``mu_hat = lower``. Safe mode: mean/std/lower of the
        posterior with grouped noise, and ``mu_hat`` = the paper-mode lower bound capped by the
        hard bounds (see ``docs/fusion.md``). With no data the prior is returned.

    Raises
    ------
    ValueError
        If an array is not finite or 1-D, lengths differ, a margin is negative, ``s_eval_m`` is
        empty, ``prior`` is not a :class:`GPPrior`, ``groups`` has the wrong length or non-integer
        labels, or ``mode`` is unknown.
    numpy.linalg.LinAlgError
        If zero-margin data contradict each other at the same position.

    Examples
    --------
    >>> est = fuse([0.0, 10.0], [0.4, 0.5], [0.025, 0.1], PAPER_PRIOR, [0.0, 10.0])
    >>> bool(est.mu_hat[0] < 0.4)
    True
    """
    prior = _check_prior(prior)
    mode = _check_mode(mode)
    s, y, m = _check_data(s_m, mu, margin)
    e = _as_1d("s_eval_m", s_eval_m, allow_empty=False)
    grp = _check_groups(groups, s.size)
    return _fuse_checked(s, y, m, prior, e, grp, mode)


def _fuse_checked(
    s: np.ndarray,
    y: np.ndarray,
    m: np.ndarray,
    prior: GPPrior,
    e: np.ndarray,
    grp: np.ndarray | None,
    mode: str,
) -> FusedEstimate:
    if s.size == 0:
        mean = np.full(e.size, prior.mean)
        std = np.full(e.size, prior.std)
        lower = mean - Z95 * std
        return FusedEstimate(e, mean, std, lower, lower.copy())
    resid = y - prior.mean
    offset, std = _latent_posterior(prior, s, e, m, resid)
    mean = prior.mean + offset
    lower = mean - Z95 * std
    if mode == "paper":
        return FusedEstimate(e, mean, std, lower, lower.copy())
    # Safe mode: honest posterior with one shared error per group ...
    labels = np.arange(s.size) if grp is None else grp
    g_offset, g_std = _latent_posterior(prior, s, e, m, resid, labels)
    g_mean = prior.mean + g_offset
    g_lower = g_mean - Z95 * g_std
    # ... and μ̂ = paper lower bound capped by what the estimates guarantee (docs/fusion.md).
    bound, outside = _hard_bound_envelope(s, y, m, e)
    mu_hat = np.minimum(lower, bound)
    mu_hat = np.where(outside, np.minimum(mu_hat, g_lower), mu_hat)
    return FusedEstimate(e, g_mean, g_std, g_lower, mu_hat)


def fuse_batch(
    s_m: np.ndarray,
    mu: np.ndarray,
    margin: np.ndarray,
    prior: GPPrior,
    s_eval_m: np.ndarray,
    *,
    groups: np.ndarray | None = None,
    mode: FusionMode = "paper",
) -> FusedEstimate:
    """:func:`fuse` for ``B`` horizons at once (fleet or campaign use).

    Parameters
    ----------
    s_m
        Data positions [m], shape ``(n,)`` shared by all horizons or ``(B, n)``.
    mu
        Friction values [-], shape ``(B, n)``. NaN marks an absent point, so horizons with
        different numbers of data points share one array (the point is decoupled exactly: its row
        and column of ``K + Σ`` become the identity and its residual 0).
    margin
        95 % half-widths [-], ``>= 0``, shape ``(n,)`` or ``(B, n)``; ignored where ``mu`` is NaN.
    prior, s_eval_m, mode
        As in :func:`fuse`; ``s_eval_m`` is shared, shape ``(m,)``.
    groups
        Optional integer labels, shape ``(n,)`` or ``(B, n)``.

    Returns
    -------
    FusedEstimate
        ``s_m`` of shape ``(m,)``; ``mean``, ``std``, ``lower``, ``mu_hat`` of shape ``(B, m)``.
        Row ``b`` equals ``fuse`` on row ``b``'s present points: bit for bit in safe mode, with
        per-horizon positions or with margins too small for the feature path (these run horizon by
        horizon); to rounding (≈ 1e-13) in paper mode on shared positions, which runs all
        horizons in one vectorized pass.

    Raises
    ------
    ValueError
        As :func:`fuse`, plus shapes that do not broadcast to ``(B, n)``.

    Examples
    --------
    >>> est = fuse_batch([0.0, 10.0], [[0.4, 0.5], [0.8, np.nan]], [0.025, 0.1],
    ...                  PAPER_PRIOR, [0.0, 10.0])
    >>> est.mu_hat.shape
    (2, 2)
    """
    prior = _check_prior(prior)
    mode = _check_mode(mode)
    y = np.asarray(mu, dtype=float)
    if y.ndim != 2:
        raise ValueError(f"mu must have shape (B, n), got {y.shape}")
    b, n = y.shape
    if b == 0:
        raise ValueError("mu must hold at least one horizon (B >= 1)")
    if np.isinf(y).any():
        raise ValueError("mu must be finite or NaN (absent point), got inf")
    present = ~np.isnan(y)

    def _broadcast(name: str, value: object) -> np.ndarray:
        arr = np.asarray(value, dtype=float)
        if arr.shape not in ((n,), (b, n)):
            raise ValueError(f"{name} must have shape ({n},) or ({b}, {n}), got {arr.shape}")
        return np.broadcast_to(arr, (b, n))

    s = _broadcast("s_m", s_m)
    if not np.isfinite(s).all():
        raise ValueError("s_m must be finite (no NaN or inf)")
    m = _broadcast("margin", margin)
    if not np.isfinite(m[present]).all() or (m[present] < 0.0).any():
        raise ValueError("margin must be finite and >= 0 where mu is given")
    e = _as_1d("s_eval_m", s_eval_m, allow_empty=False)
    if groups is None:
        grp = np.broadcast_to(np.arange(n), (b, n))
    else:
        graw = np.asarray(groups)
        if graw.shape not in ((n,), (b, n)):
            raise ValueError(f"groups must have shape ({n},) or ({b}, {n}), got {graw.shape}")
        if graw.size and not np.issubdtype(graw.dtype, np.integer):
            gf = np.asarray(graw, dtype=float)
            if not (np.isfinite(gf).all() and np.array_equal(gf, np.round(gf))):
                raise ValueError("groups must be integer labels")
        grp = np.broadcast_to(np.asarray(graw).astype(np.int64), (b, n))

    if mode == "paper" and np.asarray(s_m).ndim == 1 and n > 0:
        out = _fuse_batch_features(s[0], y, m, present, prior, e)
        if out is not None:
            return out
    # Safe mode, per-horizon positions, tiny margins: horizon by horizon (exactly ``fuse``).
    rows = [
        _fuse_checked(
            s[i][present[i]], y[i][present[i]], m[i][present[i]], prior, e,
            None if groups is None else grp[i][present[i]], mode,
        )
        for i in range(b)
    ]
    return FusedEstimate(
        e,
        np.stack([r.mean for r in rows]),
        np.stack([r.std for r in rows]),
        np.stack([r.lower for r in rows]),
        np.stack([r.mu_hat for r in rows]),
    )


def _fuse_batch_features(
    s: np.ndarray,
    y: np.ndarray,
    m: np.ndarray,
    present: np.ndarray,
    prior: GPPrior,
    e: np.ndarray,
) -> FusedEstimate | None:
    """Paper mode on shared positions: the feature posterior for all horizons in one pass.

    An absent point gets zero precision, which removes it exactly. Returns None when the
    positions are not low rank or a margin is too small for the feature path.
    """
    sd = np.where(present, m, 1.0) / Z95
    noise_var = sd * sd
    if noise_var.min() < _FEATURE_MIN_NOISE * prior.variance:
        return None
    feats = _features_cached(prior, s.tobytes(), e.tobytes())
    if feats is None:
        return None
    prec = np.where(present, 1.0 / noise_var, 0.0)
    resid = np.where(present, y - prior.mean, 0.0)
    phi_x, phi_e = feats.phi_x, feats.phi_e
    r = phi_x.shape[1]
    # M_b = I + Φ_xᵀ diag(p_b) Φ_x for every horizon b; then as _posterior_features.
    mats = np.einsum("nr,bn,ns->brs", phi_x, prec, phi_x, optimize=True)
    mats[:, np.arange(r), np.arange(r)] += 1.0
    rhs = (prec * resid) @ phi_x
    minv = np.linalg.inv(mats)
    coef = np.einsum("brs,bs->br", minv, rhs)
    mean = prior.mean + coef @ phi_e.T
    var = np.einsum("jr,brs,js->bj", phi_e, minv, phi_e, optimize=True) + feats.rest_e
    std = np.sqrt(np.maximum(var, 0.0))
    lower = mean - Z95 * std
    return FusedEstimate(e, mean, std, lower, lower.copy())


class GPFusion:
    """Fusion on a fixed prior and evaluation grid: the state kept between planning steps.

    The eigen-features for a set of data positions are cached (they repeat every step on a fixed
    grid), so a step costs one small Cholesky factorization and one triangular solve.

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
        self.prior = _check_prior(prior)
        grid = np.arange(0.0, 51.0) if s_eval_m is None else s_eval_m
        self.s_eval_m = _as_1d("s_eval_m", grid, allow_empty=False)
        self.s_eval_m.setflags(write=False)
        self.mode = _check_mode(mode)

    def fuse(
        self,
        s_m: np.ndarray,
        mu: np.ndarray,
        margin: np.ndarray,
        groups: np.ndarray | None = None,
    ) -> FusedEstimate:
        """:func:`fuse` with this object's prior, grid and mode (same parameters and errors)."""
        s, y, m = _check_data(s_m, mu, margin)
        grp = _check_groups(groups, s.size)
        return _fuse_checked(s, y, m, self.prior, self.s_eval_m, grp, self.mode)

    def step(self, data: FusionData) -> FusedEstimate:
        """Fuse one :class:`~mufusion.fusion.assembly.FusionData` (one planning step)."""
        return self.fuse(data.s_m, data.mu, data.margin, data.groups)
