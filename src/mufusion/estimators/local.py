"""Emulated slip-based (local) friction estimator (paper Sec. IV-A, Table I, configuration L).

A slip-based estimator measures the friction under the tires only when the tires are excited
enough: available iff the tire-force utilization ``λ_t > 0.5``, then accurate to
``max{|e_l|} = 0.025``. When it is not available the latest value is held (the paper's
``μ̂_0``).

When it samples the utilization, how many samples it remembers, which axle counts and when its
answer reaches the planner are set by a :class:`~mufusion.estimators.timing.LocalTiming`. Two ways
to drive it:

* :meth:`LocalEstimator.update` (``mu_true_here, utilization``), once per planning step with the
  caller's aggregate of the utilization: the paper's timing, as the closed loop has always done.
* :meth:`LocalEstimator.observe` (``t_s``, realised utilization and true μ per axle) at the plant or
  controller rate, and :meth:`LocalEstimator.update_at` (``t_s``) at each planning step: any timing,
  e.g. the authors' 4 Hz, 3-sample, front-axle emulation.

Error sign: the paper sets worst-case over-estimation in the turn and under-estimation in the
pop-up scenario; the authors' configuration files set ``wce_local: -0.025`` in both, which is
``error="worst_under"`` here (``μ_gt − 0.025``; configuration L then plans with ``μ_gt − 0.05``).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from mufusion.estimators.errors import check_error_model, signed_error
from mufusion.estimators.timing import PAPER_LOCAL_TIMING, TIME_TOLERANCE_S, LocalTiming

# Worst-case error of the local estimator max{|e_l|} [-] (paper Table I).
LOCAL_MAX_ERROR = 0.025
# Tire-force utilization above which the local estimate is available [-] (paper Table I).
UTILIZATION_THRESHOLD = 0.5
# Admissible true friction coefficients [-]: physically 0 < μ, and no tire exceeds 2.
MU_MAX = 2.0


@dataclass(frozen=True)
class LocalEstimate:
    """Output of one local-estimator update.

    Attributes
    ----------
    mu : float
        Held local estimate including its error [-] (``μ_gt(0) + e_l`` of the latest
        measurement, or the initial value).
    margin : float
        Its worst-case error ``max{|e_l|}`` [-].
    available : bool
        Whether this update measured (utilization above the threshold).
    """

    mu: float
    margin: float
    available: bool


def _check_mu(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and 0.0 < value <= MU_MAX):
        raise ValueError(f"{name} must be a friction coefficient in (0, {MU_MAX}], got {value!r}")
    return value


@dataclass(frozen=True)
class _Observation:
    t_s: float
    utilization: float  # of the axle(s) that decide availability
    mu: float  # true μ under the measuring axle


def _check_util(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"{name} must be finite and ≥ 0, got {value!r}")
    return value


def _check_time(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite time in s, got {value!r}")
    return value


class LocalEstimator:
    """Slip-based local friction estimator with a hold (paper configuration L, without the
    conservative offset, which the configuration subtracts).

    Parameters
    ----------
    max_error : float
        Worst-case error ``max{|e_l|}`` [-], in (0, 1); also the reported margin.
    utilization_threshold : float
        Available iff a buffered utilization sample > this [-], ≥ 0.
    error : {"none", "worst_over", "worst_under", "random"}
        Error model ``e_l`` of a measurement: 0, ``+max_error``, ``−max_error`` or
        ``U(−max_error, max_error)`` drawn per measurement from ``rng``.
    rng : numpy.random.Generator, optional
        Required for ``error="random"``.
    initial_mu : float, optional
        Held value before the first measurement [-] (taken as an estimate, no error added). If
        None, the very first update (or observation) measures the true μ with the error model as
        if the estimate had been available just before the run started (the vehicle drove on that
        surface); that update still reports ``available=False``.
    timing : LocalTiming
        Sampling, buffer, axle, publishing and delay; default the paper's
        (:data:`~mufusion.estimators.timing.PAPER_LOCAL_TIMING`).

    Raises
    ------
    ValueError
        On a parameter outside the ranges above, an unknown error model, or ``"random"``
        without ``rng``.

    Examples
    --------
    >>> est = LocalEstimator(error="worst_over")
    >>> first = est.update(0.8, utilization=0.2)  # measured as if available before the start
    >>> round(first.mu, 3), first.available
    (0.825, False)
    >>> round(est.update(0.4, utilization=0.2).mu, 3)  # not excited: the old value is held
    0.825
    >>> now = est.update(0.4, utilization=0.7)
    >>> round(now.mu, 3), now.available
    (0.425, True)
    """

    def __init__(
        self,
        *,
        max_error: float = LOCAL_MAX_ERROR,
        utilization_threshold: float = UTILIZATION_THRESHOLD,
        error: str = "none",
        rng: np.random.Generator | None = None,
        initial_mu: float | None = None,
        timing: LocalTiming = PAPER_LOCAL_TIMING,
    ) -> None:
        max_error = float(max_error)
        if not (math.isfinite(max_error) and 0.0 < max_error < 1.0):
            raise ValueError(f"max_error must be in (0, 1), got {max_error!r}")
        utilization_threshold = float(utilization_threshold)
        if not (math.isfinite(utilization_threshold) and utilization_threshold >= 0.0):
            raise ValueError(
                f"utilization_threshold must be finite and ≥ 0, got {utilization_threshold!r}"
            )
        if not isinstance(timing, LocalTiming):
            raise ValueError(f"timing must be a LocalTiming, got {type(timing).__name__}")
        self.max_error = max_error
        self.utilization_threshold = utilization_threshold
        self.error = error
        self.rng = check_error_model("error", error, rng)
        self.initial_mu = None if initial_mu is None else _check_mu("initial_mu", initial_mu)
        self.timing = timing
        self.reset()

    @property
    def estimate(self) -> LocalEstimate | None:
        """The output of the latest update (None before the first)."""
        return self._last

    def reset(self) -> None:
        """Forget all measurements and observations: back to ``initial_mu`` (the rng is not
        rewound)."""
        self._held: float | None = self.initial_mu
        self._last: LocalEstimate | None = None
        self._samples: deque[float] = deque(maxlen=self.timing.buffer_length)
        # Timed path (observe / update_at): observations not yet consumed, the clocks' progress.
        self._observations: list[_Observation] = []
        self._observed = False
        self._processed_until_s = -math.inf
        self._last_sample_s = -math.inf
        self._next_sample = 0
        self._next_publish = 0

    def _measure(self, mu_true_here: float) -> float:
        # μ̂_l = μ_gt(0) + e_l (paper Sec. IV-B, configuration L); never a negative friction.
        return max(mu_true_here + float(signed_error(self.error, self.max_error, self.rng)), 0.0)

    def _excited(self) -> bool:
        return any(u > self.utilization_threshold for u in self._samples)

    def _emit(self, held: float, available: bool) -> LocalEstimate:
        self._held = held
        self._last = LocalEstimate(mu=held, margin=self.max_error, available=available)
        return self._last

    # -- per planning step, the caller aggregates -------------------------------------------
    def update(self, mu_true_here: float, utilization: float) -> LocalEstimate:
        """One estimator cycle with the utilization aggregated by the caller.

        The sample is ``utilization``; the buffer and threshold of the timing apply (the paper's
        timing keeps one sample). Only for timings that sample once per planning step without
        delay (``timing.per_planning_step`` and ``detection_delay_s == 0``).

        Parameters
        ----------
        mu_true_here : float
            True μ under the vehicle [-], in (0, 2].
        utilization : float
            Realised tire-force utilization ``λ_t`` over the last interval [-], finite, ≥ 0.

        Returns
        -------
        LocalEstimate

        Raises
        ------
        ValueError
            If an argument is outside its range, the timing samples on its own clock or delays,
            or :meth:`observe` has been used since the last reset.
        """
        mu_true_here = _check_mu("mu_true_here", mu_true_here)
        utilization = _check_util("utilization", utilization)
        if not self.timing.per_planning_step or self.timing.detection_delay_s > 0.0:
            raise ValueError(
                "update(mu_true_here, utilization) needs a timing that samples once per planning "
                "step without delay; with this timing use observe(...) and update_at(t_s)"
            )
        if self._observed:
            raise ValueError("this estimator is fed by observe(); use update_at(t_s), or reset()")
        self._samples.append(utilization)
        available = self._excited()
        if available or self._held is None:
            # Not excited at the first update: measure once as if available before the start.
            return self._emit(self._measure(mu_true_here), available)
        return self._emit(self._held, available)

    # -- timed: observations at the plant rate, updates at the planning rate ----------------
    def observe(
        self,
        t_s: float,
        utilization_front: float,
        utilization_rear: float,
        mu_true_front: float,
        mu_true_rear: float | None = None,
    ) -> None:
        """Record the realised tire state at time ``t_s`` (call at the plant or controller rate).

        Parameters
        ----------
        t_s : float
            Time the values refer to [s] (for a plant step, the time at its end); non-decreasing
            across calls and not before the latest :meth:`update_at` time minus the delay.
        utilization_front, utilization_rear : float
            Realised utilization ``hypot(F_x, F_y) / (μ F_z)`` of each axle [-], finite, ≥ 0.
        mu_true_front : float
            True μ under the front axle [-], in (0, 2].
        mu_true_rear : float, optional
            True μ under the rear axle [-]; needed only when ``timing.axle == "rear"``.

        Raises
        ------
        ValueError
            If a value is outside its range or ``t_s`` goes back in time.
        """
        t_s = _check_time("t_s", t_s)
        u_f = _check_util("utilization_front", utilization_front)
        u_r = _check_util("utilization_rear", utilization_rear)
        mu_f = _check_mu("mu_true_front", mu_true_front)
        axle = self.timing.axle
        if axle == "rear":
            if mu_true_rear is None:
                raise ValueError("mu_true_rear is needed when timing.axle is 'rear', got None")
            mu = _check_mu("mu_true_rear", mu_true_rear)
        else:
            mu = mu_f
        latest = self._observations[-1].t_s if self._observations else -math.inf
        floor = max(latest, self._processed_until_s)
        if t_s < floor - TIME_TOLERANCE_S:
            raise ValueError(f"t_s must not go back in time: got {t_s!r} after {floor!r}")
        utilization = {"front": u_f, "rear": u_r, "either": max(u_f, u_r)}[axle]
        if self._held is None:
            self._held = self._measure(mu)
        self._observed = True
        self._observations.append(_Observation(t_s, utilization, mu))

    def _sample_at(self, t_s: float) -> None:
        window = [o for o in self._observations if o.t_s <= t_s + TIME_TOLERANCE_S]
        if self.timing.sample_statistic == "instant":
            value = window[-1].utilization if window else 0.0
        else:
            since = self._last_sample_s + TIME_TOLERANCE_S
            value = max((o.utilization for o in window if o.t_s > since), default=0.0)
        self._samples.append(value)
        self._last_sample_s = t_s

    def _publish_at(self, t_s: float, held: float) -> float:
        """Publish at ``t_s``; returns the held value afterwards."""
        seen = [o for o in self._observations if o.t_s <= t_s + TIME_TOLERANCE_S]
        if seen and self._excited():
            return self._emit(self._measure(seen[-1].mu), True).mu
        return self._emit(held, False).mu

    def _prune(self) -> None:
        # Keep what later samples need: everything after the last sample, plus the latest
        # observation at or before it (the zero-order hold of "instant" and the μ to measure).
        cut = min(self._last_sample_s, self._processed_until_s) + TIME_TOLERANCE_S
        keep_from = 0
        for i, o in enumerate(self._observations):
            if o.t_s <= cut:
                keep_from = i
        del self._observations[:keep_from]

    def update_at(self, t_s: float) -> LocalEstimate:
        """The estimate a planning step at time ``t_s`` sees (call at the planning rate).

        Processes every sample and publish instant up to ``t_s − timing.detection_delay_s`` from
        the observations so far and returns the latest published estimate (with the paper's
        per-step timing, a sample and a publish happen at that instant).

        Parameters
        ----------
        t_s : float
            Planning time [s], non-decreasing across calls.

        Returns
        -------
        LocalEstimate

        Raises
        ------
        ValueError
            If ``t_s`` is not finite or goes back in time, or nothing has been observed and no
            ``initial_mu`` was given (there is no value to report).
        """
        t_s = _check_time("t_s", t_s)
        target = t_s - self.timing.detection_delay_s
        if target < self._processed_until_s - TIME_TOLERANCE_S:
            raise ValueError(f"t_s must not go back in time: got {t_s!r} after an update at "
                             f"{self._processed_until_s + self.timing.detection_delay_s!r}")
        held = self._held
        if held is None:
            raise ValueError(
                "update_at needs an observation first (or initial_mu): nothing to report yet"
            )
        timing = self.timing
        if timing.sample_rate_hz is None:
            self._sample_at(target)
            held = self._publish_at(target, held)
        else:
            sample_period = 1.0 / timing.sample_rate_hz
            publish_period = 1.0 / timing.publish_rate_hz if timing.publish_rate_hz else None
            while True:
                t_sample = timing.phase_s + self._next_sample * sample_period
                t_publish = (
                    timing.phase_s + self._next_publish * publish_period
                    if publish_period is not None
                    else math.inf
                )
                if min(t_sample, t_publish) > target + TIME_TOLERANCE_S:
                    break
                # A sample and a publish at the same instant: the sample enters the buffer first.
                if t_sample <= t_publish + TIME_TOLERANCE_S:
                    self._sample_at(t_sample)
                    self._next_sample += 1
                else:
                    held = self._publish_at(t_publish, held)
                    self._next_publish += 1
            if publish_period is None:
                held = self._publish_at(target, held)
        self._processed_until_s = max(self._processed_until_s, target)
        self._prune()
        if self._last is None:
            # Before the first publish instant: the initial value, not available.
            return self._emit(held, False)
        return self._last
