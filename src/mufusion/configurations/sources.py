"""The friction-estimation configurations of the paper (Sec. IV-B): GT, L, P, F, and F-safe.

All five share one step interface, so the closed loop does not care which one it drives::

    estimate = configuration.step(s_ahead_m, mu_true_ahead, utilization)
    planner.step(..., mu_hat_of_s=lambda s: np.interp(s, s_ego + estimate.s_m, estimate.mu_hat))

``GT``
    Ground truth: ``μ̂(s) = μ_gt(s)``.
``L``
    Local only: the held local estimate minus its worst-case error over the whole horizon,
    ``μ̂(s) = μ̂_l − max{|e_l|}``.
``P``
    Predictive only: the lowest μ of the camera's (always correct) class at each ``s``; beyond
    the camera range the last in-range value is held. The camera's error model does not affect P:
    only the class is used.
``F``
    Fused (paper): camera class values and margins, replaced near the vehicle by the local
    estimate when it is available, fused by GP regression; ``μ̂`` is the posterior's lower
    95 % bound (paper Sec. III).
``F-safe``
    As F with the fusion's ``mode="safe"`` (see :mod:`mufusion.fusion`).

Every configuration updates the local estimator at every step, so the local value and its
availability are logged for all of them. Each ``μ̂`` is finally clipped into
``[MU_HAT_MIN, MU_HAT_MAX]``: the planner's friction polygons need a positive radius (the GP's
lower bound far from any data, or L after a tiny measurement, could fall to or below 0), and no
tire exceeds μ = 2.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.configurations.registry import Configuration
from mufusion.estimators import (
    CAMERA_RANGE_M,
    LOCAL_MAX_ERROR,
    PAPER_CLASSES,
    PAPER_LOCAL_TIMING,
    UTILIZATION_THRESHOLD,
    LocalEstimate,
    LocalEstimator,
    LocalTiming,
    SurfaceClass,
    check_error_model,
    predictive_estimate,
    validate_classes,
)
from mufusion.estimators.predictive import check_grid
from mufusion.fusion import PAPER_PRIOR, FusedEstimate, FusionData, GPFusion, assemble_inputs

# Clip range of every μ̂ handed to the planner [-] (see the module docstring): 0.05 is half the
# lowest class value the paper admits (snow/ice starts at 0.1).
MU_HAT_MIN = 0.05
MU_HAT_MAX = 2.0


@dataclass(frozen=True)
class FrictionEstimate:
    """One planning step's friction estimate over the grid ahead of the vehicle.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (n,)
        Distances ahead of the vehicle [m] (the ``s_ahead_m`` passed to ``step``).
    mu_hat : numpy.ndarray, shape (n,)
        Friction coefficient the planner uses at each distance [-]; finite, in
        ``[MU_HAT_MIN, MU_HAT_MAX]``.
    local_available : bool
        Whether the local estimator measured at this step.
    local_mu : float or None
        Held local estimate including its error [-] (None only if it never had a value).
    fused : FusedEstimate or None
        The GP posterior on ``s_m`` (F and F-safe only).
    data : FusionData or None
        The fusion's input data (F and F-safe only).
    """

    s_m: np.ndarray
    mu_hat: np.ndarray
    local_available: bool
    local_mu: float | None
    fused: FusedEstimate | None = None
    data: FusionData | None = None


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


class FrictionConfiguration:
    """Base of the configurations: the local estimator, input checks, ``step`` and ``reset``.

    Use :func:`make_configuration` to build one. Subclasses implement :meth:`_mu_hat`.
    """

    configuration: Configuration

    @property
    def name(self) -> str:
        """The configuration's short name (``"GT"``, ..., ``"F-safe"``)."""
        return self.configuration.value

    def __init__(
        self,
        *,
        local: LocalEstimator,
        classes: tuple[SurfaceClass, ...],
        predictive_error: str,
        rng: np.random.Generator | None,
        range_m: float,
    ) -> None:
        self.local = local
        self.classes = classes
        self.predictive_error = predictive_error
        self.rng = rng
        self.range_m = range_m

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"

    def reset(self) -> None:
        """Forget the local estimator's measurements (the rng is not rewound)."""
        self.local.reset()

    def observe(
        self,
        t_s: float,
        utilization_front: float,
        utilization_rear: float,
        mu_front: float,
        mu_rear: float,
    ) -> None:
        """Record the realised tire state after a plant step (time ``t_s`` [s], its end).

        Only a local timing with its own sample rate keeps these (the authors' 4 Hz estimator);
        with the paper's per-step timing the planning step's peak utilization is all it needs,
        and this returns at once.
        """
        if not self.local.timing.per_planning_step:
            self.local.observe(t_s, utilization_front, utilization_rear, mu_front, mu_rear)

    def step(
        self,
        s_ahead_m: np.ndarray,
        mu_true_ahead: np.ndarray,
        utilization: float,
        *,
        camera_ok: bool = True,
        t_s: float | None = None,
    ) -> FrictionEstimate:
        """Estimate the friction over the grid ahead for one planning step.

        Parameters
        ----------
        s_ahead_m : array_like, shape (n,)
            Distances ahead of the vehicle [m], strictly increasing from 0 (paper:
            0, 1, ..., 50 m).
        mu_true_ahead : array_like, shape (n,)
            True μ at those distances [-]; ``mu_true_ahead[0]`` is under the vehicle.
        utilization : float
            Realised tire-force utilization over the last planning interval (its maximum) [-].
        camera_ok : bool
            False when the camera delivers nothing usable this step (dropped out, or its values
            were invalid and discarded): P then assumes the lowest class minimum everywhere,
            F and F-safe fuse without predictive data.
        t_s : float, optional
            Time of this step [s]. With a local timing that samples at its own rate (not once
            per planning step) the local estimate is the one published by ``t_s`` from what
            :meth:`observe` recorded, and ``utilization`` is not used.

        Returns
        -------
        FrictionEstimate

        Raises
        ------
        ValueError
            If the grid does not start at 0 m or is not strictly increasing, a μ is not
            finite and > 0 (or the μ under the vehicle exceeds 2), the utilization is not
            finite and ≥ 0, or (P, F, F-safe) a μ within the camera range lies in no class.
        """
        s, mu = check_grid(s_ahead_m, mu_true_ahead, mu_name="mu_true_ahead")
        if s[0] != 0.0:
            raise ValueError(f"s_ahead_m must start at 0 m (under the vehicle), got {s[0]!r}")
        if self.local.timing.per_planning_step or t_s is None:
            local = self.local.update(float(mu[0]), utilization)
        else:
            local = self.local.update_at(t_s)
        mu_hat, fused, data = self._mu_hat(s, mu, local, camera_ok)
        # np.clip's values for these non-zero bounds, without its per-call overhead.
        mu_hat = np.minimum(np.maximum(np.asarray(mu_hat, dtype=float), MU_HAT_MIN), MU_HAT_MAX)
        if not np.all(np.isfinite(mu_hat)):
            # A NaN would silently remove the friction constraint in the planner: fail loudly.
            raise ValueError(f"configuration {self.name!r} produced a non-finite μ̂: {mu_hat}")
        return FrictionEstimate(
            s_m=_read_only(s),
            mu_hat=_read_only(mu_hat),
            local_available=local.available,
            local_mu=local.mu,
            fused=fused,
            data=data,
        )

    def _mu_hat(
        self, s: np.ndarray, mu: np.ndarray, local: LocalEstimate, camera_ok: bool
    ) -> tuple[np.ndarray, FusedEstimate | None, FusionData | None]:
        raise NotImplementedError


class GroundTruth(FrictionConfiguration):
    """GT: the true friction ahead (paper Sec. IV-B, ``μ̂(s) = μ_gt(s)``)."""

    configuration = Configuration.GT

    def _mu_hat(self, s, mu, local, camera_ok):
        return mu.copy(), None, None


class LocalOnly(FrictionConfiguration):
    """L: the held local estimate minus its worst-case error, over the whole horizon."""

    configuration = Configuration.L

    def _mu_hat(self, s, mu, local, camera_ok):
        # μ̂_l = −max{|e_l|} + (μ_gt(0) + e_l if available else μ̂_0)  (paper Sec. IV-B)
        return np.full(s.shape, local.mu - self.local.max_error), None, None


class PredictiveOnly(FrictionConfiguration):
    """P: the lowest μ of the camera's class at each s, held beyond the camera's range."""

    configuration = Configuration.P

    def _mu_hat(self, s, mu, local, camera_ok):
        # Only the class matters to P, so the reported value's error model is irrelevant here.
        if not camera_ok:
            # No class seen: the lowest class minimum is all P can assume.
            return np.full(s.shape, min(c.mu_low for c in self.classes)), None, None
        camera = predictive_estimate(s, mu, classes=self.classes, range_m=self.range_m)
        mu_hat = np.array(camera.mu_low)
        seen = camera.in_range
        # The camera sees a prefix of the grid (s ≤ range, s[0] = 0): hold its last value.
        mu_hat[~seen] = mu_hat[seen][-1]
        return mu_hat, None, None


class Fused(FrictionConfiguration):
    """F / F-safe: camera and local estimates fused by GP regression (paper Sec. III)."""

    def __init__(
        self,
        *,
        configuration: Configuration,
        prior,
        s_local_m: float | None,
        **common,
    ) -> None:
        super().__init__(**common)
        mode = configuration.fusion_mode
        if mode is None:
            raise ValueError(f"configuration {configuration.value!r} is not a fused one")
        self.configuration = configuration
        self.mode = mode
        self.prior = prior
        self.s_local_m = s_local_m
        # The fusion's cached kernel blocks are per evaluation grid; rebuilt if the grid changes.
        self._fusion: GPFusion | None = None

    def _fusion_on(self, s: np.ndarray) -> GPFusion:
        if self._fusion is None or not np.array_equal(self._fusion.s_eval_m, s):
            self._fusion = GPFusion(self.prior, s, mode=self.mode)
        return self._fusion

    def _mu_hat(self, s, mu, local, camera_ok):
        camera = predictive_estimate(
            s, mu, classes=self.classes, error=self.predictive_error, rng=self.rng,
            range_m=self.range_m,
        )
        extra = {} if self.s_local_m is None else {"s_local_m": self.s_local_m}
        # Drawn even without a camera, so that the random errors stay in step with a run
        # without the fault; NaN marks "no data" to the assembly.
        camera_mu = camera.mu if camera_ok else np.full(s.shape, np.nan)
        # Paper Sec. III, input data: the local estimate replaces the camera's for s < s_l.
        data = assemble_inputs(
            s,
            camera_mu,
            camera.margin,
            local_mu=local.mu if local.available else None,
            local_margin=self.local.max_error,
            mode=self.mode,
            **extra,
        )
        fused = self._fusion_on(s).step(data)
        return np.asarray(fused.mu_hat, dtype=float), fused, data


def make_configuration(
    name: str | Configuration,
    *,
    classes: Sequence[SurfaceClass] = PAPER_CLASSES,
    local_error: str = "none",
    predictive_error: str = "none",
    rng: np.random.Generator | None = None,
    initial_local_mu: float | None = None,
    length_scale_m: float | None = None,
    s_local_m: float | None = None,
    max_local_error: float = LOCAL_MAX_ERROR,
    utilization_threshold: float = UTILIZATION_THRESHOLD,
    range_m: float = CAMERA_RANGE_M,
    local_timing: LocalTiming = PAPER_LOCAL_TIMING,
) -> FrictionConfiguration:
    """Build one of the paper's friction-estimation configurations.

    Parameters
    ----------
    name : Configuration or its name {"GT", "L", "P", "F", "F-safe"}
        Configuration (paper Sec. IV-B; F-safe is F with the fusion's safe mode).
    classes : sequence of SurfaceClass
        Camera class table; default the paper's.
    local_error, predictive_error : {"none", "worst_over", "worst_under", "random"}
        Error models of the local and camera estimators (:mod:`mufusion.estimators.errors`).
    rng : numpy.random.Generator, optional
        Source of all randomness; required if an error model is ``"random"``.
    initial_local_mu : float, optional
        Held local value before the first measurement [-] (the paper's ``μ̂_0``); None: the
        first step measures the μ under the vehicle as if the estimate had just been available.
    length_scale_m : float, optional
        GP kernel length scale [m]; None keeps the fusion's default prior.
    s_local_m : float, optional
        Reach ``s_l`` of the local estimate in the fusion input [m]; None keeps the fusion's
        default.
    max_local_error : float
        Worst-case local error ``max{|e_l|}`` [-] (paper: 0.025).
    utilization_threshold : float
        Local estimate available iff utilization exceeds this [-] (paper: 0.5).
    range_m : float
        Camera range ``s_f`` [m] (paper: 50).
    local_timing : LocalTiming
        Sampling, buffer, axle, publishing and delay of the local estimator; default the paper's
        (one sample per step, as ``step`` feeds it). Other timings are fed through
        ``configuration.local.observe`` / ``update_at`` (:mod:`mufusion.estimators.timing`).

    Returns
    -------
    FrictionConfiguration
        With ``.name``, ``.step(s_ahead_m, mu_true_ahead, utilization)`` and ``.reset()``.

    Raises
    ------
    ValueError
        If ``name`` is unknown (the message lists the allowed names), an error model is
        unknown or ``"random"`` without ``rng``, or another parameter is out of range.

    Examples
    --------
    >>> conf = make_configuration("P")
    >>> est = conf.step(np.arange(0.0, 61.0, 10.0), [0.8, 0.8, 0.4, 0.4, 0.4, 0.4, 0.3], 0.2)
    >>> est.mu_hat.tolist()  # 60 m is beyond the camera's 50 m: 0.4 is held
    [0.6, 0.6, 0.4, 0.4, 0.4, 0.4, 0.4]
    """
    configuration = Configuration.parse(name)
    table = validate_classes(classes)
    check_error_model("local_error", local_error, rng)
    check_error_model("predictive_error", predictive_error, rng)
    if not (math.isfinite(range_m) and range_m > 0.0):
        raise ValueError(f"range_m must be finite and > 0 m, got {range_m!r}")
    if s_local_m is not None and not (math.isfinite(s_local_m) and s_local_m >= 0.0):
        raise ValueError(f"s_local_m must be finite and ≥ 0 m or None, got {s_local_m!r}")
    local = LocalEstimator(
        max_error=max_local_error,
        utilization_threshold=utilization_threshold,
        error=local_error,
        rng=rng,
        initial_mu=initial_local_mu,
        timing=local_timing,
    )
    simple = {c.configuration: c for c in (GroundTruth, LocalOnly, PredictiveOnly)}
    if configuration in simple:
        return simple[configuration](
            local=local, classes=table, predictive_error=predictive_error, rng=rng,
            range_m=range_m,
        )
    prior = PAPER_PRIOR
    if length_scale_m is not None:
        if not (math.isfinite(length_scale_m) and length_scale_m > 0.0):
            raise ValueError(f"length_scale_m must be finite and > 0 m, got {length_scale_m!r}")
        prior = dataclasses.replace(PAPER_PRIOR, length_scale_m=float(length_scale_m))
    return Fused(
        configuration=configuration, prior=prior, s_local_m=s_local_m, local=local,
        classes=table, predictive_error=predictive_error, rng=rng, range_m=range_m,
    )
