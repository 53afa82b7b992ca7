"""When the slip-based (local) estimator samples the tires, and when its answer reaches the planner.

The paper (Table I) says only that the local estimate is available when the tire-force utilization
exceeds 0.5. Two timings are presets here:

``PAPER_LOCAL_TIMING`` (default)
    One sample per planning step: the peak realised utilization of either axle since the previous
    planning step; available iff that sample exceeds the threshold; no delay. This is exactly what
    the closed loop has always fed :meth:`~mufusion.estimators.LocalEstimator.update`.
``AUTHORS_LOCAL_TIMING``
    What the authors' emulation did (``perception/scripts/road_perception.py`` in their
    ``tamp_ws`` repository, parameter ``dt_road_perception: 0.25``): every 0.25 s it reads the
    *latest* realised front-axle utilization (an instantaneous value, so excitation between two
    samples is missed), keeps the last 3 samples, is available if any of them exceeds the
    threshold, and publishes its estimate at the same 4 Hz; the μ it reports is the one under the
    front axle at publish time. A single excited sample therefore keeps the estimate available for
    3 × 0.25 s = 0.75 s. The simulator published tire forces at every plant step, so no transport
    delay is added: the detection lag is the wait for the next 4 Hz sample (0 to 0.25 s, set by the
    phase of the sampling clock against the event) plus the wait for the next planning step that
    reads the published estimate (0 to 0.1 s at 10 Hz): at most 0.35 s.

Clock conventions: sample and publish instants are ``phase_s + k / rate``; an observation
timestamped within :data:`TIME_TOLERANCE_S` of an instant counts as taken at that instant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

Axle = Literal["front", "rear", "either"]
AXLES: tuple[str, ...] = get_args(Axle)
SampleStatistic = Literal["peak", "instant"]
SAMPLE_STATISTICS: tuple[str, ...] = get_args(SampleStatistic)

# Two instants closer than this are the same instant [s]: the loop's clocks are i·dt sums.
TIME_TOLERANCE_S = 1e-9


@dataclass(frozen=True)
class LocalTiming:
    """Sampling, buffering, publishing and delay of the local estimator.

    Attributes
    ----------
    sample_rate_hz : float or None
        Rate of the utilization samples [Hz], > 0; None: one sample per planning step (each call
        of :meth:`~mufusion.estimators.LocalEstimator.update_at`, or of the legacy
        :meth:`~mufusion.estimators.LocalEstimator.update`).
    sample_statistic : {"peak", "instant"}
        ``"peak"``: a sample is the largest realised utilization observed since the previous sample
        (nothing between samples is missed); ``"instant"``: the latest observation at the sampling
        instant (a zero-order hold, as a subscriber that keeps the last message).
    buffer_length : int
        Number of latest samples kept, ≥ 1; available iff any of them exceeds the threshold.
    axle : {"front", "rear", "either"}
        Whose realised utilization decides availability (``"either"``: the larger of the two).
        The μ measured is the one under the front axle, or the rear one for ``"rear"``.
    publish_rate_hz : float or None
        Rate at which the estimate is recomputed and published [Hz], > 0; None: at every
        planning step. Needs ``sample_rate_hz``.
    detection_delay_s : float
        Extra transport delay [s], ≥ 0: a planning step at ``t`` sees what was published by
        ``t − detection_delay_s``.
    phase_s : float
        Offset of the sample and publish clocks [s], ≥ 0 and below the sample period.
    source : str
        Where the numbers come from.

    Raises
    ------
    ValueError
        If a field is outside the range above; the message names the field.

    Examples
    --------
    >>> AUTHORS_LOCAL_TIMING.hold_s
    0.75
    >>> PAPER_LOCAL_TIMING.per_planning_step
    True
    """

    sample_rate_hz: float | None = None
    sample_statistic: SampleStatistic = "peak"
    buffer_length: int = 1
    axle: Axle = "either"
    publish_rate_hz: float | None = None
    detection_delay_s: float = 0.0
    phase_s: float = 0.0
    source: str = ""

    def __post_init__(self) -> None:
        for name in ("sample_rate_hz", "publish_rate_hz"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"LocalTiming.{name} must be None or finite and > 0 Hz, "
                                 f"got {value!r}")
        if self.publish_rate_hz is not None and self.sample_rate_hz is None:
            raise ValueError(
                "LocalTiming.publish_rate_hz needs a sample_rate_hz (a fixed publish clock over "
                "per-planning-step samples is undefined); got sample_rate_hz=None"
            )
        if self.sample_statistic not in SAMPLE_STATISTICS:
            raise ValueError(f"LocalTiming.sample_statistic must be one of "
                             f"{list(SAMPLE_STATISTICS)}, got {self.sample_statistic!r}")
        if self.axle not in AXLES:
            raise ValueError(f"LocalTiming.axle must be one of {list(AXLES)}, got {self.axle!r}")
        if isinstance(self.buffer_length, bool) or not isinstance(self.buffer_length, int) or (
            self.buffer_length < 1
        ):
            raise ValueError(f"LocalTiming.buffer_length must be an int ≥ 1, "
                             f"got {self.buffer_length!r}")
        if not (math.isfinite(self.detection_delay_s) and self.detection_delay_s >= 0.0):
            raise ValueError(f"LocalTiming.detection_delay_s must be finite and ≥ 0 s, "
                             f"got {self.detection_delay_s!r}")
        top = math.inf if self.sample_rate_hz is None else 1.0 / self.sample_rate_hz
        if not (math.isfinite(self.phase_s) and 0.0 <= self.phase_s < top):
            raise ValueError(f"LocalTiming.phase_s must be in [0, {top}) s (one sample period), "
                             f"got {self.phase_s!r}")
        if self.sample_rate_hz is None and self.phase_s != 0.0:
            raise ValueError("LocalTiming.phase_s needs a sample_rate_hz; got sample_rate_hz=None "
                             f"and phase_s={self.phase_s!r}")

    @property
    def per_planning_step(self) -> bool:
        """True if samples are taken at the planning steps (``sample_rate_hz`` is None)."""
        return self.sample_rate_hz is None

    @property
    def hold_s(self) -> float | None:
        """How long one excited sample keeps the estimate available [s] (None per step)."""
        if self.sample_rate_hz is None:
            return None
        return self.buffer_length / self.sample_rate_hz


PAPER_LOCAL_TIMING = LocalTiming(
    source="paper Table I (available iff λ_t > 0.5), evaluated once per planning step on the "
    "peak realised utilization of either axle since the previous step",
)

AUTHORS_LOCAL_TIMING = LocalTiming(
    sample_rate_hz=4.0,
    sample_statistic="instant",
    buffer_length=3,
    axle="front",
    publish_rate_hz=4.0,
    detection_delay_s=0.0,
    source="authors' tamp_ws road_perception.py: dt_road_perception 0.25 s, Ff_util_buffer of 3, "
    "front-axle utilization sqrt(Fxf² + Fyf²)/(Fzf μ), true μ at the front axle",
)

LOCAL_TIMINGS: dict[str, LocalTiming] = {
    "paper": PAPER_LOCAL_TIMING,
    "authors": AUTHORS_LOCAL_TIMING,
}


def local_timing(name: str) -> LocalTiming:
    """Return a local-estimator timing preset by name.

    Parameters
    ----------
    name : {"paper", "authors"}

    Raises
    ------
    ValueError
        If ``name`` is unknown; the message lists the presets.

    Examples
    --------
    >>> local_timing("authors").sample_rate_hz
    4.0
    """
    try:
        return LOCAL_TIMINGS[name]
    except KeyError:
        raise ValueError(f"local timing must be one of {sorted(LOCAL_TIMINGS)}, "
                         f"got {name!r}") from None
