"""Active friction probing as a supervisor of the loop: when to start, the braking it adds.

What it does and why: :mod:`mufusion.sim.supervision` ("Active friction probing"); the probe's
own state is a :class:`~mufusion.sim.supervision.Prober`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.sim.components import PlanningMode
from mufusion.sim.events import EventKind, EventSink
from mufusion.sim.settings import ProbingSettings
from mufusion.sim.supervision import ProbeEndReason, Prober, RoadBeyond
from mufusion.sim.supervisor import PlanningContext, Supervisor
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State


@dataclass(frozen=True)
class ProbeEnd:
    """How one probe ended."""

    t_s: float
    reason: ProbeEndReason
    speed_lost_mps: float


class Probing(Supervisor):
    """Starts a probe at a planning step when one is due; brakes while it runs.

    Parameters
    ----------
    settings, utilization_factor
        As :class:`~mufusion.sim.supervision.Prober`'s (the probe's own state).
    planning_horizon_s
        How far ahead the planner plans [s]: with ``settings.beyond_camera`` the trigger reads
        the road that far at the current speed, past the estimate's grid.
    params
        Vehicle parameters (mass and axle loads for the braking torques).
    estimate_grid_m
        Distances ahead at which friction is estimated [m].
    curvature
        The road's curvature [1/m] at arc lengths [m].
    event
        Where the probes' starts and ends are reported.
    """

    def __init__(
        self,
        settings: ProbingSettings,
        utilization_factor: float,
        planning_horizon_s: float,
        params: VehicleParams,
        estimate_grid_m: np.ndarray,
        curvature: Callable[[np.ndarray], np.ndarray],
        event: EventSink,
    ) -> None:
        self.settings = settings
        self.prober = Prober(settings, utilization_factor)
        self.planning_horizon_s = planning_horizon_s
        self.params = params
        self.grid_m = estimate_grid_m
        self.curvature = curvature
        self._event = event
        self._local_available = False  # at the last planning step
        self.ends: list[ProbeEnd] = []
        """The probes' ends, in order."""

    @property
    def active(self) -> bool:
        """A probe is running."""
        return self.prober.active

    def choose_mode(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate
    ) -> tuple[PlanningMode, FrictionEstimate]:
        """Start a probe if one is due (the mode and estimate pass through)."""
        self._local_available = estimate.local_available
        if self.prober.active or ctx.minimal_risk:
            return mode, estimate
        s_ego = ctx.s_m
        near = any(o.s_m - s_ego < self.settings.clear_distance_m for o in ctx.obstacles)
        kappa = self.curvature(s_ego + self.grid_m)
        why = self.prober.reason_to_probe(
            ctx.t_s, ctx.speed_mps, estimate, kappa, near,
            lambda: self._beyond(s_ego, ctx.speed_mps, estimate))
        if why is not None:
            self.prober.start(ctx.t_s, ctx.speed_mps)
            self._event(ctx.t_s, EventKind.PROBE_START, why)
        return mode, estimate

    def _beyond(self, s_ego_m: float, speed_mps: float,
                estimate: FrictionEstimate) -> RoadBeyond | None:
        """The road past the grid, each metre up to the first at or past the planner's reach at
        ``speed_mps``, with the friction the estimate declares possible there (its
        ``unseen_mu``; where it declares none, its last value holds, as the planner takes it);
        None where the reach ends inside the grid or ``beyond_camera`` is off."""
        end = float(self.grid_m[-1])
        reach = speed_mps * self.planning_horizon_s
        if not self.settings.beyond_camera or reach <= end:
            return None
        s = np.arange(end + 1.0, reach + 1.0, 1.0)
        mu = (estimate.unseen_mu if estimate.unseen_mu is not None
              else float(np.asarray(estimate.mu_hat, dtype=float)[-1]))
        return RoadBeyond(s, np.asarray(self.curvature(s_ego_m + s), dtype=float),
                          np.full(s.shape, mu))

    def shape(self, t_s: float, xf: np.ndarray, command: ActuatorCommand) -> ActuatorCommand:
        """While probing: the controller's steering, the probe's braking (or harder)."""
        prober = self.prober
        if not prober.active:
            return command
        speed = float(np.hypot(xf[State.vx], xf[State.vy]))
        why = prober.reason_to_stop(t_s, speed, self._local_available)
        if why is not None:
            lost = prober.stop(t_s, speed)
            self.ends.append(ProbeEnd(t_s, why, lost))
            self._event(t_s, EventKind.PROBE_END, f"{why}; {lost:.2f} m/s lost")
            return command
        p = self.params
        force = p.mass_kg * prober.decel_mps2(t_s)
        share_front = p.cog_to_rear_axle_m / p.wheelbase_m
        r = p.wheel_radius_m
        return ActuatorCommand(
            command.steer_rad,
            min(command.torque_front_nm, -share_front * force * r),
            min(command.torque_rear_nm, -(1.0 - share_front) * force * r),
        ).clipped(p)
