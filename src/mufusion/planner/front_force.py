"""The front lateral force as an OCP state whose rate the steering bounds (beyond the paper).

The planner plans tire forces (TAMP). A force input may jump from one stage to the next, which a
steering actuator cannot follow: at the truck's limit the plans reverse the front force between
the polygon's bounds from one stage to the next (+38, +38, +12, −38, −38 kN on a straight at
11 m/s), the next plan starts from a state the last one did not predict, and the loop weaves
(docs/decisions/0011, "Tracking at the limit"). With ``PlannerConfig.steering_rate_limit`` the
OCP's state is the planner's six states plus ``F_yf``, and the input's ``Input.fyf`` slot is that
force's rate, bounded by :func:`~mufusion.vehicle.planner_model.front_force_rate_limit_n_per_s`.
The backends take and return the planner's ``(N+1, 6)`` states and ``(N, 3)`` tire forces:
:mod:`mufusion.planner.ocp_state` lays out the OCP's state and translates at the boundary, so
nothing outside the backends sees the augmented layout.
"""

from __future__ import annotations

from mufusion.planner.ocp import PlannerConfig
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import front_force_rate_limit_n_per_s


def front_force_rate_bound_n_per_s(params: VehicleParams, config: PlannerConfig) -> float:
    """Bound on ``|dF_yf/dt|`` in the plans [N/s] (the secant stiffness at the utilisation)."""
    return front_force_rate_limit_n_per_s(params, config.utilization_factor)
