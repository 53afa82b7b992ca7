"""When the loop enters the minimal-risk manoeuvre: :class:`MinimalRisk`.

The manoeuvre itself, its planned roll-out and the command the loop applies while it cannot
plan (:func:`~mufusion.planner.minimal_risk.minimal_risk_command`), is in
:mod:`mufusion.planner.minimal_risk`.
"""

from __future__ import annotations

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner.config import PlannerMode
from mufusion.planner.minimal_risk import minimal_risk_command
from mufusion.planner.safety import SafetySettings
from mufusion.sim.events import EventKind, EventSink
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams

MINIMAL_RISK_MODE: PlannerMode = "minimal_risk"
"""The planner's mode during the minimal-risk manoeuvre: brake to a stop in lane."""


class MinimalRisk:
    """When the loop enters the minimal-risk manoeuvre, and its command while it cannot plan.

    After ``safety.max_consecutive_fallbacks`` planning steps in a row without a usable plan
    (not counting those at rest in front of an obstacle,
    :data:`~mufusion.planner.minimal_risk.AT_REST_MPS`), or at once when a component raises
    (:meth:`enter`), the manoeuvre starts; it is latched until the end of the run. The planner
    then plans a stop in lane (:data:`MINIMAL_RISK_MODE`); while it cannot, the loop brakes in
    lane itself (:meth:`command`).

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
        # Stopped for an obstacle, the manoeuvre's stop is done: a failed plan (at rest with the
        # brakes on the package's OCP is infeasible: it holds such a stop without a solve; a
        # plug-in may not)
        # keeps the vehicle held and starts nothing.
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
