"""Stopping in lane for an obstacle, and the braking probe that may earn it, as a supervisor.

What it does and why: :mod:`mufusion.sim.supervision` ("Stopping in lane for an obstacle").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum

from mufusion.configurations import FrictionEstimate
from mufusion.sim.components import PlanningMode
from mufusion.sim.events import EventKind, EventSink
from mufusion.sim.settings import LaneRecoverySettings
from mufusion.sim.supervision import plausible_estimate, relaxed_estimate
from mufusion.sim.supervisor import PlanningContext, Supervisor

UPPER_EDGE = float("inf")
"""``StopInLane.blocked_alpha`` while a blocked road's stop brakes at the posterior's upper edge."""


def smallest_relaxation(
    estimate: FrictionEstimate, steps: Sequence[float], fits: Callable[[FrictionEstimate], bool],
    measured_first: bool = True,
) -> tuple[float, FrictionEstimate] | None:
    """The smallest of ``steps`` whose :func:`relaxed_estimate` ``fits``, with that estimate;
    None if none does or nothing relaxes (no posterior, or its mean adds nothing to μ̂).
    ``measured_first``: as :func:`relaxed_estimate`'s."""
    for alpha in steps:
        relaxed = relaxed_estimate(estimate, alpha, measured_first)
        if relaxed is None:
            return None  # the mean adds nothing to μ̂: no step will
        if fits(relaxed):
            return alpha, relaxed
    return None


class StopProbeEnd(StrEnum):
    """Why a braking probe ended."""

    STOP_FITS = "stop_fits"
    """A relaxed μ̂ grants the stop: the vehicle stops in lane."""
    EVADING = "evading"
    """The stop is still not granted (measured, or the probe's time is up): evading."""
    RULE = "rule"
    """The stop-or-evade rule itself no longer evades."""


@dataclass(frozen=True)
class StopProbe:
    """One braking probe: its start, end and why it ended."""

    start_s: float
    end_s: float
    ended: StopProbeEnd


class StopInLane(Supervisor):
    """Turns the stop-or-evade rule's evasion into a stop in lane where a relaxed μ̂ grants it
    or a braking probe may.

    Parameters
    ----------
    settings
        Lane recovery's settings (``enabled``, ``steps``, ``stop_probe_s``).
    event
        Where its decisions are reported.
    """

    def __init__(self, settings: LaneRecoverySettings, event: EventSink) -> None:
        self.settings = settings
        self._event = event
        self.probe_since_s: float | None = None
        """The braking probe's start [s], while it runs."""
        self.probe_spent = False
        """One braking probe per run: its measurement stands."""
        self.alpha: float | None = None
        """The relaxation of the stop in lane, while held."""
        self.probes: list[StopProbe] = []
        """The braking probes that ended."""
        self.blocked_alpha: float | None = None
        """The relaxation of a stop the rule chose with μ̂ granting none (a blocked road)."""

    def choose_mode(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate
    ) -> tuple[PlanningMode, FrictionEstimate]:
        """``("emergency", relaxed)``, ``("emergency", estimate)`` while probing, else the rule's
        choice (ending a running probe if the rule no longer evades); a stop the rule chose
        where μ̂ grants none (a blocked road) with the estimate of :meth:`_blocked_stop`."""
        if mode == "evade" and self.settings.enabled and not ctx.minimal_risk:
            return self._stop_in_lane(ctx, estimate)
        self.end_probe(ctx.t_s, StopProbeEnd.RULE, f"the stop-or-evade rule chose {mode}")
        if (mode == "emergency" and self.settings.enabled and not ctx.minimal_risk
                and estimate.fused is not None and not ctx.stop_granted(estimate)):
            return mode, self._blocked_stop(ctx, estimate)
        self.blocked_alpha = None
        return mode, estimate

    def _blocked_stop(self, ctx: PlanningContext, estimate: FrictionEstimate) -> FrictionEstimate:
        """The estimate to stop with where the rule stops although μ̂ grants no stop (no side of
        the obstacle has room): μ̂ relaxed towards the posterior mean, the smallest of ``steps``
        that grants it, else μ̂ at the posterior's upper 95 % edge. Braking at μ̂ the vehicle hits
        for certain; braking harder, in lane, can only lower the impact speed, and on a road the
        camera's class under-states it excites the slip estimator, which μ̂'s own braking may not
        (docs/decisions/0095)."""
        found = smallest_relaxation(estimate, self.settings.steps, ctx.stop_granted,
                                    self.settings.measured_surface_first)
        if found is not None:
            alpha, relaxed = found
            if alpha != self.blocked_alpha:
                self._event(ctx.t_s, EventKind.LANE_RECOVERY,
                            f"the road is blocked and μ̂ grants no stop: braking with μ̂ "
                            f"relaxed {alpha:.2f} of the way to the posterior mean")
            self.blocked_alpha = alpha
            return relaxed
        # Nothing the estimates vouch for stops in time: brake with the most friction the
        # posterior allows, its upper 95 % edge, as brake assist brakes at the tires' limit (the
        # vehicle's slip control holds the wheels there, and in lane on a straight a plan above
        # the road's friction loses nothing but the speed it could not have shed anyway).
        edge = plausible_estimate(estimate)
        if edge is None:
            return estimate
        if self.blocked_alpha != UPPER_EDGE:
            self._event(ctx.t_s, EventKind.LANE_RECOVERY,
                        "the road is blocked and no μ̂ the estimates vouch for grants the stop: "
                        "braking with μ̂ at the posterior's upper 95 % edge")
        self.blocked_alpha = UPPER_EDGE
        return edge

    def _stop_in_lane(
        self, ctx: PlanningContext, estimate: FrictionEstimate
    ) -> tuple[PlanningMode, FrictionEstimate]:
        t = ctx.t_s
        # Once the evasion is under way it is kept (and without a posterior nothing relaxes).
        if ctx.last_mode == "evade" or estimate.fused is None:
            return "evade", estimate
        found = smallest_relaxation(estimate, self.settings.steps,
                                    lambda relaxed: ctx.mode_of(relaxed) == "emergency",
                                    self.settings.measured_surface_first)
        if found is not None:
            alpha, relaxed = found
            self.end_probe(t, StopProbeEnd.STOP_FITS, f"the stop fits with μ̂ relaxed "
                           f"{alpha:.2f} of the way to the posterior mean")
            if alpha != self.alpha:
                self._event(
                    t, EventKind.LANE_RECOVERY, f"stop in lane, μ̂ relaxed {alpha:.2f} of the "
                    "way to the posterior mean (μ̂ grants no stop: evading would leave the "
                    "lane)")
            self.alpha = alpha
            return "emergency", relaxed
        self.alpha = None
        since = self.probe_since_s
        probing = since is not None
        may_probe = (
            not estimate.local_available
            and not self.probe_spent
            and self.settings.stop_probe_s > 0.0
            and (since is None or t - since < self.settings.stop_probe_s - 1e-9)
        )
        plausible = plausible_estimate(estimate) if may_probe else None
        if plausible is not None and ctx.mode_of(plausible) == "emergency":
            if not probing:
                self.probe_since_s = t
                self._event(
                    t, EventKind.STOP_PROBE, "neither μ̂ nor the posterior mean grants the stop, "
                    "the posterior's 95 % band does: braking in lane to measure the friction")
            return "emergency", estimate
        self.end_probe(t, StopProbeEnd.EVADING,
                       "the stop is not granted; evading" if probing else "")
        return "evade", estimate

    def end_probe(self, t_s: float, ended: StopProbeEnd, why: str) -> None:
        """End the braking probe if it runs (reported with ``why``); it is not made again."""
        if self.probe_since_s is not None:
            self.probes.append(StopProbe(self.probe_since_s, t_s, ended))
            self._event(t_s, EventKind.STOP_PROBE_END, f"{why} after "
                        f"{t_s - self.probe_since_s:.2f} s")
            self.probe_since_s = None
            self.probe_spent = True
