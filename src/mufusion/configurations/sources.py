"""The friction-estimation configurations of the paper (Sec. IV-B): GT, L, P, F, and F-safe.

Each is an estimator on the sensor frame
(:class:`~mufusion.configurations.interface.FrictionEstimator`): it reads what the emulated
camera and slip estimator report (:mod:`mufusion.estimators.sensor_model`), never the true
friction, except GT, which declares the truth channel and reads nothing else::

    estimate = step_source(estimator, sensors, s_ahead_m, mu_true_ahead, utilization)
    planner.step(..., mu_hat_of_s=lambda s: np.interp(s, s_ego + estimate.s_m, estimate.mu_hat))

``GT``
    Ground truth: ``μ̂(s) = μ_gt(s)``.
``L``
    Local only: the held slip report minus its worst-case error over the whole horizon,
    ``μ̂(s) = μ̂_l − max{|e_l|}``.
``P``
    Predictive only: the lowest μ of the camera's (always correct) class at each ``s``; beyond
    the camera range the last in-range value is held. The camera's error model does not affect P:
    only the class is read.
``F``
    Fused (paper): the camera's μ reports and margins, replaced near the vehicle by the slip
    report when it measured, fused by GP regression; ``μ̂`` is the posterior's lower 95 % bound
    (paper Sec. III).
``F-safe``
    As F with the fusion's ``mode="safe"`` (see :mod:`mufusion.fusion`).
``F+shared``, ``F-safe+shared``
    As F and F-safe, with the reports of other vehicles received so far as a third source
    (decision 0060), placed against the frame's time and map position
    (``SensorFrame.s_ego_m``). Without reports they are F and F-safe, bit for bit.

The slip estimator reports at every step whichever configuration reads it, so the local value
and its availability are logged for all of them. Each ``μ̂`` is finally clipped into
``[MU_HAT_MIN, MU_HAT_MAX]`` (:func:`~mufusion.configurations.interface.step_source`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from mufusion.configurations.interface import (
    MU_HAT_MIN,
    FrictionEstimate,
    FrictionEstimator,
    channels_of,
    step_source,
)
from mufusion.configurations.registry import Configuration
from mufusion.estimators import (
    CAMERA_RANGE_M,
    LOCAL_MAX_ERROR,
    PAPER_CLASSES,
    PAPER_LOCAL_TIMING,
    UTILIZATION_THRESHOLD,
    LocalEstimator,
    LocalTiming,
    SurfaceClass,
    validate_classes,
)
from mufusion.estimators.comm import ReportInbox
from mufusion.estimators.sensor_model import SensorModel, make_sensor_model
from mufusion.estimators.sensors import Channel, SensorFrame, TrueFriction
from mufusion.fusion import (
    DEFAULT_SHARED,
    PAPER_PRIOR,
    GPFusion,
    GPPrior,
    ReportData,
    SharedSettings,
    assemble_inputs,
    report_data,
)

REPORT_WINDOW_SLACK_M = 10.0
"""Reports this far behind the grid's start or beyond its end still enter the fusion [m]."""


class FrictionConfiguration(FrictionEstimator):
    """Base of the paper's configurations: an estimator on the sensor frame.

    Use :func:`make_estimator` to build one (or :func:`make_configuration` for one together with
    its emulated sensors). Subclasses implement :meth:`step`.
    """

    configuration: Configuration

    @property
    def name(self) -> str:
        """The configuration's short name (``"GT"``, ..., ``"F-safe"``)."""
        return self.configuration.value

    def step(
        self, frame: SensorFrame, truth: TrueFriction | None = None
    ) -> FrictionEstimate | np.ndarray:
        """The configuration's μ̂ on ``frame.s_ahead_m`` (clipped by the caller)."""
        raise NotImplementedError


class GroundTruth(FrictionConfiguration):
    """GT: the true friction ahead (paper Sec. IV-B, ``μ̂(s) = μ_gt(s)``); reads the truth."""

    configuration = Configuration.GT
    channels = frozenset({Channel.TRUTH})

    def step(self, frame, truth=None):
        if truth is None:
            raise ValueError("GT needs the true friction: call it step(frame, truth)")
        return truth.mu


class LocalOnly(FrictionConfiguration):
    """L: the held slip report minus its worst-case error, over the whole horizon."""

    configuration = Configuration.L
    channels = frozenset[Channel]()

    def step(self, frame, truth=None):
        # μ̂_l = −max{|e_l|} + (μ_gt(0) + e_l if available else μ̂_0)  (paper Sec. IV-B)
        return np.full(frame.s_ahead_m.shape, frame.slip.mu - frame.slip.margin)


class PredictiveOnly(FrictionConfiguration):
    """P: the lowest μ of the camera's class at each s, held beyond the camera's range.

    Only the class matters to P, so the camera's μ reports (and their error model) are not read.
    """

    configuration = Configuration.P
    channels = frozenset({Channel.CAMERA_CLASSES})

    def __init__(self, classes: Sequence[SurfaceClass] = PAPER_CLASSES) -> None:
        self.classes = validate_classes(classes)

    def step(self, frame, truth=None):
        camera = frame.camera
        if camera is None or not camera.available:
            # No class seen: the lowest class minimum is all P can assume.
            return np.full(frame.s_ahead_m.shape, min(c.mu_low for c in self.classes))
        mu_hat = np.array(camera.mu_low)
        seen = camera.in_range
        # The camera sees a prefix of the grid (s ≤ range, s[0] = 0): hold its last value.
        mu_hat[~seen] = mu_hat[seen][-1]
        return mu_hat


class Fused(FrictionConfiguration):
    """F / F-safe: camera and slip reports fused by GP regression (paper Sec. III); the shared
    configurations also fuse the reports in ``inbox`` (decision 0060).

    ``unseen_mu``: what the estimate declares possible beyond its grid
    (:attr:`FrictionEstimate.unseen_mu`); :func:`make_estimator` gives the safe configurations
    the lowest class minimum, the paper's F none (the last value holds, decision 0084).
    """

    channels = frozenset({Channel.CAMERA_CLASSES, Channel.CAMERA_MU})

    def __init__(
        self,
        *,
        configuration: Configuration,
        prior: GPPrior = PAPER_PRIOR,
        s_local_m: float | None = None,
        shared: SharedSettings = DEFAULT_SHARED,
        inbox: ReportInbox | None = None,
        unseen_mu: float | None = None,
    ) -> None:
        mode = configuration.fusion_mode
        if mode is None:
            raise ValueError(f"configuration {configuration.value!r} is not a fused one")
        if inbox is not None and not configuration.shares_reports:
            raise ValueError(f"configuration {configuration.value!r} reads no shared reports")
        self.configuration = configuration
        self.mode = mode
        self.prior = prior
        self.s_local_m = s_local_m
        self.shared = shared
        self.inbox = inbox
        self.unseen_mu = unseen_mu
        # The fusion's cached kernel blocks are per evaluation grid; rebuilt if the grid changes.
        self._fusion: GPFusion | None = None

    def _reports(self, frame: SensorFrame) -> ReportData | None:
        """The reports placed against the frame's time and map position (none without a
        position: a report cannot be placed ahead of a vehicle that does not know where it is)."""
        t_s, s_ego_m, s = frame.t_s, frame.s_ego_m, frame.s_ahead_m
        if self.inbox is None or not (math.isfinite(t_s) and math.isfinite(s_ego_m)):
            return None
        window = (float(s[0]) - REPORT_WINDOW_SLACK_M, float(s[-1]) + REPORT_WINDOW_SLACK_M)
        return report_data(self.inbox.at(t_s), t_now_s=t_s, s_ego_m=s_ego_m, prior=self.prior,
                           settings=self.shared, window_m=window)

    def _fusion_on(self, s: np.ndarray) -> GPFusion:
        if self._fusion is None or not np.array_equal(self._fusion.s_eval_m, s):
            self._fusion = GPFusion(self.prior, s, mode=self.mode)
        return self._fusion

    def step(self, frame, truth=None):
        s, camera, slip = frame.s_ahead_m, frame.camera, frame.slip
        if camera is None or camera.mu is None:
            raise ValueError(f"{self.name} reads the camera's μ reports: declare Channel.CAMERA_MU")
        extra = {} if self.s_local_m is None else {"s_local_m": self.s_local_m}
        # NaN marks "no data" to the assembly (an unavailable camera reports NaN everywhere).
        # Paper Sec. III, input data: the local estimate replaces the camera's for s < s_l.
        data = assemble_inputs(
            s,
            camera.mu,
            camera.margin,
            local_mu=slip.mu if slip.available else None,
            local_margin=slip.margin,
            mode=self.mode,
            **extra,
        )
        fused = self._fusion_on(s).step(data, self._reports(frame))
        return FrictionEstimate(
            s_m=s, mu_hat=np.asarray(fused.mu_hat, dtype=float), local_available=slip.available,
            local_mu=slip.mu, fused=fused, data=data, unseen_mu=self.unseen_mu,
        )


def make_estimator(
    name: str | Configuration,
    *,
    classes: Sequence[SurfaceClass] = PAPER_CLASSES,
    length_scale_m: float | None = None,
    s_local_m: float | None = None,
    shared: SharedSettings = DEFAULT_SHARED,
    inbox: ReportInbox | None = None,
    safe_beyond_camera: bool = True,
) -> FrictionConfiguration:
    """One of the paper's estimators on the sensor frame (GT, L, P, F, F-safe, and F+shared,
    F-safe+shared with the reports of other vehicles).

    Parameters
    ----------
    name : Configuration or its name
        Configuration (paper Sec. IV-B; F-safe is F with the fusion's safe mode).
    classes : sequence of SurfaceClass
        The camera's class table (P's lowest class minimum when the camera is out).
    length_scale_m : float, optional
        GP kernel length scale [m]; None keeps the fusion's default prior.
    s_local_m : float, optional
        Reach ``s_l`` of the local estimate in the fusion input [m]; None keeps the default.
    shared : SharedSettings
        How the shared configurations treat reports (ageing, trust test, sender cap).
    inbox : ReportInbox, optional
        The reports a shared configuration receives; None: none (it is then F or F-safe).
    safe_beyond_camera : bool
        A safe configuration declares the lowest class minimum (at least ``MU_HAT_MIN``)
        beyond its grid (:attr:`FrictionEstimate.unseen_mu`, docs/decisions/0084); false: None,
        the last value holds, as for the paper's configurations.

    Raises
    ------
    ValueError
        If ``name`` is unknown (the message lists the names), a parameter is out of range, or
        an ``inbox`` is given to a configuration that reads no reports.
    """
    configuration = Configuration.parse(name)
    table = validate_classes(classes)
    if s_local_m is not None and not (math.isfinite(s_local_m) and s_local_m >= 0.0):
        raise ValueError(f"s_local_m must be finite and ≥ 0 m or None, got {s_local_m!r}")
    if configuration is Configuration.GT:
        return GroundTruth()
    if configuration is Configuration.L:
        return LocalOnly()
    if configuration is Configuration.P:
        return PredictiveOnly(table)
    prior = PAPER_PRIOR
    if length_scale_m is not None:
        if not (math.isfinite(length_scale_m) and length_scale_m > 0.0):
            raise ValueError(f"length_scale_m must be finite and > 0 m, got {length_scale_m!r}")
        prior = dataclasses.replace(PAPER_PRIOR, length_scale_m=float(length_scale_m))
    # Safe mode's promise reaches past the data: beyond the camera's range any class may lie,
    # down to the lowest (docs/decisions/0084).
    # (The authors' rounding scheme's lowest class starts at 0; μ̂ never goes below MU_HAT_MIN.)
    unseen_mu = (max(min(c.mu_low for c in table), MU_HAT_MIN)
                 if configuration.fusion_mode == "safe" and safe_beyond_camera else None)
    return Fused(configuration=configuration, prior=prior, s_local_m=s_local_m, shared=shared,
                 inbox=inbox, unseen_mu=unseen_mu)


class EmulatedConfiguration:
    """A paper configuration together with its emulated sensors, driven by the true friction.

    For use outside the closed loop (figures, tests, studies): ``step`` takes the true μ ahead,
    lets :attr:`sensors` report on it and hands the frame to :attr:`estimator`
    (:func:`~mufusion.configurations.interface.step_source`).
    """

    def __init__(self, sensors: SensorModel, estimator: FrictionConfiguration) -> None:
        self.sensors = sensors
        self.estimator = estimator
        self._channels = channels_of(estimator)

    @property
    def name(self) -> str:
        return self.estimator.name

    @property
    def configuration(self) -> Configuration:
        return self.estimator.configuration

    @property
    def local(self) -> LocalEstimator:
        """The emulated slip-based estimator."""
        return self.sensors.local

    def __repr__(self) -> str:
        return f"<EmulatedConfiguration {self.name!r}>"

    def reset(self) -> None:
        """Forget the sensors' measurements and the estimator's state (the rng is not rewound)."""
        self.sensors.reset()
        self.estimator.reset()

    def observe(self, t_s: float, utilization_front: float, utilization_rear: float,
                mu_front: float, mu_rear: float) -> None:
        """See :meth:`~mufusion.estimators.sensor_model.SensorModel.observe`."""
        self.sensors.observe(t_s, utilization_front, utilization_rear, mu_front, mu_rear)

    def step(
        self,
        s_ahead_m: np.ndarray,
        mu_true_ahead: np.ndarray,
        utilization: float,
        *,
        camera_ok: bool = True,
        t_s: float | None = None,
    ) -> FrictionEstimate:
        """The estimate for one planning step; parameters as
        :meth:`~mufusion.estimators.sensor_model.SensorModel.frame`."""
        return step_source(
            self.estimator, self.sensors, s_ahead_m, mu_true_ahead, utilization,
            camera_ok=camera_ok, t_s=t_s, channels=self._channels,
        )


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
) -> EmulatedConfiguration:
    """One of the paper's friction-estimation configurations with its emulated sensors.

    Parameters
    ----------
    name : Configuration or its name {"GT", "L", "P", "F", "F-safe"}
        Configuration (paper Sec. IV-B; F-safe is F with the fusion's safe mode).
    length_scale_m, s_local_m
        The estimator's: see :func:`make_estimator`.
    classes, local_error, predictive_error, rng, initial_local_mu
        The sensors': see :func:`~mufusion.estimators.sensor_model.make_sensor_model`
        (``classes`` is also P's class table).
    max_local_error, utilization_threshold, range_m, local_timing
        The sensors' as well (a local timing with its own sample rate is fed through
        ``configuration.observe``).

    Returns
    -------
    EmulatedConfiguration
        With ``.name``, ``.step(s_ahead_m, mu_true_ahead, utilization)`` and ``.reset()``: the
        estimator of :func:`make_estimator` on the sensors of
        :func:`~mufusion.estimators.sensor_model.make_sensor_model`.

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
    estimator = make_estimator(
        name, classes=classes, length_scale_m=length_scale_m, s_local_m=s_local_m
    )
    sensors = make_sensor_model(
        classes=classes, local_error=local_error, predictive_error=predictive_error, rng=rng,
        initial_local_mu=initial_local_mu, max_local_error=max_local_error,
        utilization_threshold=utilization_threshold, range_m=range_m, local_timing=local_timing,
    )
    return EmulatedConfiguration(sensors, estimator)
