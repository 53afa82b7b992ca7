"""mufusion.planner: traction-adaptive MPC planner and the controller that tracks its plans."""

from mufusion.planner.controller import ControllerGains, TrackingController
from mufusion.planner.ocp import CostWeights, PlannerConfig, PlannerObstacle
from mufusion.planner.planner import Plan, TractionAdaptivePlanner
from mufusion.planner.sampling import SamplingConfig

__all__ = [
    "ControllerGains",
    "CostWeights",
    "Plan",
    "PlannerConfig",
    "PlannerObstacle",
    "SamplingConfig",
    "TrackingController",
    "TractionAdaptivePlanner",
]
