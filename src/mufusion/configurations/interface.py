"""The friction-source interface: sensor frame in, μ̂ over the grid ahead out.

A friction source is anything with ``step(frame)``; the closed loop calls it once per planning
step with a :class:`~mufusion.estimators.sensors.SensorFrame` (the camera's class reports, the
slip estimator's report, the vehicle's signals; never the true friction)::

    class MyEstimator(FrictionEstimator):
        def step(self, frame: SensorFrame) -> np.ndarray:
            return np.full(frame.s_ahead_m.shape, frame.slip.mu - frame.slip.margin)

``step`` returns the μ̂ at ``frame.s_ahead_m`` (an array) or a :class:`FrictionEstimate`. A
source may also define ``observe(signals)``, called after every plant step with the
:class:`~mufusion.estimators.sensors.VehicleSignals` of that step, and ``reset()``. It declares the
channels it reads in ``channels`` (default: every sensor channel, not the truth); a source that
declares :attr:`~mufusion.estimators.sensors.Channel.TRUTH` is called ``step(frame, truth)``.
:func:`step_source` is the one place that hands a source its frame (and the truth).
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from mufusion.estimators.sensor_model import SensorModel
from mufusion.estimators.sensors import (
    SENSOR_CHANNELS,
    Channel,
    SensorFrame,
    VehicleSignals,
)

if TYPE_CHECKING:  # the fusion (SciPy with it) loads with the sources that fuse, not here: the
    # command line checks a --config against this interface before the heavy stack loads
    from mufusion.fusion import FusedEstimate, FusionData

# Clip range of every μ̂ handed to the planner [-]: the planner's friction polygons need a positive
# radius (the GP's lower bound far from any data, or L after a tiny measurement, could fall to or
# below 0), and no tire exceeds μ = 2. 0.05 is half the lowest class value the paper admits
# (snow/ice starts at 0.1).
MU_HAT_MIN = 0.05
MU_HAT_MAX = 2.0


@dataclass(frozen=True)
class FrictionEstimate:
    """One planning step's friction estimate over the grid ahead of the vehicle.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (n,)
        Distances ahead of the vehicle [m] (the frame's ``s_ahead_m``).
    mu_hat : numpy.ndarray, shape (n,)
        Friction coefficient the planner uses at each distance [-]; finite, in
        ``[MU_HAT_MIN, MU_HAT_MAX]``.
    local_available : bool
        Whether the slip-based estimator measured at this step.
    local_mu : float or None
        Its held report including its error [-] (None only if it never had a value).
    fused : FusedEstimate or None
        The GP posterior on ``s_m`` (F and F-safe only).
    data : FusionData or None
        The fusion's input data (F and F-safe only).
    unseen_mu : float or None
        The friction the source declares possible beyond its grid's last point [-], clipped
        into ``[MU_HAT_MIN, MU_HAT_MAX]`` as μ̂ is: the planner's speed reference keeps a curve
        there reachable on it (docs/decisions/0084). None (the paper's configurations): the
        last value holds there, as in the authors' TAMP framework.
    """

    s_m: np.ndarray
    mu_hat: np.ndarray
    local_available: bool
    local_mu: float | None
    fused: FusedEstimate | None = None
    data: FusionData | None = None
    unseen_mu: float | None = None


@runtime_checkable
class FrictionSource(Protocol):
    """What the closed loop calls on a friction source (see the module docstring)."""

    def step(self, frame: SensorFrame, /) -> FrictionEstimate | np.ndarray:
        """μ̂ at ``frame.s_ahead_m`` (a source declaring ``Channel.TRUTH`` also gets the truth)."""
        ...


class FrictionEstimator:
    """Convenience base of a friction source: a name, the channels it reads, ``reset``.

    Subclasses implement ``step(frame)`` and, if they want every plant step's signals,
    ``observe(signals)``.
    """

    channels: ClassVar[frozenset[Channel]] = SENSOR_CHANNELS
    """The channels this source reads (default: every sensor channel, not the truth)."""

    @property
    def name(self) -> str:
        """The source's label in logs, tables and figures (default: the class name)."""
        return type(self).__name__

    def reset(self) -> None:
        """Forget what has been estimated (nothing to forget here)."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"


def channels_of(source: object) -> frozenset[Channel]:
    """The channels ``source`` declares (every sensor channel if it declares none).

    Raises
    ------
    ValueError
        If ``channels`` holds something that is not a :class:`Channel` name.
    """
    declared = getattr(source, "channels", None)
    if declared is None:
        return SENSOR_CHANNELS
    try:
        return frozenset(Channel(c) for c in declared)
    except (TypeError, ValueError):
        raise ValueError(
            f"channels of {source!r} must be a collection of {[c.value for c in Channel]}, "
            f"got {declared!r}"
        ) from None


def step_source(
    source: Any,
    sensors: SensorModel,
    s_ahead_m: np.ndarray,
    mu_true_ahead: np.ndarray,
    utilization: float,
    *,
    camera_ok: bool = True,
    t_s: float | None = None,
    signals: VehicleSignals | None = None,
    channels: Collection[Channel] | None = None,
    s_ego_m: float | None = None,
) -> FrictionEstimate:
    """One planning step of ``source`` on what ``sensors`` report from the true friction.

    The only place a source is handed the true μ: as ``step(frame, truth)``, and only if it
    declares :attr:`Channel.TRUTH`; every other source is called ``step(frame)``. The μ̂ it
    returns is clipped into ``[MU_HAT_MIN, MU_HAT_MAX]``.

    Parameters
    ----------
    source
        The friction source (see :class:`FrictionSource`).
    sensors
        The sensor model that makes the frame.
    s_ahead_m, mu_true_ahead, utilization, camera_ok, t_s, signals, s_ego_m
        See :meth:`~mufusion.estimators.sensor_model.SensorModel.frame`.
    channels
        The source's channels, if already known (default: :func:`channels_of`).

    Returns
    -------
    FrictionEstimate

    Raises
    ------
    ValueError
        On bad sensor inputs, or if the source's μ̂ has the wrong shape or a non-finite value,
        or its ``unseen_mu`` is not finite (the message names the source). Finite values of
        both are clipped into ``[MU_HAT_MIN, MU_HAT_MAX]``.
    """
    channels = channels_of(source) if channels is None else channels
    frame, truth = sensors.frame(
        s_ahead_m, mu_true_ahead, utilization, channels=channels, camera_ok=camera_ok, t_s=t_s,
        signals=signals, s_ego_m=s_ego_m,
    )
    out = source.step(frame, truth) if Channel.TRUTH in channels else source.step(frame)
    estimate = out if isinstance(out, FrictionEstimate) else None
    raw = np.asarray(estimate.mu_hat if estimate is not None else out, dtype=float)
    if raw.shape != frame.s_ahead_m.shape:
        raise ValueError(f"friction source {_label(source)!r} returned μ̂ of shape {raw.shape}, "
                         f"expected {frame.s_ahead_m.shape} (one value per frame.s_ahead_m)")
    # np.clip's values for these non-zero bounds, without its per-call overhead.
    mu_hat = np.minimum(np.maximum(raw, MU_HAT_MIN), MU_HAT_MAX)
    if not np.all(np.isfinite(mu_hat)):
        # A NaN would silently remove the friction constraint in the planner: fail loudly.
        raise ValueError(f"friction source {_label(source)!r} produced a non-finite μ̂: {mu_hat}")
    mu_hat.setflags(write=False)
    if estimate is None:
        return FrictionEstimate(
            s_m=frame.s_ahead_m, mu_hat=mu_hat, local_available=frame.slip.available,
            local_mu=frame.slip.mu,
        )
    unseen = estimate.unseen_mu
    if unseen is not None:
        if not math.isfinite(unseen):
            raise ValueError(f"friction source {_label(source)!r} declared a non-finite "
                             f"unseen_mu: {unseen!r} (None or a friction value)")
        unseen = min(max(float(unseen), MU_HAT_MIN), MU_HAT_MAX)  # μ̂'s own bounds
    return FrictionEstimate(
        s_m=frame.s_ahead_m, mu_hat=mu_hat, local_available=estimate.local_available,
        local_mu=estimate.local_mu, fused=estimate.fused, data=estimate.data,
        unseen_mu=unseen,
    )


def _label(source: object) -> str:
    return str(getattr(source, "name", type(source).__name__))
