"""The GP posterior engine: two linear-algebra paths and the per-grid caches they reuse.

:class:`PosteriorEngine` computes the latent posterior (mean offset and std) of the GP at
evaluation positions, for noise that is independent per point plus optional shared columns (safe
mode's one error per group). Inputs are validated arrays; nothing is checked here.

* **Eigen-feature path** (fast): the prior on the joint data and evaluation positions z is
  K(z, z) = Φ Φᵀ (eigen-decomposition, directions below 1e-15 of the largest eigenvalue dropped:
  the squared-exponential K is numerically singular there anyway, so the result equals the dense
  one to ~1e-13). Then the posterior is Bayesian linear regression on Φ: one r × r Cholesky
  (r = 16 for the 51-point grid, ℓ = 15 m). Φ depends only on the prior and the positions, which
  repeat from one planning step to the next: it is cached per (prior, positions).
* **Dense path**: Cholesky of K + Σ (Rasmussen & Williams, Alg. 2.1), for positions that are not
  low rank or noise too small for the feature path; the kernel blocks are cached the same way.

The caches belong to the engine instance (a :class:`~mufusion.fusion.GPFusion` owns one; the
module-level :func:`~mufusion.fusion.fuse` shares one default engine) and hold at most
``max_grids`` position sets each, the oldest dropped first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg
from scipy.linalg import blas, lapack

from mufusion.fusion.data import NOISE_STD_FLOOR
from mufusion.fusion.prior import Z95, GPPrior

# Feature path: prior eigen-directions below this share of the largest eigenvalue are dropped.
_EIG_TOL = 1e-15
# ... and it is used only when every noise std is at least this share of the prior std (tiny
# noise makes I + Φᵀ Σ⁻¹ Φ ill-conditioned). NOISE_STD_FLOOR = 1e-3 ≥ this × the widest allowed
# prior std (1), so independent noise always qualifies; safe mode's per-point part may not.
_FEATURE_MIN_SD_RATIO = 1e-3


@dataclass(frozen=True)
class _Features:
    """Eigen-features of the prior on fixed data and evaluation positions (cached per grid)."""

    phi_x: np.ndarray  # (n, r) features at the data points, K(x, x) ≈ Φ_x Φ_xᵀ, Fortran order
    phi_e: np.ndarray  # (m, r) features at the evaluation points
    phi_e_t: np.ndarray  # (r, m) the same, transposed, Fortran order
    eye: np.ndarray  # (r, r) identity, Fortran order (the prior term of M)
    ones: np.ndarray  # (r,) ones (column sums)
    rest_e: np.ndarray  # (m,) prior variance in the dropped directions (≈ 1e-16)


_MISSING = object()


class PosteriorEngine:
    """GP posterior computations with caches owned by this instance.

    Parameters
    ----------
    max_grids
        How many (prior, data positions, evaluation positions) sets each cache keeps, ``>= 1``.
        A planning loop on a fixed grid uses one or two.

    Raises
    ------
    ValueError
        If ``max_grids`` is not an integer ``>= 1``.

    Examples
    --------
    >>> from mufusion.fusion import PAPER_PRIOR
    >>> eng = PosteriorEngine()
    >>> s = np.arange(0.0, 51.0)
    >>> offset, std = eng.latent(PAPER_PRIOR, s, s, np.zeros(51), np.full(51, 0.05))
    >>> offset.shape, eng.cached_grids
    ((51,), 1)
    """

    def __init__(self, max_grids: int = 16) -> None:
        if isinstance(max_grids, bool) or not isinstance(max_grids, int) or max_grids < 1:
            raise ValueError(f"max_grids must be an integer >= 1, got {max_grids!r}")
        self.max_grids = max_grids
        self._features: dict[tuple, _Features | None] = {}
        self._blocks: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}

    def __repr__(self) -> str:
        return f"<PosteriorEngine {self.cached_grids} cached grid(s), max {self.max_grids}>"

    @property
    def cached_grids(self) -> int:
        """Number of position sets whose eigen-features or kernel blocks are cached."""
        return len(self._features.keys() | self._blocks.keys())

    def clear(self) -> None:
        """Drop every cached eigen-decomposition and kernel block."""
        self._features.clear()
        self._blocks.clear()

    def _remember(self, cache: dict, key: tuple, value: object) -> None:
        if len(cache) >= self.max_grids:
            cache.pop(next(iter(cache)), None)  # oldest first: grids rarely alternate
        cache[key] = value

    # -- cached per grid --------------------------------------------------------------------

    def features(self, prior: GPPrior, s: np.ndarray, e: np.ndarray) -> _Features | None:
        """Eigen-features on (s, e), or None if the prior is not low rank there."""
        key = (prior, s.tobytes(), e.tobytes())
        feats = self._features.get(key, _MISSING)
        if feats is _MISSING:
            feats = _eigen_features(prior, s, e)
            self._remember(self._features, key, feats)
        return feats  # type: ignore[return-value]

    def kernel_blocks(
        self, prior: GPPrior, s: np.ndarray, e: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """K(x, x) and K(x, x⋆), read-only."""
        key = (prior, s.tobytes(), e.tobytes())
        blocks = self._blocks.get(key)
        if blocks is None:
            kxx, kxe = prior.kernel(s, s), prior.kernel(s, e)
            kxx.flags.writeable = False
            kxe.flags.writeable = False
            blocks = (kxx, kxe)
            self._remember(self._blocks, key, blocks)
        return blocks

    # -- posterior --------------------------------------------------------------------------

    def latent(
        self,
        prior: GPPrior,
        s: np.ndarray,
        e: np.ndarray,
        resid: np.ndarray,
        noise_sd: np.ndarray,
        shared: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean offset (prior mean removed) and latent std at ``e`` (eqs. 7–8).

        Parameters
        ----------
        prior
            The GP prior.
        s, e
            Data and evaluation positions [m], shapes ``(n,)`` (n ≥ 1) and ``(m,)``.
        resid
            ``y − prior.mean`` [-], shape ``(n,)``.
        noise_sd
            Independent noise std per point [-], shape ``(n,)``, ``>= NOISE_STD_FLOOR`` unless
            ``shared`` carries most of the variance.
        shared
            Optional shared-error columns, shape ``(n, g)``: the noise covariance is
            ``diag(noise_sd²) + shared sharedᵀ`` (one N(0, 1) latent error per column).

        Returns
        -------
        tuple of numpy.ndarray
            Mean offset and std, shape ``(m,)`` each.
        """
        k = 0 if shared is None else shared.shape[1]
        if 2 * k <= s.size:
            floor = feature_noise_floor(prior)
            # Independent noise is floored at NOISE_STD_FLOOR, which is ≥ floor for any allowed
            # prior: no reduction needed then.
            if (shared is None and NOISE_STD_FLOOR >= floor) or np.minimum.reduce(
                noise_sd
            ) >= floor:
                feats = self.features(prior, s, e)
                if feats is not None:
                    out = _posterior_features(feats, noise_sd, resid, shared)
                    if out is not None:
                        return out
        kxx, kxe = self.kernel_blocks(prior, s, e)
        cov = np.diag(noise_sd * noise_sd)
        if shared is not None:
            cov += np.einsum("ik,jk->ij", shared, shared)  # no BLAS: see _posterior_features
        return _posterior_dense(kxx, kxe, cov, resid, prior.variance)

    def latent_batch(
        self,
        prior: GPPrior,
        s: np.ndarray,
        e: np.ndarray,
        resid: np.ndarray,
        precision: np.ndarray,
        shared: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The feature path for ``B`` horizons on shared positions ``s`` in one vectorized pass.

        ``resid`` and ``precision`` (1 / independent noise variance, 0 for an absent point, which
        removes it exactly) have shape ``(B, n)``; optional ``shared`` loadings ``(B, n, G)`` add
        one N(0, 1) error per column (an all-zero column decouples exactly). Returns mean offset
        and std of shape ``(B, m)``, or None if the prior is not low rank on these positions.
        """
        feats = self.features(prior, s, e)
        if feats is None:
            return None
        phi_x, phi_e = feats.phi_x, feats.phi_e
        r = phi_x.shape[1]
        # M_b = I + Ψ_bᵀ diag(p_b) Ψ_b with Ψ_b = [Φ_x, G_b]; then as _posterior_features.
        top = np.einsum("nr,bn,ns->brs", phi_x, precision, phi_x, optimize=True)
        rhs = (precision * resid) @ phi_x
        if shared is None:
            mats = top
        else:
            g = shared.shape[2]
            weighted = precision[:, :, None] * shared
            cross = np.einsum("nr,bng->brg", phi_x, weighted, optimize=True)
            mats = np.empty((resid.shape[0], r + g, r + g))
            mats[:, :r, :r] = top
            mats[:, :r, r:] = cross
            mats[:, r:, :r] = cross.transpose(0, 2, 1)
            mats[:, r:, r:] = np.einsum("bng,bnh->bgh", shared, weighted, optimize=True)
            rhs = np.concatenate([rhs, np.einsum("bng,bn->bg", weighted, resid)], axis=1)
        k = mats.shape[1]
        mats[:, np.arange(k), np.arange(k)] += 1.0
        minv = np.linalg.inv(mats)
        coef = np.einsum("brs,bs->br", minv[:, :r, :], rhs)
        offset = coef @ phi_e.T
        var = np.einsum("jr,brs,js->bj", phi_e, minv[:, :r, :r], phi_e, optimize=True)
        var += feats.rest_e
        return offset, np.sqrt(np.maximum(var, 0.0))


def feature_noise_floor(prior: GPPrior) -> float:
    """Smallest independent noise std [-] the feature path takes (smaller: the dense path)."""
    return _FEATURE_MIN_SD_RATIO * prior.std


def _eigen_features(prior: GPPrior, s: np.ndarray, e: np.ndarray) -> _Features | None:
    z = np.concatenate([s, e])
    # SciPy's LAPACK, as everywhere here (see _posterior_features on mixing BLAS libraries).
    lam, vec = linalg.eigh(prior.kernel(z, z))
    keep = lam > _EIG_TOL * lam[-1]
    r = int(keep.sum())
    if 2 * r > s.size:
        return None  # not low rank here: the dense Cholesky path is as fast
    phi = vec[:, keep] * np.sqrt(lam[keep])
    # Fortran order: the BLAS calls take them without a copy.
    phi_x = np.asfortranarray(phi[: s.size])
    phi_e = np.asfortranarray(phi[s.size :])
    rest_e = np.maximum(prior.variance - np.einsum("ij,ij->i", phi_e, phi_e), 0.0)
    feats = _Features(
        phi_x=phi_x,
        phi_e=phi_e,
        phi_e_t=np.asfortranarray(phi_e.T),
        eye=np.eye(r, order="F"),
        ones=np.ones(r),
        rest_e=rest_e,
    )
    for arr in (feats.phi_x, feats.phi_e, feats.phi_e_t, feats.rest_e, feats.eye, feats.ones):
        arr.flags.writeable = False
    return feats


def _posterior_features(
    feats: _Features,
    noise_sd: np.ndarray,
    resid: np.ndarray,
    shared: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Posterior by Bayesian linear regression on the prior's eigen-features (exact to ~1e-13).

    f = Φ w with w ~ N(0, I) and K = Φ Φᵀ; y − m0 = Φ_x w + G u + ε, with u ~ N(0, I) the shared
    errors (columns ``shared``) and ε ~ N(0, diag(noise_sd²)). With Ψ = [Φ_x, G]:
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
    # L⁻¹ explicitly (k × k, k ≈ 16): OpenBLAS runs a triangular solve with many right-hand
    # sides (dtrsm) on two threads even at this size, which costs ~150 µs instead of ~5 µs when
    # the other core is busy; dtrtri + dgemm stay single-threaded. Error ~ cond(L) · eps.
    linv, info = lapack.dtrtri(chol, lower=1, overwrite_c=1)
    if info != 0:
        return None
    # z = L⁻¹ Ψᵀ Σ⁻¹ (y − m0) and X_e = L⁻¹ (Φ_e, 0)ᵀ; then mean = X_eᵀ z
    # (= Φ_e M⁻¹ Ψᵀ Σ⁻¹ (y − m0)) and var = column sums of X_e².
    z = blas.dgemv(1.0, linv, blas.dgemv(1.0, scaled, resid * inv_sd, trans=1))
    x_e = blas.dgemm(1.0, linv[:, :r], phi_e_t)
    offset = blas.dgemv(1.0, x_e, z, trans=1)
    x_e *= x_e
    var = blas.dgemv(1.0, x_e, feats.ones if k == r else np.ones(k), trans=1)
    var += rest_e
    return offset, np.sqrt(var, out=var)


def _posterior_dense(
    kxx: np.ndarray,
    kxe: np.ndarray,
    noise_cov: np.ndarray,
    resid: np.ndarray,
    prior_variance: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Posterior mean offset and latent std by the Cholesky of K + Σ (eqs. 7–8)."""
    # Alg. 2.1 (Rasmussen & Williams), line 2: L = cholesky(K + Σ). With the noise floor the
    # smallest eigenvalue of K + Σ is ≥ 1e-9 (safe mode's per-point share of 1e-6), so LAPACK
    # does not fail for any input the boundary accepts.
    chol, info = lapack.dpotrf(kxx + noise_cov, lower=1, clean=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"K + Σ is not positive definite (dpotrf info={info})")
    # V = L⁻¹ K(x, x⋆), z = L⁻¹ (y − m0); mean offset = Vᵀ z, var = k(x⋆, x⋆) − colsum(V²).
    # L⁻¹ explicitly, as in _posterior_features (a threaded dtrsm is slow on a busy machine).
    linv, info = lapack.dtrtri(chol, lower=1, overwrite_c=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"triangular inverse failed (info={info})")
    v = blas.dgemm(1.0, linv, kxe)
    offset = blas.dgemv(1.0, v, blas.dgemv(1.0, linv, resid), trans=1)
    var = prior_variance - np.einsum("ij,ij->j", v, v)
    np.maximum(var, 0.0, out=var)
    return offset, np.sqrt(var)


def noise_sd_of(margin: np.ndarray) -> np.ndarray:
    """GP noise std of each datum [-]: ``max(margin / 1.96, NOISE_STD_FLOOR)``."""
    return np.maximum(margin / Z95, NOISE_STD_FLOOR)
