"""The interface of the loop's supervisory behaviours: one planning step's hooks and the command's.

At each planning step the loop asks its supervisors, in order, to choose the planner's mode and
the estimate to plan with (:meth:`Supervisor.choose_mode`), to adjust the estimate the first plan
is made with (:meth:`Supervisor.adjust_inputs`) and to review that plan, planning again where it
must (:meth:`Supervisor.review`); at each controller tick, to shape the controller's command
(:meth:`Supervisor.shape`). Each supervisor owns its state and reports what it does as events;
a hook it does not need passes its input through. The minimal-risk manoeuvre, which overrides the
planner and the controller alike, is the loop's own
(:class:`~mufusion.sim.minimal_risk.MinimalRisk`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner import Plan, PlannerObstacle
from mufusion.sim.components import PlanningMode
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.planner_model import State


@dataclass(frozen=True)
class PlanningContext:
    """What a supervisor sees of one planning step.

    ``plan(estimate, mode)`` makes one planner step from this state against these obstacles (the
    planner's warm start moves on with each call); ``mode_of(estimate)`` is the stop-or-evade
    rule (:func:`~mufusion.sim.obstacle_response.obstacle_mode`) with that estimate;
    ``stop_granted(estimate)`` whether that estimate grants the stop in front of every static
    obstacle in the path (:func:`~mufusion.sim.obstacle_response.stop_within_reach`: the rule
    also stops where the road is blocked, granted or not).
    """

    t_s: float
    xf: np.ndarray
    """The Frenet state ``(s, d, Δψ, ψ̇, v_x, v_y)``."""
    obstacles: Sequence[PlannerObstacle]
    minimal_risk: bool
    """The minimal-risk manoeuvre is under way (the supervisors stand aside)."""
    last_mode: PlanningMode
    """The mode chosen at the previous planning step."""
    plan: Callable[[FrictionEstimate, PlanningMode], Plan]
    mode_of: Callable[[FrictionEstimate], PlanningMode]
    stop_granted: Callable[[FrictionEstimate], bool] = lambda estimate: True

    @property
    def s_m(self) -> float:
        return float(self.xf[State.s])

    @property
    def speed_mps(self) -> float:
        return float(np.hypot(self.xf[State.vx], self.xf[State.vy]))


class Supervisor:
    """A supervisory behaviour of the loop; every hook passes its input through by default."""

    def choose_mode(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate
    ) -> tuple[PlanningMode, FrictionEstimate]:
        """The mode to plan in and the estimate to plan with, given the rule's (or the supervisor
        before's) choice."""
        return mode, estimate

    def adjust_inputs(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate
    ) -> FrictionEstimate:
        """The estimate the step's first plan is made with."""
        return estimate

    def review(
        self, ctx: PlanningContext, mode: PlanningMode, estimate: FrictionEstimate, plan: Plan
    ) -> tuple[Plan, FrictionEstimate]:
        """The plan to adopt and the estimate it was made with (``estimate`` is unadjusted)."""
        return plan, estimate

    def shape(self, t_s: float, xf: np.ndarray, command: ActuatorCommand) -> ActuatorCommand:
        """The command sent to the actuators instead of the controller's ``command``."""
        return command

