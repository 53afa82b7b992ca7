"""The sections of a ``road`` scenario file (``[path]``, ``[lanes]``, ``[friction]``,
``[[obstacles]]``): one validated (pydantic) model each, with the checks a section can make on
its own (ranges, zero lengths, overlapping friction zones). The checks that need the whole
scenario (the path against the vehicle, obstacles against the lanes) are
:mod:`mufusion.scenarios.road_kind`. Schema: docs/scenarios.md, "The road kind".
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from mufusion.road import FrictionMap, Obstacle, PathSegment, ReferencePath
from mufusion.road.polyline import DEFAULT_STEP_M, path_from_polyline
from mufusion.scenarios.sections import Friction, NonNegFloat, PositiveFloat, _Strict

FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
Curvature = Annotated[float, Field(ge=-1.0, le=1.0, allow_inf_nan=False)]


class StraightSegment(_Strict):
    """A straight of ``length_m`` [m]."""

    kind: Literal["straight"]
    length_m: Annotated[float, Field(gt=0.0, le=5000.0, allow_inf_nan=False)]

    def segment(self) -> PathSegment:
        return PathSegment.straight(self.length_m)


class ArcSegment(_Strict):
    """A circular arc of ``radius_m`` [m] turning by ``angle_rad`` (left +, right −)."""

    kind: Literal["arc"]
    radius_m: Annotated[float, Field(gt=0.0, le=10000.0, allow_inf_nan=False)]
    angle_rad: Annotated[float, Field(ge=-2.0 * math.pi, le=2.0 * math.pi, allow_inf_nan=False)]

    @model_validator(mode="after")
    def _turns(self) -> ArcSegment:
        if self.angle_rad == 0.0:
            raise ValueError("angle_rad must not be 0 (an arc of zero length; left +, right −)")
        return self

    def segment(self) -> PathSegment:
        return PathSegment.arc(self.radius_m, self.angle_rad)


class ClothoidSegment(_Strict):
    """A clothoid of ``length_m`` [m] whose curvature runs linearly from start to end [1/m]."""

    kind: Literal["clothoid"]
    length_m: Annotated[float, Field(gt=0.0, le=5000.0, allow_inf_nan=False)]
    curvature_start_1pm: Curvature = 0.0
    curvature_end_1pm: Curvature = 0.0

    def segment(self) -> PathSegment:
        return PathSegment.clothoid(self.length_m, self.curvature_start_1pm,
                                    self.curvature_end_1pm)


SegmentConfig = Annotated[
    StraightSegment | ArcSegment | ClothoidSegment, Field(discriminator="kind")
]


class PathConfig(_Strict):
    """The ego lane's centre line: ``segments`` or a polyline ``points_m`` (exactly one).

    Segments start at the origin heading +X; a polyline starts at its (smoothed) first point
    along its tangent and is smoothed into clothoids of ``step_m``
    (:func:`mufusion.road.polyline.path_from_polyline`; ``smoothing_length_m`` None chooses
    the smoothing by cross-validation).
    """

    segments: list[SegmentConfig] | None = None
    points_m: list[tuple[FiniteFloat, FiniteFloat]] | None = None
    smoothing_length_m: Annotated[float, Field(gt=0.0, le=200.0)] | None = None
    step_m: Annotated[float, Field(ge=0.2, le=20.0)] = DEFAULT_STEP_M

    @model_validator(mode="after")
    def _one_source(self) -> PathConfig:
        if (self.segments is None) == (self.points_m is None):
            raise ValueError("give exactly one of segments or points_m")
        if self.segments is not None and not self.segments:
            raise ValueError("segments must hold at least one segment")
        if self.points_m is None and (
                self.smoothing_length_m is not None or "step_m" in self.model_fields_set):
            raise ValueError("smoothing_length_m and step_m apply to points_m only")
        if self.points_m is not None:
            try:
                path_from_polyline(self.points_m, self.smoothing_length_m, self.step_m)
            except ValueError as err:
                raise ValueError(str(err)) from None
        return self

    def build(self) -> ReferencePath:
        """The reference path (the ego lane's centre)."""
        if self.segments is not None:
            return ReferencePath([seg.segment() for seg in self.segments])
        assert self.points_m is not None
        return path_from_polyline(self.points_m, self.smoothing_length_m, self.step_m).path()


class LanesConfig(_Strict):
    """The own lane and the opposing lane to its left (0: a one-way road)."""

    ego_width_m: Annotated[float, Field(ge=2.0, le=6.0)] = 3.5
    opposing_width_m: Annotated[float, Field(ge=0.0, le=6.0)] = 3.5
    drivable: Literal["ego_lane", "road"] = "ego_lane"
    """Where the planner may drive: its own lane, or the whole road (to evade)."""

    @model_validator(mode="after")
    def _opposing(self) -> LanesConfig:
        if 0.0 < self.opposing_width_m < 2.0:
            raise ValueError(f"opposing_width_m must be 0 (no opposing lane) or in [2, 6] m, "
                             f"got {self.opposing_width_m}")
        return self


class FrictionZone(_Strict):
    """μ on ``[start_m, end_m)`` of the path (no ``end_m``: to the path's end and beyond, where
    it runs on straight); ``mu_opposing``: the opposing lane's (split μ)."""

    start_m: NonNegFloat
    end_m: PositiveFloat | None = None
    mu: Friction
    mu_opposing: Friction | None = None

    @model_validator(mode="after")
    def _ordered(self) -> FrictionZone:
        if self.end_m is not None and self.end_m <= self.start_m:
            raise ValueError(f"end_m must exceed start_m = {self.start_m} m, got {self.end_m}")
        return self


class RoadFriction(_Strict):
    """μ everywhere (``mu``) but in the zones."""

    mu: Friction = 1.0
    zones: list[FrictionZone] = Field(default_factory=list)

    @model_validator(mode="after")
    def _apart(self) -> RoadFriction:
        for i in range(1, len(self.zones)):
            before, zone = self.zones[i - 1], self.zones[i]
            if before.end_m is None:
                raise ValueError(f"zones.{i - 1}.end_m is needed: a zone follows it (without "
                                 "end_m a zone reaches the path's end)")
            if zone.start_m < before.end_m:
                raise ValueError(
                    f"zones.{i}.start_m must be at or after zones.{i - 1}.end_m = "
                    f"{before.end_m} m (zones in order along the path, not overlapping), "
                    f"got {zone.start_m}")
        return self

    def build(self, ego_lane_width_m: float, path_length_m: float) -> FrictionMap:
        """The true friction map (split μ on the lane line ``d = ego_lane_width_m / 2``); a
        zone that reaches the path's end holds beyond it (where the path runs on straight)."""
        starts, mu, opposing = [0.0], [self.mu], [self.mu]
        for zone in self.zones:
            if zone.start_m == starts[-1]:  # a zone at the path's start or right after another
                mu[-1], opposing[-1] = zone.mu, zone.mu_opposing or zone.mu
            else:
                starts.append(zone.start_m)
                mu.append(zone.mu)
                opposing.append(zone.mu if zone.mu_opposing is None else zone.mu_opposing)
            if zone.end_m is None or zone.end_m >= path_length_m:
                break
            starts.append(zone.end_m)
            mu.append(self.mu)
            opposing.append(self.mu)
        split = any(zone.mu_opposing is not None for zone in self.zones)
        return FrictionMap(tuple(starts), tuple(mu), tuple(opposing) if split else None,
                           lane_width_m=ego_lane_width_m)


class RoadObstacleConfig(_Strict):
    """An obstacle on the road: centre at ``(s_m, d_m)`` at time 0, moving at ``speed_mps``."""

    s_m: NonNegFloat
    d_m: Annotated[float, Field(ge=-10.0, le=20.0, allow_inf_nan=False)] = 0.0
    length_m: Annotated[float, Field(gt=0.0, le=30.0)] = 4.5
    width_m: Annotated[float, Field(gt=0.0, le=5.0)] = 1.8
    speed_mps: Annotated[float, Field(ge=-40.0, le=40.0, allow_inf_nan=False)] = 0.0
    appear_at_time_s: NonNegFloat | None = None
    """Pops up at this time [s]."""
    appear_ahead_m: Annotated[float, Field(gt=0.0, le=500.0)] | None = None
    """Pops up when the ego's front is this far before the obstacle's centre [m] (as the
    ``popup`` kind's ``distance_m``)."""

    def build(self, cog_to_body_front_m: float) -> Obstacle:
        """The road's obstacle; ``appear_ahead_m`` becomes the ego CoG progress it appears at."""
        at_ego = None if self.appear_ahead_m is None else (
            self.s_m - self.appear_ahead_m - cog_to_body_front_m)
        return Obstacle(
            s_m=self.s_m, d_m=self.d_m, length_m=self.length_m, width_m=self.width_m,
            appear_at_ego_s_m=at_ego, appear_at_time_s=self.appear_at_time_s,
            speed_mps=self.speed_mps,
        )
