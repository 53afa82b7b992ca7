"""The minimal-risk manoeuvre when no plan can be trusted: brake in lane, steer along it.

:class:`MinimalRisk` holds when the loop enters it; :func:`minimal_risk_command` is its command,
used by the loop once the planner has failed too often, or a component raised, and the planner
cannot plan the stop itself. Deliberately simple (no model, no optimisation): curvature
feed-forward plus lateral and heading feedback for steering; braking with what the friction
circle at a declared share of μ̂ g leaves after the lateral acceleration that following the lane
takes (``v² κ``), split over the axles by their static loads. The vehicle's slip control (ABS)
keeps the wheels rolling if μ̂ over-estimates the road.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner.config import PlannerMode
from mufusion.planner.safety import SafetySettings
from mufusion.sim.events import EventKind, EventSink
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import State


@dataclass(frozen=True)
class LaneKeepingGains:
    """Steering feedback of the manoeuvre (left positive, like the Frenet offset)."""

    lateral_rad_per_m: float = 0.05
    heading_rad_per_rad: float = 0.8


def minimal_risk_command(
    x_frenet: np.ndarray,
    curvature_1pm: float,
    params: VehicleParams,
    mu: float,
    utilization: float,
    gains: LaneKeepingGains | None = None,
) -> ActuatorCommand:
    """Actuator command of the minimal-risk manoeuvre at Frenet state ``x_frenet``.

    Parameters
    ----------
    x_frenet
        ``(s, d, Δψ, ψ̇, v_x, v_y)``.
    curvature_1pm
        Road curvature at the vehicle [1/m].
    params
        Vehicle parameters.
    mu
        Friction assumed for braking [-] (the last usable estimate under the vehicle, or the
        floor).
    utilization
        Share of ``μ g`` the manoeuvre may use [-], in (0, 1]: the lateral acceleration the
        lane's curvature asks at the current speed first, braking with the rest.

    Raises
    ------
    ValueError
        If ``mu`` or ``utilization`` is out of range.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> cmd = minimal_risk_command(np.array([0, 0, 0, 0, 10.0, 0]), 0.0, TRUCK, 0.4, 0.5)
    >>> cmd.steer_rad, cmd.torque_front_nm < 0 and cmd.torque_rear_nm < 0
    (0.0, True)
    """
    if not (np.isfinite(mu) and 0.0 < mu <= 2.0):
        raise ValueError(f"mu must be in (0, 2], got {mu!r}")
    if not 0.0 < utilization <= 1.0:
        raise ValueError(f"utilization must be in (0, 1], got {utilization!r}")
    g = gains or LaneKeepingGains()
    x = np.asarray(x_frenet, dtype=float)
    d = float(x[State.d]) if np.isfinite(x[State.d]) else 0.0
    dpsi = float(x[State.dpsi]) if np.isfinite(x[State.dpsi]) else 0.0
    steer = (
        params.wheelbase_m * curvature_1pm
        - g.lateral_rad_per_m * d
        - g.heading_rad_per_rad * dpsi
    )
    available = utilization * mu * GRAVITY_MPS2
    lateral = float(x[State.vx]) ** 2 * abs(curvature_1pm) if np.isfinite(x[State.vx]) else 0.0
    force = params.mass_kg * math.sqrt(max(available * available - lateral * lateral, 0.0))
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    r = params.wheel_radius_m
    return ActuatorCommand(
        float(steer), -share_front * force * r, -(1.0 - share_front) * force * r
    ).clipped(params)


MINIMAL_RISK_MODE: PlannerMode = "minimal_risk"
"""The planner's mode during the minimal-risk manoeuvre: brake to a stop in lane."""
AT_REST_MPS = 0.1
"""Below this speed [m/s] a vehicle stopping for an obstacle has stopped."""


class MinimalRisk:
    """When the loop enters the minimal-risk manoeuvre, and its command while it cannot plan.

    After ``safety.max_consecutive_fallbacks`` planning steps in a row without a usable plan
    (not counting those at rest in front of an obstacle, :data:`AT_REST_MPS`), or at once when
    a component raises (:meth:`enter`), the manoeuvre starts; it is latched until the end of
    the run. The planner then plans a stop in lane (:data:`MINIMAL_RISK_MODE`); while it cannot,
    the loop brakes in lane itself (:meth:`command`).

    Parameters
    ----------
    safety
        The fallback count, the friction floor and the manoeuvre's share of ``μ g``.
    params
        Vehicle parameters.
    event
        Where the manoeuvre's start is reported.
    """

    def __init__(self, safety: SafetySettings, params: VehicleParams, event: EventSink) -> None:
        self.safety = safety
        self.params = params
        self._event = event
        self.active = False
        self.consecutive_fallbacks = 0
        self.planner_usable = True
        """The last planning step gave a usable plan."""

    def enter(self, t_s: float, why: str) -> None:
        """Start the manoeuvre (once; reported with ``why``)."""
        if not self.active:
            self.active = True
            self._event(t_s, EventKind.MINIMAL_RISK, why)

    def count(self, failed: bool, at_rest_braking: bool) -> None:
        """Count a planning step; ``failed``: it gave no usable plan."""
        self.planner_usable = not failed
        # Stopped for an obstacle, the manoeuvre's stop is done: a failed plan (the model is stiff
        # at rest) keeps the vehicle held and starts nothing.
        self.consecutive_fallbacks = (
            0 if not failed else self.consecutive_fallbacks + (not at_rest_braking)
        )

    def check(self, t_s: float) -> None:
        """Enter the manoeuvre if too many planning steps in a row failed."""
        if self.consecutive_fallbacks >= self.safety.max_consecutive_fallbacks:
            self.enter(t_s, f"{self.consecutive_fallbacks} planning steps in a row "
                            "without a usable plan")

    @property
    def trusts_planner(self) -> bool:
        """The controller may track the plan (not: under way with the planner failing)."""
        return not (self.active and not self.planner_usable)

    def command(
        self, xf: np.ndarray, curvature_1pm: float, estimate: FrictionEstimate
    ) -> ActuatorCommand:
        """Brake in lane with μ̂ under the vehicle (at least the floor) and steer along it."""
        mu_hat = np.asarray(estimate.mu_hat, dtype=float)
        floor = self.safety.mu_floor
        mu = float(mu_hat[0]) if mu_hat.size and np.isfinite(mu_hat[0]) else floor
        return minimal_risk_command(
            xf, curvature_1pm, self.params, min(max(mu, floor), 2.0),
            self.safety.minimal_risk_decel_fraction,
        )
