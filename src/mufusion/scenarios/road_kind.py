"""The ``road`` scenario kind: any road from segments or a polyline, two lanes of their own
widths, friction zones (split μ too) and any number of obstacles (static, popping up by time or
by distance, moving along the path).

:class:`RoadScenario` builds the :class:`~mufusion.road.Road` and checks the whole description
before any run (each error names the key and what is allowed): the path may not cross itself,
no curve may be tighter than the vehicle can steer or than the road's inner edge allows
(:func:`min_radius_m`), the lane must hold the vehicle and the planner's footprint margin,
obstacles must lie on the road and on the path, friction zones on the path, and the path must
reach beyond where the vehicle can get in ``duration_s`` (:func:`required_length_m`). Schema:
docs/scenarios.md, "The road kind".
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from mufusion.road import ReferencePath, Road
from mufusion.scenarios.base import Scenario
from mufusion.scenarios.road_sections import (
    LanesConfig,
    PathConfig,
    RoadFriction,
    RoadObstacleConfig,
)
from mufusion.scenarios.sections import FOOTPRINT_MARGIN_M
from mufusion.vehicle.params import VehicleParams, vehicle_preset

CROSSING_STEP_M = 0.5
"""Spacing of the centre-line samples the self-intersection check compares [m]."""
EDGE_CLEARANCE_M = 1.0
"""A curve's radius must exceed the road's inner edge offset by this much [m] (the edge's own
radius: a smaller one folds the edge over itself)."""
START_ROOM_M = 10.0
"""Road behind the vehicle's start at least [m] (its rear and the estimators' look-back)."""


def min_radius_m(params: VehicleParams, inner_edge_m: float) -> float:
    """Smallest curve radius a road may have [m]: the vehicle's kinematic turning radius
    ``L / tan(δ_max)`` at full steering, and the road's inner edge ``inner_edge_m`` (its offset
    from the centre line on the curve's inside) plus :data:`EDGE_CLEARANCE_M`, the larger.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> round(min_radius_m(TRUCK, 1.75), 2) == round(TRUCK.wheelbase_m / math.tan(0.6), 2)
    True
    """
    return max(params.wheelbase_m / math.tan(params.max_steer_rad), inner_edge_m + EDGE_CLEARANCE_M)


def required_length_m(start_s_m: float, speed_mps: float, duration_s: float,
                      params: VehicleParams) -> float:
    """Shortest path a run needs [m]: the start, the distance at ``speed_mps`` in
    ``duration_s`` and the vehicle's front. The planner's horizon may look beyond the path's
    end: the path runs on straight there (:class:`~mufusion.road.ReferencePath`) with the last
    friction, so a plan stays defined; requiring the horizon too would reject the paper's own
    turn (its 12 s at 12 m/s plus the 4 s horizon overrun its road by 3 m)."""
    return start_s_m + speed_mps * duration_s + params.cog_to_body_front_m


def crossing_m(path: ReferencePath, step_m: float = CROSSING_STEP_M) -> tuple[float, float] | None:
    """Two progresses [m] where the centre line comes within ``step_m`` of itself, away from
    each other along it by more than 4 steps (a crossing or a touch); None if it does not.

    Samples every ``step_m``: a crossing puts two samples of the two strands within a step of
    each other; neighbours along one strand are a step apart too, so pairs closer along the
    path than 4 steps are left out (a curve tighter than ``2 step / π`` would fold onto itself
    there; :func:`min_radius_m` forbids far wider ones).
    """
    from scipy.spatial import cKDTree  # only a road file's check needs it (not at import)

    s = np.linspace(0.0, path.length_m, max(2, math.ceil(path.length_m / step_m) + 1))
    x, y = path.position(s)
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(step_m, output_type="ndarray")
    apart = pairs[np.abs(s[pairs[:, 0]] - s[pairs[:, 1]]) > 4.0 * step_m] if len(pairs) else pairs
    if len(apart) == 0:
        return None
    i, j = sorted(apart[0].tolist())
    return float(s[i]), float(s[j])


class RoadScenario(Scenario):
    """Any road: the path, its lanes, friction zones and obstacles (``docs/scenarios.md``)."""

    name: Literal["road"]
    start_s_m: Annotated[float, Field(ge=START_ROOM_M, le=5000.0)] = 60.0
    """The vehicle's start progress along the path [m] (room behind it)."""
    path: PathConfig
    lanes: LanesConfig = LanesConfig()
    friction: RoadFriction = RoadFriction()
    obstacles: list[RoadObstacleConfig] = Field(default_factory=list)
    emergency_on_obstacle: bool = False
    """Switch the planner to its emergency (stop) mode when an obstacle appears."""

    @model_validator(mode="after")
    def _check_road(self) -> RoadScenario:
        params = vehicle_preset(self.vehicle)
        path = self.path.build()
        self._check_lanes(params)
        self._check_curves(path, params)
        crossing = crossing_m(path)
        if crossing is not None:
            xy = [round(float(v), 2) for v in path.position(crossing[0])]
            raise ValueError(f"path crosses itself: s = {crossing[0]:.1f} m and s = "
                             f"{crossing[1]:.1f} m meet near (x, y) = {xy} m")
        speed = max(self.initial_speed_mps + self.perturbation.speed_mps, self.cruise_speed_mps)
        needed = required_length_m(self.start_s_m, speed, self.duration_s, params)
        if path.length_m < needed:
            raise ValueError(
                f"path is {path.length_m:.1f} m long; the run needs at least {needed:.1f} m "
                f"(start_s_m {self.start_s_m} + {speed} m/s x duration_s {self.duration_s} + the "
                f"vehicle's front): lengthen the path or shorten duration_s")
        self._check_friction(path.length_m)
        self._check_obstacles(path.length_m)
        return self

    def _check_lanes(self, params: VehicleParams) -> None:
        need = params.width_m + 2.0 * FOOTPRINT_MARGIN_M
        if self.lanes.ego_width_m < need:
            raise ValueError(
                f"lanes.ego_width_m must be at least the {params.name}'s width plus the "
                f"planner's footprint margin each side = {need:.2f} m, "
                f"got {self.lanes.ego_width_m}")

    def _check_curves(self, path: ReferencePath, params: VehicleParams) -> None:
        where = "path.segments" if self.path.segments is not None else "path.points_m"
        for i, seg in enumerate(path.segments):
            for kappa in (seg.curvature_start_1pm, seg.curvature_end_1pm):
                if kappa == 0.0:
                    continue
                # The inside of a left curve (κ > 0) is the opposing lane's side.
                inner = 0.5 * self.lanes.ego_width_m + (
                    self.lanes.opposing_width_m if kappa > 0.0 else 0.0)
                limit = min_radius_m(params, inner)
                if 1.0 / abs(kappa) < limit:
                    piece = f"{where}.{i}" if self.path.segments is not None else where
                    raise ValueError(
                        f"{piece}: radius {1.0 / abs(kappa):.2f} m is below the smallest "
                        f"allowed {limit:.2f} m (the {params.name}'s turning radius at full "
                        f"steering, and the road's inner edge {inner:.2f} m off the centre line "
                        f"+ {EDGE_CLEARANCE_M} m)")

    def _check_friction(self, length_m: float) -> None:
        for i, zone in enumerate(self.friction.zones):
            if zone.start_m >= length_m:
                raise ValueError(f"friction.zones.{i}.start_m must be within the path "
                                 f"(< {length_m:.2f} m), got {zone.start_m}")
            if zone.end_m is not None and zone.end_m > length_m:
                raise ValueError(f"friction.zones.{i}.end_m must be within the path "
                                 f"(<= {length_m:.2f} m), got {zone.end_m}")
            if zone.mu_opposing is not None and self.lanes.opposing_width_m == 0.0:
                raise ValueError(f"friction.zones.{i}.mu_opposing needs an opposing lane "
                                 "(lanes.opposing_width_m is 0)")

    def _check_obstacles(self, length_m: float) -> None:
        lo = -0.5 * self.lanes.ego_width_m
        hi = 0.5 * self.lanes.ego_width_m + self.lanes.opposing_width_m
        for i, ob in enumerate(self.obstacles):
            right, left = ob.d_m - 0.5 * ob.width_m, ob.d_m + 0.5 * ob.width_m
            if right < lo or left > hi:
                raise ValueError(
                    f"obstacles.{i}: off the road: it spans d = [{right:.2f}, {left:.2f}] m, "
                    f"the road [{lo:.2f}, {hi:.2f}] m (d_m is its centre, left +)")
            if ob.s_m > length_m:
                raise ValueError(f"obstacles.{i}.s_m must be on the path (<= {length_m:.2f} m), "
                                 f"got {ob.s_m}")
            if ob.appear_at_time_s is not None and ob.appear_at_time_s >= self.duration_s:
                raise ValueError(f"obstacles.{i}.appear_at_time_s must be before duration_s = "
                                 f"{self.duration_s} s, got {ob.appear_at_time_s}")

    def build_road(self, params: VehicleParams) -> Road:
        """The path, its lanes, the friction zones and the obstacles (``appear_ahead_m`` from
        the vehicle's front, as the ``popup`` kind measures)."""
        path = self.path.build()
        opposing = self.lanes.opposing_width_m
        return Road(
            path=path,
            lane_width_m=self.lanes.ego_width_m,
            friction=self.friction.build(self.lanes.ego_width_m, path.length_m),
            obstacles=tuple(ob.build(params.cog_to_body_front_m) for ob in self.obstacles),
            opposing_lane_width_m=None if opposing == self.lanes.ego_width_m else opposing,
        )

    def drivable_d_m(self) -> tuple[float, float]:
        """Where the vehicle may drive: its own lane, or (``lanes.drivable = "road"``) both."""
        half = 0.5 * self.lanes.ego_width_m
        if self.lanes.drivable == "ego_lane":
            return -half, half
        return -half, half + self.lanes.opposing_width_m
