"""Typed records with neutral defaults, for tests that craft logs by hand.

Every field has a default here, so a test states only the values it is about; the records
themselves (``mufusion.sim.records``) keep every field required.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from mufusion.sim.records import (
    EstimateGrid,
    LoopRatesMeta,
    PlannerSettings,
    PlanningStep,
    PlanStages,
    RoadTrace,
    RunMeta,
    Tick,
    VehicleGeometry,
)


def _defaults(record_type: type) -> dict[str, Any]:
    values: dict[str, Any] = {}
    for f in dataclasses.fields(record_type):
        kind = str(f.type)
        values[f.name] = (
            False if kind == "bool" else "plan" if kind == "str" else 0 if kind == "int" else 0.0
        )
    return values


def tick(**values: Any) -> Tick:
    """A controller tick: zeros, no flags, NaN clearance, unless given."""
    base = {**_defaults(Tick), "clearance_m": math.nan, "lane_margin_m": 0.45,
            "road_margin_m": 2.2}
    return Tick(**{**base, **values})


def ticks(n: int, dt_s: float = 0.02, **columns: Any) -> list[Tick]:
    """``n`` ticks at ``dt_s``; each keyword is a scalar or an array of length ``n``."""
    arrays = {k: np.broadcast_to(v, (n,)) for k, v in columns.items()}
    return [
        tick(t_s=i * dt_s, **{k: v[i].item() for k, v in arrays.items()}) for i in range(n)
    ]


def planning_step(**values: Any) -> PlanningStep:
    """A successful planning step, unless told otherwise."""
    base = {**_defaults(PlanningStep), "mode": "cruise", "ok": True, "local_mu": math.nan}
    return PlanningStep(**{**base, **values})


def plan_stages(step: int, t_s: float, n: int = 4, **arrays: Any) -> PlanStages:
    """A plan of ``n`` stages; each keyword is a scalar or an array of length ``n``."""
    fields = [f.name for f in dataclasses.fields(PlanStages) if f.name not in ("step", "t_s")]
    values = {name: np.zeros(n) for name in fields}
    values["k"] = np.arange(n)
    values.update({k: np.broadcast_to(np.asarray(v, dtype=float), (n,)) for k, v in arrays.items()})
    return PlanStages(step=step, t_s=t_s, **values)


def estimate_grid(step: int, t_s: float, mu_hat: float, mu_true: float,
                  grid: np.ndarray | None = None) -> EstimateGrid:
    """A flat estimate over the grid ahead (no posterior, no fusion data)."""
    s = np.arange(0.0, 51.0) if grid is None else grid
    nan = np.full(s.size, np.nan)
    return EstimateGrid(step=step, t_s=t_s, s_ahead_m=s, s_m=s, mu_true=np.full(s.size, mu_true),
                        mu_hat=np.full(s.size, mu_hat), mean=nan, std=nan, lower=nan,
                        data_mu=nan, data_margin=nan)


def run_meta(**values: Any) -> RunMeta:
    """Metadata of a straight 200 m road, a truck-sized vehicle, configuration F."""
    s = np.arange(0.0, 200.0, 0.5)
    zeros = np.zeros_like(s).tolist()
    base: dict[str, Any] = dict(
        scenario_name="turn",
        configuration="F",
        seed=0,
        scenario_config={},
        vehicle=VehicleGeometry(name="truck", length_m=6.28, width_m=2.6, wheelbase_m=3.4,
                                cog_to_front_axle_m=1.2, cog_to_rear_axle_m=2.2),
        road=RoadTrace(s_m=s.tolist(), x_m=s.tolist(), y_m=zeros, psi_rad=zeros,
                       curvature_1pm=zeros, mu=np.ones_like(s).tolist(), lane_width_m=3.5),
        obstacles=[],
        planner=PlannerSettings(horizon_steps=40, dt_s=0.1, utilization_factor=0.9,
                                polygon_sides=12, obstacle_margin_m=0.5, lane_d_min_m=-0.35,
                                lane_d_max_m=0.35, backend="acados", use_sampling=True),
        rates=LoopRatesMeta(plant_hz=200.0, controller_hz=50.0, planner_hz=10.0),
        start_s_m=0.0,
        start_heading_rad=0.0,
        comparison_time_s=0.0,
        duration_s=10.0,
    )
    return RunMeta(**{**base, **values})


def straight_plan(d_end_m: float, *, n: int = 20, length_m: float = 20.0, speed_mps: float = 10.0,
                  mode: str = "cruise") -> Any:
    """A solved straight plan of ``n`` stages over ``length_m`` at ``speed_mps`` whose reference
    point drifts linearly to ``d_end_m`` off the lane centre (no forces)."""
    from mufusion.planner import Plan
    from mufusion.vehicle.planner_model import State

    states = np.zeros((n + 1, 6))
    states[:, State.s] = np.linspace(0.0, length_m, n + 1)
    states[:, State.d] = np.linspace(0.0, d_end_m, n + 1)
    states[:, State.vx] = speed_mps
    zeros = np.zeros(n)
    return Plan(0.0, states, np.zeros((n, 3)), zeros, zeros, zeros, zeros, zeros, zeros,
                status=0, ok=True, fallback=False, solve_time_s=0.0, mode=mode)
