"""Beyond the paper: what the loop does when caution alone would drive the vehicle off the road.

A conservative estimate (F-safe on a slippery road plans with the class minimum, e.g. μ̂ = 0.1)
and an estimator that needs excitation (the slip-based one measures only above 0.5 utilisation)
lock each other out: the planner never asks for enough force to excite the tires, the local
estimate never arrives, and a curve that the true friction allows cannot be planned. Two
supervisory behaviours break the lock; both are logged as events and as control modes.

**Active friction probing** (:class:`Prober`). On a straight, with no obstacle near, when the
local estimate is unavailable or stale, the posterior band ahead is wide (mean − μ̂ ≥
``min_band``) and the road ahead at the current speed needs more friction than μ̂ grants (the
estimate's grid and, with ``beyond_camera``, the road past it as far as the planner's horizon
reaches, at the friction the estimate declares possible there: :class:`RoadBeyond`), the loop
brakes briefly and boundedly (deceleration ramped to ``max_decel_mps2`` over ``ramp_s``, at most
``max_duration_s`` and ``max_speed_loss_mps``) so that the tires' utilisation passes the local
estimator's threshold; it stops as soon as the local estimate is available. The speed lost is the
probe's cost; it also helps, as the vehicle arrives slower.

**Lane recovery** (:func:`relaxed_estimate`). When the friction-limited plan cannot keep the
vehicle within its lane (the plan's own predicted footprint, :func:`planned_footprint_violation_m`,
leaves the band the planner keeps the body in by more than ``violation_tolerance_m``), the
planner plans again with μ̂ relaxed towards the posterior mean, ``μ̂ + α (target − μ̂)`` for the
smallest ``α`` of ``steps`` that keeps the lane (the least violating if none does, where a plan
predicted to hit an obstacle, :func:`planned_obstacle_clearance_m`, ranks after every plan
predicted to pass it; the candidates in increasing ``α``, each from the one before, and the next
step continues the one adopted):
the guarantee of the lower bound is given up only as far as needed to stay on the road, and
only with a posterior (F, F-safe). The target is the posterior mean, but never above what the
local estimate guarantees on the surface it measured (``μ_l − m_l``, carried over the camera's
class under the vehicle; :func:`mufusion.fusion.local_surface_bound`): the mean follows the
local value itself, and trusting that beyond its declared error over-estimated by up to ``m_l``
(docs/decisions/0043, "Lane recovery trusts a measurement within its declared error"), and
nowhere above what the estimates there declare possible (``y + m``: the mean can sit far above
the class the camera reports ahead; docs/decisions/0061). Where a measurement vouches for more,
the guarantee goes faster (``measured_surface_first``, :class:`RelaxationGain`): the measured
surface moves ``min(2α, 1)`` of its way, the road beyond ``α``; at one pace the plan that kept the
lane by braking harder on the measured surface came with a curve ahead, on a surface only the
camera has seen, planned above its friction (docs/decisions/0122).
The ``α`` adopted is held: the next step plans with it first and searches upwards from it if
that plan leaves the lane; if it keeps the lane, one step less is tried, and adopted if it keeps
the lane too without leaning on the rear tire's slack beyond the plan it replaces
(:func:`planned_rear_overuse` at most ``max(that plan's, 1) + rear_overuse_tolerance``): a plan
on a lower μ̂ that keeps the lane only by braking the rear past its friction while cornering
keeps it on paper, and the rear slides (docs/decisions/0074). Without the hold each step
started from the unrelaxed μ̂, and since its one RTI iteration rarely kept the lane where the
relaxed plans of the steps before had, the loop flipped between them and never settled on a
relaxed plan (docs/decisions/0040, "Lane recovery holds its relaxation"). Evading (the lane is
left by design), nothing is held. The footprint's corners are checked, not the reference
point alone: on a curve and yawed against the lane the corners reach up to the body's swing and
bulge further out, and a plan whose reference point stays within its bounds can still carry
the body over the edge.

**Stopping in lane for an obstacle** (:func:`relaxed_estimate`, :func:`plausible_estimate`). The
stop-or-evade rule (:mod:`mufusion.sim.obstacle_response`) evades whenever μ̂ does not grant the
stop, and for an obstacle in the lane evading means leaving it. Before the vehicle turns away,
the loop looks for a stop in lane, in this order:

1. μ̂ relaxed towards the posterior mean, the smallest ``α`` of ``steps`` that grants the stop:
   the vehicle stops in lane with that estimate (the plan brakes with it, too).
2. Otherwise, when the local estimate is unavailable (the road under the vehicle is unmeasured)
   and the upper edge of the posterior's 95 % band (mean + 1.96 σ) grants the stop, a *braking
   probe*: the vehicle brakes in lane with μ̂ as it is, for at most ``stop_probe_s``. Braking
   does two things for the stop: the brakes' lag is paid (the stop-or-evade test no longer adds
   it), and the tires' utilisation passes the local estimator's threshold, so the posterior
   learns the friction under the vehicle. Step 1 decides again at each planning step; if the
   stop is still not granted once the local estimate has arrived, or the probe's time is up,
   the vehicle evades, from a little less speed.

Both apply only before an evasion has started: a stop that fits only once the vehicle is turning
away comes late, and switching mid-manoeuvre is worse than either (measured:
docs/decisions/0027, "F-safe's lane in the pop-up").

The rule also stops where no side of the obstacle has room, whether μ̂ grants the stop or not.
Where it does not (:func:`~mufusion.sim.obstacle_response.stop_within_reach`), braking with μ̂
hits for certain: the stop brakes with μ̂ relaxed as in step 1, the smallest ``α`` that grants
it, and where none does with μ̂ at the posterior's upper 95 % edge, braking at the tires' limit
under slip control as brake assist does (docs/decisions/0095). In lane, braking harder can only
lower the impact speed, and on a road the camera's class under-states, braking at its minimum
may load the tires too little for the local estimator ever to measure.

**Braking when the evasion is futile** (``brake_when_futile``). Evading, lane recovery ranks a
candidate predicted to hit an obstacle (:func:`planned_obstacle_clearance_m`) after every one
predicted to pass it, one passing closer than ``obstacle_margin_share`` of the planner's margin
after every one that keeps it, searching on (the less short first, 0127): relaxed only until its
plans stopped hitting, the loop adopted at each step an evasion scraping past at its friction
limit, and the vehicle, turning away on a fraction of the road's friction, hit (0085). When
every candidate hits, one more plan is made with μ̂ at the upper
edge of the posterior's 95 % band (:func:`plausible_estimate`): if it hits too, the vehicle
brakes in lane with the unrelaxed μ̂ (emergency mode) to lower the impact speed, logged as
``futile_evasion``, unless that stop meets it wider (``graze_over_stop``, 0126); if it passes,
that evasion is driven (``evade_at_upper_edge``, logged as ``evasion_at_upper_edge``): every plan
with less friction is predicted to hit, and keeping one of them drove into the obstacle
(docs/decisions/0086). The check is made afresh at each planning step. An evasion inside the
band it may use (the road) that is predicted to hit is reviewed the same way, and so is one
planned where μ̂ is already all the estimates guarantee (nothing to relax; the check still asks
the posterior's upper edge, docs/decisions/0094); without a posterior (GT, L, P) the check
re-plans the evasion with μ̂ itself (docs/decisions/0062). With ``evade_at_tires_limit`` the
check plans at the tires' limit, its friction divided by the planner's utilisation factor λ
(:func:`at_tires_limit`): braking in lane hits for certain, so the reserve λ keeps for tracking
is spent on the evasion, as brake assist spends it on braking; without a posterior an evasion
that passes only there is driven (``evasion_at_tires_limit``). GT had braked into an obstacle
its evasion at λ missed by 2 cm (docs/decisions/0103).

The loop runs them as its supervisors (:class:`~mufusion.sim.supervisor.Supervisor`):
:class:`~mufusion.sim.stop_in_lane.StopInLane`, :class:`~mufusion.sim.lane_recovery.LaneRecovery`
(with the futile-evasion braking) and :class:`~mufusion.sim.probing.Probing`; this module holds
their pieces.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from enum import StrEnum

import numpy as np

from mufusion.configurations import MU_HAT_MAX, FrictionEstimate
from mufusion.fusion import Z95, declared_central_value, declared_upper_bound, local_surface_bound

# The plan's geometric checks and the settings live apart; importers of this module keep them.
from mufusion.sim.plan_checks import planned_footprint_violation_m as planned_footprint_violation_m
from mufusion.sim.plan_checks import planned_obstacle_clearance_m as planned_obstacle_clearance_m
from mufusion.sim.plan_checks import planned_obstacle_hit as planned_obstacle_hit
from mufusion.sim.plan_checks import (
    planned_obstacle_shortfall_m as planned_obstacle_shortfall_m,
)
from mufusion.sim.plan_checks import planned_rear_overuse as planned_rear_overuse
from mufusion.sim.settings import LaneRecoverySettings as LaneRecoverySettings
from mufusion.sim.settings import ProbingSettings
from mufusion.vehicle.params import GRAVITY_MPS2


@dataclasses.dataclass(frozen=True)
class RelaxationGain:
    """How far :func:`relaxed_estimate` may raise μ̂ at each of its points [-], split by what
    vouches for the higher value: ``measured`` on the surface the local estimate measured (up to
    what it guarantees there, :func:`mufusion.fusion.local_surface_bound`), ``reported`` beyond
    it (up to what the estimates there report, or the posterior mean without data). Each of
    shape (M,), ≥ 0; at each point at most one of the two is non-zero."""

    measured: np.ndarray
    reported: np.ndarray

    @functools.cached_property
    def staged(self) -> bool:
        """Whether both parts are non-zero somewhere (once per gain, not per fraction)."""
        return bool(np.any(self.measured > 1e-9)) and bool(np.any(self.reported > 1e-9))

    def at(self, alpha: float, measured_first: bool = True) -> np.ndarray:
        """The raise at ``alpha`` in [0, 1] [-], shape (M,): the whole gain at 1.

        ``measured_first`` (where both parts are non-zero somewhere): the measured part at twice
        the pace, ``min(2 alpha, 1)`` of it, the reported part ``alpha`` of it; otherwise
        ``alpha`` of both. Each ``alpha`` then raises the road beyond the measured surface as far
        as without it and the measured surface at least as far.

        >>> g = RelaxationGain(np.array([0.2, 0.0]), np.array([0.0, 0.1]))
        >>> [np.round(g.at(a), 3).tolist() for a in (0.25, 0.5, 0.75, 1.0)]
        [[0.1, 0.025], [0.2, 0.05], [0.2, 0.075], [0.2, 0.1]]
        >>> np.round(g.at(0.25, measured_first=False), 3).tolist()
        [0.05, 0.025]
        """
        if measured_first and self.staged:
            return min(2.0 * alpha, 1.0) * self.measured + alpha * self.reported
        # One of the two is zero at each point: their sum is the gain, bit for bit.
        return alpha * (self.measured + self.reported)


def relaxed_estimate(
    estimate: FrictionEstimate, alpha: float, measured_first: bool = True
) -> FrictionEstimate | None:
    """μ̂ moved the fraction ``alpha`` towards the posterior mean (never lowered); None without
    a posterior or when the mean adds nothing. ``measured_first``: the surface the local estimate
    measured at twice the pace of the road beyond it (:meth:`RelaxationGain.at`).

    The target is the mean capped, where the data hold a local estimate, by what it guarantees
    on the surface it measured (:func:`mufusion.fusion.local_surface_bound`), beyond that surface
    by the value the estimates there report, their most probable μ
    (:func:`mufusion.fusion.declared_central_value`, ``y``), and everywhere by the highest
    friction their declared errors allow (:func:`mufusion.fusion.declared_upper_bound`,
    ``y + m``). The posterior mean can lie far above a class the camera reports ahead (0.9 over a
    class of 0.25 ± 0.15 once the local estimate on 0.9 anchors it): plans relaxed to it reached
    a drop too fast (docs/decisions/0061), and relaxed to the class's upper edge (0.4 over a
    surface of 0.3) they still planned the arc above its friction (docs/decisions/0069).
    Without data the target is the mean.

    Examples
    --------
    >>> from mufusion.fusion import FusedEstimate
    >>> s = np.array([0.0, 10.0])
    >>> post = FusedEstimate(s, np.array([0.5, 0.5]), np.ones(2), np.zeros(2), np.zeros(2))
    >>> est = FrictionEstimate(s, np.array([0.1, 0.3]), False, None, fused=post)
    >>> np.round(relaxed_estimate(est, 0.5).mu_hat, 6).tolist()
    [0.3, 0.4]
    """
    return relaxed_by(estimate, relaxation_gain(estimate), alpha, measured_first)


def relaxation_gain(estimate: FrictionEstimate) -> RelaxationGain | None:
    """How far :func:`relaxed_estimate` moves μ̂ at ``alpha = 1``: the target less μ̂, never
    negative, split by what vouches for it; None without a posterior or when the mean adds
    nothing. A caller that relaxes one estimate by several fractions computes it once
    (:func:`relaxed_by`)."""
    if estimate.fused is None:
        return None
    mu_hat = np.asarray(estimate.mu_hat, dtype=float)
    target = np.asarray(estimate.fused.mean, dtype=float)
    measured = np.zeros(mu_hat.shape, dtype=bool)
    if estimate.data is not None:
        # On the surface the local estimate measured, what it guarantees; beyond it, what the
        # estimates there say is most probable (docs/decisions/0069).
        local = local_surface_bound(estimate.data, estimate.s_m)
        measured = ~np.isinf(local)
        ahead = np.where(measured, local, declared_central_value(estimate.data, estimate.s_m))
        target = np.minimum(np.minimum(target, ahead),
                            declared_upper_bound(estimate.data, estimate.s_m))
    gain = np.maximum(target - mu_hat, 0.0)
    if not np.any(gain > 1e-9):
        return None
    return RelaxationGain(np.where(measured, gain, 0.0), np.where(measured, 0.0, gain))


def relaxed_by(
    estimate: FrictionEstimate, gain: RelaxationGain | None, alpha: float,
    measured_first: bool = True,
) -> FrictionEstimate | None:
    """``estimate`` with μ̂ raised by its :func:`relaxation_gain` ``gain`` at ``alpha``
    (:meth:`RelaxationGain.at`; None for a gain of None): :func:`relaxed_estimate` without
    computing the gain again."""
    if gain is None:
        return None
    return dataclasses.replace(
        estimate, mu_hat=np.asarray(estimate.mu_hat, dtype=float)
        + gain.at(alpha, measured_first))


def plausible_estimate(estimate: FrictionEstimate) -> FrictionEstimate | None:
    """μ̂ raised to the upper edge of the posterior's 95 % band, ``mean + 1.96 σ`` (never
    lowered, at most ``MU_HAT_MAX``); None without a posterior.

    Not an estimate to plan with: the friction the posterior does not rule out, to ask whether a
    manoeuvre is worth measuring for (the braking probe of the module docstring).

    Examples
    --------
    >>> from mufusion.fusion import FusedEstimate
    >>> s = np.array([0.0, 10.0])
    >>> post = FusedEstimate(s, np.array([0.7, 0.7]), np.full(2, 0.1), np.zeros(2), np.zeros(2))
    >>> est = FrictionEstimate(s, np.array([0.6, 0.9]), False, None, fused=post)
    >>> np.round(plausible_estimate(est).mu_hat, 6).tolist()
    [0.896, 0.9]
    """
    if estimate.fused is None:
        return None
    fused = estimate.fused
    top = np.asarray(fused.mean, dtype=float) + Z95 * np.asarray(fused.std, dtype=float)
    mu_hat = np.asarray(estimate.mu_hat, dtype=float)
    return dataclasses.replace(estimate, mu_hat=np.clip(np.maximum(mu_hat, top), None, MU_HAT_MAX))


def at_tires_limit(estimate: FrictionEstimate, utilization_factor: float) -> FrictionEstimate:
    """μ̂ divided by the planner's utilisation factor λ (at most ``MU_HAT_MAX``): a plan with it
    puts its polygons at the whole of μ̂, not at the share λ that keeps a reserve for tracking.

    Not an estimate to plan with in general: the friction a manoeuvre may spend when the only
    alternative is a collision, as brake assist spends the reserve on braking (the
    futile-evasion check, docs/decisions/0103).

    Examples
    --------
    >>> est = FrictionEstimate(np.array([0.0, 10.0]), np.array([0.45, 1.9]), False, None)
    >>> at_tires_limit(est, 0.9).mu_hat.tolist()
    [0.5, 2.0]
    """
    if not 0.0 < utilization_factor <= 1.0:
        raise ValueError(f"utilization_factor must be in (0, 1], got {utilization_factor!r}")
    mu_hat = np.asarray(estimate.mu_hat, dtype=float) / utilization_factor
    return dataclasses.replace(estimate, mu_hat=np.minimum(mu_hat, MU_HAT_MAX))


@dataclasses.dataclass(frozen=True)
class RoadBeyond:
    """The road past the estimate's grid that the probe's trigger reads (arrays of one shape):
    distances ahead of the vehicle [m], the road's curvature there [1/m] and the friction the
    estimate declares possible there [-]."""

    s_m: np.ndarray
    curvature_1pm: np.ndarray
    mu_hat: np.ndarray


class ProbeEndReason(StrEnum):
    """Why a friction probe ended (the value opens the ``probe_end`` event's detail)."""

    MEASURED = "local estimate available"
    LONGEST = "longest probe reached"
    SPEED_LOSS = "largest speed loss reached"


class Prober:
    """The state of active friction probing: when it may start, its progress, its end.

    Parameters
    ----------
    settings
        Bounds and trigger thresholds.
    utilization_factor
        The planner's λ: μ̂ grants ``λ μ̂ g`` of acceleration.
    """

    def __init__(self, settings: ProbingSettings, utilization_factor: float) -> None:
        self.settings = settings
        self.utilization_factor = utilization_factor
        self.active = False
        self.probes = 0
        self.speed_lost_mps = 0.0
        self._start_t = -math.inf
        self._start_speed = 0.0
        self._end_t = -math.inf
        self._last_local_t = -math.inf

    def reason_to_probe(
        self,
        t_s: float,
        speed_mps: float,
        estimate: FrictionEstimate,
        curvature_ahead_1pm: np.ndarray,
        obstacle_near: bool,
        beyond: Callable[[], RoadBeyond | None] | None = None,
    ) -> str | None:
        """Why a probe should start now (a text for the log), or None.

        ``curvature_ahead_1pm`` is the road's curvature at the estimate's grid points; ``beyond``
        gives the road past them that the trigger reads too (None: the grid only), called only
        once every other condition holds (it reads the road: not at every planning step).
        """
        cfg = self.settings
        if estimate.local_available:
            self._last_local_t = t_s
        if not cfg.enabled or self.active or t_s - self._end_t < cfg.cooldown_s:
            return None
        if estimate.local_available or t_s - self._last_local_t < cfg.stale_after_s:
            return None
        if estimate.fused is None or speed_mps < cfg.min_speed_mps or obstacle_near:
            return None
        grid = np.asarray(estimate.s_m, dtype=float)
        kappa = np.abs(np.asarray(curvature_ahead_1pm, dtype=float))
        if np.any(kappa[grid <= cfg.straight_ahead_m] > cfg.straight_curvature_1pm):
            return None
        mu_hat = np.asarray(estimate.mu_hat, dtype=float)
        band = float(np.max(np.asarray(estimate.fused.mean, dtype=float) - mu_hat))
        if band < cfg.min_band:
            return None
        road = None if beyond is None else beyond()
        if road is not None:
            grid = np.concatenate([grid, road.s_m])
            kappa = np.concatenate([kappa, np.abs(road.curvature_1pm)])
            mu_hat = np.concatenate([mu_hat, road.mu_hat])
        needed = speed_mps**2 * kappa / GRAVITY_MPS2
        granted = self.utilization_factor * mu_hat
        short = needed - granted
        if not np.any(short > 0.0):
            return None
        k = int(np.argmax(short))
        return (
            f"local estimate stale, band {band:.2f} wide; at {speed_mps:.1f} m/s the road "
            f"{grid[k]:.0f} m ahead needs μ {needed[k]:.2f}, μ̂ grants {granted[k]:.2f}"
        )

    def start(self, t_s: float, speed_mps: float) -> None:
        self.active, self._start_t, self._start_speed = True, t_s, speed_mps
        self.probes += 1

    def decel_mps2(self, t_s: float) -> float:
        """The probe's deceleration request at ``t_s`` (ramped to the cap)."""
        cfg = self.settings
        return cfg.max_decel_mps2 * min(1.0, (t_s - self._start_t) / cfg.ramp_s)

    def reason_to_stop(
        self, t_s: float, speed_mps: float, local_available: bool
    ) -> ProbeEndReason | None:
        """Why the running probe ends now, or None."""
        cfg = self.settings
        if local_available:
            return ProbeEndReason.MEASURED
        if t_s - self._start_t >= cfg.max_duration_s - 1e-9:
            return ProbeEndReason.LONGEST
        if self._start_speed - speed_mps >= cfg.max_speed_loss_mps:
            return ProbeEndReason.SPEED_LOSS
        return None

    def stop(self, t_s: float, speed_mps: float) -> float:
        """End the probe; returns the speed it cost [m/s]."""
        self.active, self._end_t = False, t_s
        lost = max(self._start_speed - speed_mps, 0.0)
        self.speed_lost_mps += lost
        return lost
