"""mufusion.planner: traction-adaptive MPC planner and the controller that tracks its plans."""

from mufusion.planner.backend import PlannerBackend
from mufusion.planner.config import CostWeights, PlannerConfig, PlannerObstacle, PlausibilityLimits
from mufusion.planner.controller import ControllerGains, TrackingController
from mufusion.planner.plan import FallbackReason, Plan
from mufusion.planner.planner import PlannerMemory, TractionAdaptivePlanner
from mufusion.planner.sampling import SamplingConfig
from mufusion.planner.unseen_road import UnseenRoad

__all__ = [
    "ControllerGains",
    "CostWeights",
    "FallbackReason",
    "Plan",
    "PlannerBackend",
    "PlannerConfig",
    "PlannerMemory",
    "PlannerObstacle",
    "PlausibilityLimits",
    "SamplingConfig",
    "TrackingController",
    "TractionAdaptivePlanner",
    "UnseenRoad",
]
