"""Lane recovery and braking when the evasion is futile, as a supervisor of the loop.

What they do and why: :mod:`mufusion.sim.supervision` ("Lane recovery", "Braking when the
evasion is futile").
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner import Plan
from mufusion.sim.components import Planner, PlanningMode
from mufusion.sim.events import EventKind, EventSink
from mufusion.sim.plan_checks import planned_contact_width_m
from mufusion.sim.records import RecoveryCandidate
from mufusion.sim.recovery_outcome import Recovery as Recovery
from mufusion.sim.recovery_outcome import RecoveryOutcome as RecoveryOutcome
from mufusion.sim.settings import LaneRecoverySettings
from mufusion.sim.supervision import (
    RelaxationGain,
    at_tires_limit,
    planned_footprint_violation_m,
    planned_obstacle_clearance_m,
    planned_obstacle_hit,
    planned_obstacle_shortfall_m,
    planned_rear_overuse,
    plausible_estimate,
    relaxation_gain,
    relaxed_by,
)
from mufusion.sim.supervisor import PlanningContext, Supervisor
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State

TOP_FIRST_ITERATIONS = 2
"""RTI iterations the most relaxed candidate gets before the top-first search concludes that
nothing helps: the ascending search reaches it after one per step below it, and one iteration
from the friction-limited plan ranked it worse where those four ranked it better
(docs/decisions/0091)."""


class LaneRecovery(Supervisor):
    """Re-plans with μ̂ relaxed towards the posterior mean where the plan cannot keep the lane.

    Parameters
    ----------
    settings
        Its switches and steps of relaxation.
    planner
        The planner whose warm start the search moves and restores.
    params
        Vehicle dimensions (footprint).
    lane_bounds_m
        ``(d_min, d_max)`` of the planner's reference point [m].
    curvature
        The road's curvature [1/m] at arc lengths [m].
    event
        Where the outcomes are reported.
    obstacle_margin_m
        The gap to an obstacle the planner is asked to keep [m]: evading, a plan that passes
        closer is searched on like one that leaves the lane (docs/decisions/0085).
    record
        Where each plan the search weighs is logged (the run log's ``recovery_candidates``);
        None: nowhere.
    """

    def __init__(
        self,
        settings: LaneRecoverySettings,
        planner: Planner,
        params: VehicleParams,
        lane_bounds_m: tuple[float, float],
        curvature: Callable[[np.ndarray], np.ndarray],
        event: EventSink,
        obstacle_margin_m: float = 0.0,
        utilization_factor: float = 1.0,
        record: Callable[[RecoveryCandidate], None] | None = None,
    ) -> None:
        self.settings = settings
        self.utilization_factor = utilization_factor
        """The planner's λ: the share of μ̂ its polygons use; the futility check may spend the
        rest (``evade_at_tires_limit``)."""
        self.obstacle_margin_m = obstacle_margin_m
        self.planner = planner
        self.params = params
        self.lane_bounds_m = lane_bounds_m
        self.curvature = curvature
        self._event = event
        self._record = record
        self.alpha = 0.0
        """The relaxation adopted at the last step, held into the next (0: none)."""
        self.recoveries: list[Recovery] = []
        """Each step's outcome where lane recovery acted, in order."""
        self._gain: tuple[FrictionEstimate, RelaxationGain | None] | None = None

    def _relaxed(self, estimate: FrictionEstimate, alpha: float) -> FrictionEstimate | None:
        """:func:`~mufusion.sim.supervision.relaxed_estimate`, with the gain computed once per
        estimate (a planning step relaxes the same one by up to five fractions)."""
        if self._gain is None or self._gain[0] is not estimate:
            self._gain = (estimate, relaxation_gain(estimate))
        return relaxed_by(estimate, self._gain[1], alpha, self.settings.measured_surface_first)

    def adjust_inputs(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate
    ) -> FrictionEstimate:
        """``estimate`` relaxed by the fraction adopted at the previous step (not evading)."""
        if not self.settings.enabled or ctx.minimal_risk or mode == "evade":
            return estimate
        if self.alpha > 0.0:
            relaxed = self._relaxed(estimate, self.alpha)
            if relaxed is not None:
                return relaxed
        self.alpha = 0.0
        return estimate

    def review(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate, plan: Plan
    ) -> tuple[Plan, FrictionEstimate]:
        """Re-plan with μ̂ relaxed towards the posterior mean if the plan cannot keep the lane.

        ``plan`` was planned with ``estimate`` relaxed by the fraction the previous step adopted
        (:meth:`adjust_inputs`); ``estimate`` itself is unrelaxed.
        """
        if not self.settings.enabled or ctx.minimal_risk:
            return plan, estimate
        # Evading, the plan leaves the lane by design and a held relaxation would only make the
        # swerve harder (measured: off the road 4 → 13 of 108 F-safe pop-up runs): each step
        # searches from the unrelaxed μ̂ there, and nothing is held into the steps after.
        hold = mode != "evade"
        if not hold:
            self.alpha = 0.0
        held = self.alpha
        # An evasion predicted to hit an obstacle is reviewed even where it keeps to the band
        # it may use (the road, evading): "keeps the lane" says nothing about the obstacle.
        futile = (mode == "evade" and self.settings.brake_when_futile and not plan.fallback
                  and planned_obstacle_hit(plan.states, ctx.obstacles, self.params, plan.dt_s))
        # Without a posterior (GT, L, P), or with μ̂ already at what the estimates guarantee,
        # there is nothing to relax: skip the footprint check, which would run at every planning
        # step. An evasion is still checked at the posterior's upper edge where there is one
        # (docs/decisions/0094); without one at μ̂ itself (one more iteration, so that a plan
        # still converging is not taken for a futile one).
        if self._relaxed(estimate, 1.0) is None:
            self.alpha = 0.0
            if futile:
                decided = self._when_every_evasion_hits(ctx, estimate, held=0.0)
                if decided is not None:
                    return decided
            return plan, estimate
        planned_with = self._relaxed(estimate, held) if held > 0.0 else estimate
        assert planned_with is not None
        tolerance = self.settings.violation_tolerance_m
        before = self.footprint_violation_m(plan)
        alphas = (0.0, *self.settings.steps)
        t = ctx.t_s
        # Evading, a plan that passes the obstacle closer than its share of the margin its OCP
        # keeps has met its friction limit as one leaving the lane has: relaxing μ̂ only until
        # the plan scraped past (by 0-8 cm) chose, at every step, the evasion that
        # procrastinates, and the car hit what a plan at the estimates' central value would have
        # passed (docs/decisions/0085).
        shortfall = self._obstacle_shortfall_m(ctx, mode)
        short = not plan.fallback and shortfall(plan) > 0.0
        # No friction-limited plan at all (the solve failed) counts as not keeping the lane.
        if before <= tolerance and not plan.fallback and not futile and not short:
            if held == 0.0:
                return plan, estimate
            # The lane is kept with the relaxation held: try one step less of it, so that the
            # guarantee of the lower bound returns as soon as the lane allows — but not a plan
            # that keeps the lane by braking the rear past its friction: on the road the rear
            # slides where the plan turns (docs/decisions/0074).
            lower = alphas[alphas.index(held) - 1]
            memory = self.planner.memory
            candidate_estimate = self._relaxed(estimate, lower) if lower > 0.0 else estimate
            assert candidate_estimate is not None
            candidate = ctx.plan(candidate_estimate, mode)
            rear_room = (max(planned_rear_overuse(plan), 1.0)
                         + self.settings.rear_overuse_tolerance)
            if (not candidate.fallback and self.footprint_violation_m(candidate) <= tolerance
                    and planned_rear_overuse(candidate) <= rear_room):
                self.alpha = lower
                self.recoveries.append(Recovery(t, RecoveryOutcome.EASED, lower, held))
                self._event(
                    t, EventKind.LANE_RECOVERY, f"the lane is kept with μ̂ relaxed {lower:.2f} of "
                    f"the way to the posterior mean (was {held:.2f})")
                return candidate, candidate_estimate
            self.planner.restore(memory)
            return plan, planned_with
        # Each candidate starts from the one before (a continuation in α: the later candidates
        # have had more iterations), and the next step continues the plan adopted: the planner
        # keeps its latest plan as the next warm start (and that plan's front force as where
        # the next plan's force starts), which after the search would be the last candidate
        # tried, not the one the controller tracks.
        # A plan predicted to hit an obstacle is never preferred to one predicted to pass it,
        # however much further the latter leaves the lane (evading, the road band).
        # Then the band's violation beyond the tolerance; among the candidates within it, one
        # short of its share of the obstacle margin after every one that keeps it, and among
        # those the less short first (docs/decisions/0127). A plan leaving the band beyond the
        # tolerance is not made to leave it further for the margin: measured, that put two
        # marginal pop-ups of limits_popup off the road.
        def rank(candidate: Plan, violation: float,
                 alpha: float) -> tuple[bool, float, bool, float, float]:
            hits = planned_obstacle_hit(candidate.states, ctx.obstacles, self.params,
                                        candidate.dt_s)
            gap_short = np.nan if candidate.fallback else shortfall(candidate)
            if self._record is not None:
                self._record(RecoveryCandidate(t, alpha, violation, hits, gap_short,
                                               candidate.fallback))
            if candidate.fallback:
                return (hits, np.inf, True, np.inf, np.inf)
            slack = max(violation - tolerance, 0.0)
            if self.settings.shortfall_before_band:
                return (hits, slack, gap_short > 0.0, gap_short, violation)
            return (hits, slack, gap_short > 0.0, violation, gap_short)

        best = (rank(plan, before, held), before, plan, planned_with, held,
                self.planner.memory)
        search = [a for a in alphas if a > held]
        if mode == "evade" and self.settings.evade_top_first and len(search) > 1:
            # The most relaxed candidate first, from the friction-limited plan: one that does
            # no better leaves nothing for the smaller relaxations to find, and the search ends
            # after one solve instead of one per step (docs/decisions/0091). One that does
            # better is kept as a candidate, and the smaller ones follow from the
            # friction-limited plan as before, so the smallest that suffices is adopted.
            start = self.planner.memory
            top = search.pop()
            relaxed = self._relaxed(estimate, top)
            assert relaxed is not None
            helps = False
            for _ in range(TOP_FIRST_ITERATIONS):
                candidate = ctx.plan(relaxed, mode)
                violation = self.footprint_violation_m(candidate)
                key = rank(candidate, violation, top)
                helps = not candidate.fallback and key < best[0]
                if helps:
                    best = (key, violation, candidate, relaxed, top, self.planner.memory)
                    break
            self.planner.restore(start)
            if not helps:
                search = []
        for alpha in search:
            relaxed = self._relaxed(estimate, alpha)
            assert relaxed is not None
            candidate = ctx.plan(relaxed, mode)
            violation = self.footprint_violation_m(candidate)
            key = rank(candidate, violation, alpha)
            # Ranked equal, the smaller relaxation (the top candidate's is the largest).
            if not candidate.fallback and (key, alpha) < (best[0], best[4]):
                best = (key, violation, candidate, relaxed, alpha, self.planner.memory)
            if not candidate.fallback and violation <= tolerance and not (key[0] or key[2]):
                break
        (every_one_hits, *_), violation, plan, adopted, alpha, memory = best
        self.planner.restore(memory)
        if mode == "evade" and every_one_hits and self.settings.brake_when_futile:
            decided = self._when_every_evasion_hits(ctx, estimate, held)
            if decided is not None:
                self.alpha = 0.0
                return decided
        self.alpha = alpha if hold else 0.0
        problem = "no friction-limited plan" if plan.fallback and alpha == 0.0 else (
            f"the plan left the lane by {before:.2f} m" if before > tolerance
            else "the evasion passes the obstacle within its margin" if short and not futile
            else "the friction-limited plan failed"
        )
        held_note = f" (from {held:.2f} held)" if held > 0.0 else ""
        outcome = RecoveryOutcome.RELAXED if alpha > 0.0 else RecoveryOutcome.DID_NOT_HELP
        self.recoveries.append(Recovery(t, outcome, alpha, held))
        self._event(
            t, EventKind.LANE_RECOVERY,
            f"{problem}; μ̂ relaxed {alpha:.2f} of the way to the posterior mean{held_note}, the "
            f"plan leaves the lane by {violation:.2f} m" if alpha > 0.0 else f"{problem}; "
            "relaxing μ̂ towards the posterior mean did not help",
        )
        return plan, adopted

    def _most_friction(self, estimate: FrictionEstimate) -> tuple[FrictionEstimate, bool]:
        """The most friction ``estimate`` allows, as the futility check plans with it, and
        whether it has a posterior: the posterior's upper 95 % edge, or μ̂ itself without one;
        with ``evade_at_tires_limit``, at the tires' limit (÷ λ, :func:`at_tires_limit`)."""
        edge = plausible_estimate(estimate)
        top = estimate if edge is None else edge
        if self._spends_reserve:
            top = at_tires_limit(top, self.utilization_factor)
        return top, edge is not None

    @property
    def _spends_reserve(self) -> bool:
        """Whether the futility check plans at the tires' limit (``evade_at_tires_limit`` and a
        planner that keeps a reserve, λ < 1)."""
        return self.settings.evade_at_tires_limit and self.utilization_factor < 1.0

    def _when_every_evasion_hits(
        self, ctx: PlanningContext, estimate: FrictionEstimate, held: float,
    ) -> tuple[Plan, FrictionEstimate] | None:
        """The plan to drive when every lane-recovery candidate is predicted to hit an obstacle,
        or None to continue the best candidate.

        ``estimate`` is unrelaxed. An evasion planned with the most friction it allows
        (:meth:`_most_friction`) decides: if it hits too, the stop in lane
        (``futile_evasion``); if it passes with more friction than μ̂, that evasion
        (``evasion_at_upper_edge`` with a posterior, with ``evade_at_upper_edge``;
        ``evasion_at_tires_limit`` without one). None when either plan fails, or when the
        re-planned evasion passes with μ̂ itself.
        """
        memory = self.planner.memory
        top, posterior = self._most_friction(estimate)
        check = ctx.plan(top, "evade")
        evading = self.planner.memory
        gap = planned_obstacle_clearance_m(check.states, ctx.obstacles, self.params, check.dt_s)
        if not check.fallback and gap < 0.0:
            brake = ctx.plan(estimate, "emergency")
            if not brake.fallback and self.settings.futility_weighs_contact:
                # A frontal impact is not worth the few m/s braking in lane takes off where the
                # evasion comes up short by its corner (docs/decisions/0126).
                graze = planned_contact_width_m(check.states, ctx.obstacles, self.params,
                                                check.dt_s)
                frontal = planned_contact_width_m(brake.states, ctx.obstacles, self.params,
                                                  brake.dt_s)
                if graze < frontal:
                    self.planner.restore(evading)
                    self._event(ctx.t_s, EventKind.GRAZE_OVER_STOP, (
                        f"every evasion hits the obstacle, with the most friction too ({gap:.2f} "
                        f"m), across {graze:.2f} m; braking in lane, across {frontal:.2f} m"))
                    self.recoveries.append(Recovery(ctx.t_s, RecoveryOutcome.GRAZE, 1.0, held))
                    return check, top
            if not brake.fallback:
                self._event(
                    ctx.t_s, EventKind.FUTILE_EVASION,
                    f"every evasion hits the obstacle, with the most friction the estimate "
                    f"allows too ({gap:.2f} m); braking in lane")
                self.recoveries.append(Recovery(ctx.t_s, RecoveryOutcome.BRAKING, 0.0, held))
                return brake, estimate
        elif not check.fallback and (self.settings.evade_at_upper_edge if posterior
                                     else self._spends_reserve):
            if posterior:
                # Nothing with less friction passes: the evasion the posterior allows is the one
                # to drive, not a candidate predicted to hit (docs/decisions/0086).
                kind, outcome = EventKind.EVASION_AT_UPPER_EDGE, RecoveryOutcome.UPPER_EDGE
                limit = " and the tires' limit" if self._spends_reserve else ""
                detail = ("every evasion up to the estimates' central value hits the obstacle; "
                          f"evading with μ̂ at the posterior's upper 95 % edge{limit}")
            else:
                # The reserve the polygons keep for tracking is worth more in the lane next to
                # the obstacle than in front of it: the slip control holds the tires at their
                # limit, and braking in lane hits for certain (docs/decisions/0103).
                kind, outcome = EventKind.EVASION_AT_TIRES_LIMIT, RecoveryOutcome.TIRES_LIMIT
                detail = (f"every evasion at λ = {self.utilization_factor:.2f} of μ̂ hits the "
                          "obstacle; evading at the tires' limit (all of μ̂)")
            self._event(ctx.t_s, kind, f"{detail}, which passes it ({gap:.2f} m)")
            self.recoveries.append(Recovery(ctx.t_s, outcome, 1.0, held))
            return check, top
        self.planner.restore(memory)
        return None

    def _obstacle_shortfall_m(
        self, ctx: PlanningContext, mode: PlanningMode
    ) -> Callable[[Plan], float]:
        """How far a plan of this step passes closer to the obstacles than the share of the
        margin it must keep (``obstacle_margin_share``) [m]: 0 for one that keeps it, and
        always 0 unless evading (a stop's gap is the braking's)."""
        margin = self.settings.obstacle_margin_share * self.obstacle_margin_m
        if mode != "evade" or not ctx.obstacles or margin <= 0.0:
            return lambda plan: 0.0

        def shortfall(plan: Plan) -> float:
            return planned_obstacle_shortfall_m(plan.states, ctx.obstacles, self.params,
                                                margin, plan.dt_s)

        return shortfall

    def footprint_violation_m(self, plan: Plan) -> float:
        """How far ``plan``'s predicted footprint leaves the lane [m] (0 inside)."""
        states = plan.states[1:]
        return planned_footprint_violation_m(
            states, self.curvature(states[:, State.s]), self.lane_bounds_m, self.params
        )
