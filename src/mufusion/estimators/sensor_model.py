"""The emulated sensors of the paper (Sec. IV-A): what the camera and the slip estimator report.

The paper emulates its estimators by their availability, foresight and accuracy; this is that
emulation seen as a sensor model. It reads the true friction, as a simulated sensor must, and
turns it into the :class:`~mufusion.estimators.sensors.SensorFrame` a friction source receives:
the camera's class reports along the road ahead (:func:`predictive_estimate`) and the slip-based
estimator's report under the vehicle (:class:`LocalEstimator`). The estimators that turn these
reports into a μ̂ for the planner (L, P, F) are in :mod:`mufusion.configurations`.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence

import numpy as np

from mufusion.estimators.classes import PAPER_CLASSES, SurfaceClass, validate_classes
from mufusion.estimators.errors import check_error_model
from mufusion.estimators.local import LOCAL_MAX_ERROR, UTILIZATION_THRESHOLD, LocalEstimator
from mufusion.estimators.predictive import CAMERA_RANGE_M, check_grid, predictive_estimate
from mufusion.estimators.sensors import (
    CameraReport,
    Channel,
    SensorFrame,
    TrueFriction,
    VehicleSignals,
)
from mufusion.estimators.timing import PAPER_LOCAL_TIMING, LocalTiming


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


class SensorModel:
    """The emulated camera and slip estimator of one vehicle.

    Parameters
    ----------
    local : LocalEstimator
        The emulated slip-based estimator (its error model, threshold, timing and rng).
    classes : sequence of SurfaceClass
        The camera's class table; default the paper's.
    predictive_error : {"none", "worst_over", "worst_under", "random"}
        Error model of the camera's μ reports (:mod:`mufusion.estimators.errors`).
    rng : numpy.random.Generator, optional
        Required if ``predictive_error`` is ``"random"`` (shared with ``local``: one stream per
        run, drawn in a fixed order, the slip report first).
    range_m : float
        Camera range ``s_f`` [m] (paper: 50).

    Raises
    ------
    ValueError
        On an unknown error model, ``"random"`` without ``rng``, a bad class table or a range
        that is not finite and > 0.
    """

    def __init__(
        self,
        local: LocalEstimator | None = None,
        *,
        classes: Sequence[SurfaceClass] = PAPER_CLASSES,
        predictive_error: str = "none",
        rng: np.random.Generator | None = None,
        range_m: float = CAMERA_RANGE_M,
    ) -> None:
        check_error_model("predictive_error", predictive_error, rng)
        if not (math.isfinite(range_m) and range_m > 0.0):
            raise ValueError(f"range_m must be finite and > 0 m, got {range_m!r}")
        self.local = local if local is not None else LocalEstimator()
        self.classes = validate_classes(classes)
        self.predictive_error = predictive_error
        self.rng = rng
        self.range_m = float(range_m)

    def reset(self) -> None:
        """Forget the slip estimator's measurements (the rng is not rewound)."""
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

        ``mu_front`` / ``mu_rear`` are the true μ under each axle, which the emulated slip
        estimator measures. Only a local timing with its own sample rate keeps these (the
        authors' 4 Hz estimator); with the paper's per-step timing the planning step's peak
        utilisation is all it needs.
        """
        if not self.local.timing.per_planning_step:
            self.local.observe(t_s, utilization_front, utilization_rear, mu_front, mu_rear)

    def frame(
        self,
        s_ahead_m: np.ndarray,
        mu_true_ahead: np.ndarray,
        utilization: float,
        *,
        channels: Collection[Channel],
        camera_ok: bool = True,
        t_s: float | None = None,
        signals: VehicleSignals | None = None,
        s_ego_m: float | None = None,
    ) -> tuple[SensorFrame, TrueFriction]:
        """The sensors' reports for one planning step, and the truth they were made from.

        Parameters
        ----------
        s_ahead_m : array_like, shape (n,)
            Distances ahead of the vehicle [m], strictly increasing from 0.
        mu_true_ahead : array_like, shape (n,)
            True μ at those distances [-]; ``mu_true_ahead[0]`` is under the vehicle.
        utilization : float
            Peak realised tire utilisation over the last planning interval [-].
        channels : collection of Channel
            What the source reads: the camera is emulated only for camera channels, its μ
            reports (and their random draws) only for :attr:`Channel.CAMERA_MU`.
        camera_ok : bool
            False while the camera delivers nothing usable (its μ errors are still drawn, so
            that the random stream stays in step with a run without the fault).
        t_s : float, optional
            Time of the step [s]; with a local timing that samples at its own rate the slip
            report is the one published by ``t_s`` from what :meth:`observe` recorded.
        signals : VehicleSignals, optional
            The vehicle's signals after the latest plant step (None before the first).
        s_ego_m : float, optional
            The vehicle's progress along the road's map [m] (its localisation).

        Returns
        -------
        (SensorFrame, TrueFriction)
            The truth is for the caller to hand on only to a source declaring
            :attr:`Channel.TRUTH`.

        Raises
        ------
        ValueError
            If the grid does not start at 0 m or is not strictly increasing, a μ is not finite
            and > 0 (or the μ under the vehicle exceeds 2), the utilisation is not finite and
            ≥ 0, or a μ within the camera's range lies in no class.
        """
        s, mu = check_grid(s_ahead_m, mu_true_ahead, mu_name="mu_true_ahead")
        if s[0] != 0.0:
            raise ValueError(f"s_ahead_m must start at 0 m (under the vehicle), got {s[0]!r}")
        # The slip report first: with a shared rng its draw precedes the camera's.
        if self.local.timing.per_planning_step or t_s is None:
            slip = self.local.update(float(mu[0]), utilization)
        else:
            slip = self.local.update_at(t_s)
        camera = self._camera(s, mu, channels, camera_ok)
        _read_only(s)
        frame = SensorFrame(
            t_s=math.nan if t_s is None else float(t_s), s_ahead_m=s,
            utilization_peak=float(utilization), slip=slip, camera=camera, signals=signals,
            s_ego_m=math.nan if s_ego_m is None else float(s_ego_m),
        )
        return frame, TrueFriction(s_ahead_m=s, mu=_read_only(mu))

    def _camera(
        self, s: np.ndarray, mu: np.ndarray, channels: Collection[Channel], camera_ok: bool
    ) -> CameraReport | None:
        values = Channel.CAMERA_MU in channels
        if not values and Channel.CAMERA_CLASSES not in channels:
            return None
        if not (camera_ok or values):
            return _no_report(s.shape)
        # Without the μ reports only the class matters: no error model, no draw.
        seen = predictive_estimate(
            s, mu, classes=self.classes, error=self.predictive_error if values else "none",
            rng=self.rng, range_m=self.range_m,
        )
        if not camera_ok:
            return _no_report(s.shape, with_mu=True)
        return CameraReport(
            available=True, class_index=seen.class_index, mu_low=seen.mu_low,
            margin=seen.margin, mu=seen.mu if values else None,
        )


def _no_report(shape: tuple[int, ...], with_mu: bool = False) -> CameraReport:
    nan = _read_only(np.full(shape, np.nan))
    return CameraReport(
        available=False, class_index=_read_only(np.full(shape, -1, dtype=int)), mu_low=nan,
        margin=nan, mu=nan if with_mu else None,
    )


def make_sensor_model(
    *,
    classes: Sequence[SurfaceClass] = PAPER_CLASSES,
    local_error: str = "none",
    predictive_error: str = "none",
    rng: np.random.Generator | None = None,
    initial_local_mu: float | None = None,
    max_local_error: float = LOCAL_MAX_ERROR,
    utilization_threshold: float = UTILIZATION_THRESHOLD,
    range_m: float = CAMERA_RANGE_M,
    local_timing: LocalTiming = PAPER_LOCAL_TIMING,
) -> SensorModel:
    """The paper's emulated sensors (Sec. IV-A, Table I) with the given error models.

    Parameters
    ----------
    classes : sequence of SurfaceClass
        The camera's class table; default the paper's.
    local_error, predictive_error : {"none", "worst_over", "worst_under", "random"}
        Error models of the slip estimator and the camera (:mod:`mufusion.estimators.errors`).
    rng : numpy.random.Generator, optional
        Source of all randomness; required if an error model is ``"random"``.
    initial_local_mu : float, optional
        Held slip report before the first measurement [-] (the paper's ``μ̂_0``); None: the
        first step measures the μ under the vehicle as if the estimate had just been available.
    max_local_error : float
        Worst-case slip-estimator error ``max{|e_l|}`` [-] (paper: 0.025).
    utilization_threshold : float
        The slip estimator measures iff utilisation exceeds this [-] (paper: 0.5).
    range_m : float
        Camera range ``s_f`` [m] (paper: 50).
    local_timing : LocalTiming
        Sampling, buffer, axle, publishing and delay of the slip estimator; default the paper's.

    Raises
    ------
    ValueError
        On an unknown error model, ``"random"`` without ``rng``, or a parameter out of range
        (the message names it).
    """
    table = validate_classes(classes)
    check_error_model("local_error", local_error, rng)
    check_error_model("predictive_error", predictive_error, rng)
    if not (math.isfinite(range_m) and range_m > 0.0):
        raise ValueError(f"range_m must be finite and > 0 m, got {range_m!r}")
    local = LocalEstimator(
        max_error=max_local_error,
        utilization_threshold=utilization_threshold,
        error=local_error,
        rng=rng,
        initial_mu=initial_local_mu,
        timing=local_timing,
    )
    return SensorModel(
        local, classes=table, predictive_error=predictive_error, rng=rng, range_m=range_m
    )
