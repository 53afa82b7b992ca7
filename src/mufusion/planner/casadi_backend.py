"""Reference backend: the same OCP solved to convergence by CasADi + IPOPT (not yet implemented)."""

from __future__ import annotations

from mufusion.planner.ocp import PlannerConfig
from mufusion.vehicle.params import VehicleParams


class CasadiBackend:
    """Placeholder: raises on solve, so the planner reports a failed step and keeps its plan."""

    def __init__(self, params: VehicleParams, config: PlannerConfig) -> None:
        self.params, self.config = params, config

    def solve(self, *args, **kwargs):
        raise NotImplementedError("the CasADi reference backend is not implemented yet")
