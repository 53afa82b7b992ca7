"""The loop's side of the planner: one call with the estimate on its grid, and the stop-or-evade
rule, from the state and the obstacles of one planning step.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner import Plan, PlannerObstacle, UnseenRoad
from mufusion.sim.components import Planner, PlanningMode
from mufusion.sim.events import EventKind, EventSink
from mufusion.sim.obstacle_response import (
    ObstacleResponse,
    follow_speed_mps,
    obstacle_mode,
    stop_within_reach,
    traffic_role,
)
from mufusion.sim.supervisor import PlanningContext
from mufusion.sim.world import World
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State


def road_behind(
    trail: tuple[np.ndarray, np.ndarray], last: tuple[np.ndarray, np.ndarray] | None,
    s_anchor_m: float, length_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The μ̂ of the road behind ``s_anchor_m``, up to ``length_m`` back: ``(s [m], μ̂)``.

    ``trail`` is the same for the previous step, ``last`` that step's estimate ``(s, μ̂)`` on its
    grid (absolute positions): each point keeps the value of the latest estimate that covered it,
    the one made when the centre of gravity was last behind it.

    Examples
    --------
    >>> trail = (np.array([7.0, 8.0]), np.array([0.3, 0.3]))
    >>> last = (np.array([9.0, 10.0, 11.0, 12.0]), np.array([0.3, 0.3, 0.9, 0.9]))
    >>> s, mu = road_behind(trail, last, 11.5, 4.0)
    >>> s.tolist(), mu.tolist()
    ([8.0, 9.0, 10.0, 11.0], [0.3, 0.3, 0.3, 0.9])
    """
    s, mu = trail
    if last is not None:
        older = s < last[0][0]  # behind where the last estimate started
        passed = last[0] < s_anchor_m
        s = np.concatenate([s[older], last[0][passed]])
        mu = np.concatenate([mu[older], last[1][passed]])
    kept = s >= s_anchor_m - length_m
    return s[kept], mu[kept]


class Planning:
    """Calls the planner for the loop and keeps what carries from one planning step to the next.

    Parameters
    ----------
    planner
        The planner.
    world
        Road (curvature) for the planner.
    params
        Vehicle parameters (for the stop-or-evade rule).
    estimate_grid_m
        Distances ahead at which friction is estimated [m].
    reference_speed_mps
        Cruise speed the planner tracks.
    lane_bounds_m
        ``(d_min, d_max)`` the planner's reference point must stay within.
    obstacle_response
        The stop-or-evade rule's settings.
    emergency_on_obstacle
        Stop (mode ``emergency``) whenever an obstacle is active, instead of the rule.
    event
        Where to report that the planner ignores what the estimate declares beyond its grid
        (None: nowhere).
    """

    def __init__(
        self,
        planner: Planner,
        world: World,
        params: VehicleParams,
        estimate_grid_m: np.ndarray,
        reference_speed_mps: float,
        lane_bounds_m: tuple[float, float],
        obstacle_response: ObstacleResponse,
        emergency_on_obstacle: bool,
        event: EventSink | None = None,
    ) -> None:
        self.planner = planner
        self._event = event
        self._takes_unseen = _takes_keyword(planner.step, "unseen_road")
        self._told_unseen_ignored = False
        self.world = world
        self.params = params
        self.grid_m = estimate_grid_m
        self.reference_speed_mps = reference_speed_mps
        self.lane_bounds_m = lane_bounds_m
        self.obstacle_response = obstacle_response
        self.emergency_on_obstacle = emergency_on_obstacle
        self.last_mode: PlanningMode = "cruise"
        """The mode chosen at the last planning step."""
        self.front_force_n: float | None = None
        """The front axle's body-frame lateral force of the last plant step: each plan's force
        state starts from it (None before the first step: the warm-up plans start from theirs)."""
        self.longitudinal_forces_n: tuple[float, float] | None = None
        """The front and rear longitudinal forces the wheel torques deliver now: each plan's
        longitudinal force states start from them (planner/ocp_state.py)."""
        empty = np.empty(0)
        self._behind: tuple[np.ndarray, np.ndarray] = (empty, empty)
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    def drive_on(self, s_ego_m: float, estimate: FrictionEstimate) -> None:
        """Once per planning step, with the estimate the step plans with: the road the vehicle
        has passed keeps the μ̂ it had (:func:`road_behind`, the vehicle's length back).

        An estimate starts under the centre of gravity, but the rear axle is l_r behind it: the
        speed reference's μ̂ under the axles (planner.under_axles.lowest_under_axles) saw the
        CoG's μ̂ there, so after a rise the truck drove its rear axle, still on ice, at the high
        friction's pace (docs/decisions/0072).
        """
        self._behind = road_behind(self._behind, self._last, s_ego_m, self.params.length_m)
        self._last = (s_ego_m + self.grid_m, np.asarray(estimate.mu_hat, dtype=float))

    def context(
        self, t_s: float, xf: np.ndarray, obstacles: Sequence[PlannerObstacle], minimal_risk: bool
    ) -> PlanningContext:
        """What the supervisors see of the planning step at ``t_s`` from ``xf``."""
        s_ego = float(xf[State.s])
        return PlanningContext(
            t_s, xf, obstacles, minimal_risk, self.last_mode,
            lambda estimate, mode: self.plan(xf, t_s, s_ego, estimate, obstacles, mode),
            lambda estimate: self.mode(obstacles, xf, estimate),
            lambda estimate: stop_within_reach(
                obstacles, xf, self.grid_m, estimate.mu_hat, self.params,
                self.obstacle_response, braking=self.last_mode == "emergency"),
        )

    def mode(
        self, obstacles: Sequence[PlannerObstacle], xf: np.ndarray, estimate: FrictionEstimate
    ) -> PlanningMode:
        """The stop-or-evade rule's mode (braking on if the last step braked)."""
        if obstacles and self.emergency_on_obstacle:
            return "emergency"
        return obstacle_mode(
            obstacles, xf, self.grid_m, estimate.mu_hat, self.lane_bounds_m,
            self.params, self.obstacle_response, braking=self.last_mode == "emergency",
        )

    def warm_up(
        self, xf: np.ndarray, estimate: FrictionEstimate, steps: int, planner_hz: float
    ) -> None:
        """``steps`` plans at ``xf`` before the clock starts, without obstacles: a warm start."""
        s_ego = float(xf[State.s])
        for k in range(steps):
            self.plan(xf, -(steps - k) / planner_hz, s_ego, estimate, [], "cruise")

    def plan(
        self,
        xf: np.ndarray,
        t: float,
        s_anchor_m: float,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
        mode: PlanningMode,
    ) -> Plan:
        """One planner step with ``estimate``'s μ̂ on its grid ahead of ``s_anchor_m``.

        Behind a lead vehicle the cruise speed is capped by
        :func:`~mufusion.sim.obstacle_response.follow_speed_mps`; while cruising (the lead is
        followed, docs/decisions/0058) the lead is not one of the obstacles the corridor passes:
        the plan stays behind it, as a stop stays in front of an obstacle.
        """
        mu_hat_grid = np.asarray(estimate.mu_hat, dtype=float)
        reference_speed_mps = self.reference_speed_mps
        if any(o.speed_mps > 0.0 for o in obstacles):
            reference_speed_mps = min(reference_speed_mps, follow_speed_mps(
                obstacles, xf, self.grid_m, mu_hat_grid, self.params, self.obstacle_response))
            if mode == "cruise":
                obstacles = [o for o in obstacles if o.speed_mps <= 0.0 or traffic_role(
                    o, xf, self.grid_m, mu_hat_grid, self.params, self.obstacle_response)
                    != "lead"]

        # Behind the centre of gravity, the road passed (drive_on); beyond the camera's range
        # the last estimate is held (TAMP framework).
        behind_s, behind_mu = self._behind
        passed = behind_s < s_anchor_m
        profile_s = np.concatenate([behind_s[passed], s_anchor_m + self.grid_m])
        profile_mu = np.concatenate([behind_mu[passed], mu_hat_grid])

        def mu_hat_of_s(s: np.ndarray) -> np.ndarray:
            return np.interp(np.asarray(s, dtype=float), profile_s, profile_mu)

        beyond = {}
        if estimate.unseen_mu is not None:
            if self._takes_unseen:
                beyond["unseen_road"] = UnseenRoad(s_anchor_m + float(self.grid_m[-1]),
                                                   estimate.unseen_mu)
            elif not self._told_unseen_ignored and self._event is not None:
                self._told_unseen_ignored = True
                self._event(t, EventKind.UNSEEN_ROAD_IGNORED,
                            f"the estimate declares μ {estimate.unseen_mu:g} possible beyond its "
                            "grid; the planner's step takes no unseen_road")
        return self.planner.step(
            xf,
            t,
            curvature_of_s=self.world.curvature,
            mu_hat_of_s=mu_hat_of_s,
            obstacles=obstacles,
            mode=mode,
            reference_speed_mps=reference_speed_mps,
            reference_d_m=0.0,
            lane_d_min_m=self.lane_bounds_m[0],
            lane_d_max_m=self.lane_bounds_m[1],
            front_force_n=self.front_force_n,
            longitudinal_forces_n=self.longitudinal_forces_n,
            **beyond,
        )


def _takes_keyword(method: Callable[..., object], name: str) -> bool:
    """Whether ``method`` accepts the keyword ``name`` (by name or through ``**kwargs``); a
    plug-in planner written against an older protocol may not."""
    try:
        parameters = inspect.signature(method).parameters.values()
    except (TypeError, ValueError):  # no signature to read (a C callable): try it
        return True
    return any(p.name == name or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)
