"""mufusion.road: reference path, lanes, true friction map and obstacles."""

from mufusion.road.friction import DEFAULT_LANE_WIDTH_M, FrictionMap
from mufusion.road.geometry import rectangle_corners, signed_clearance_m
from mufusion.road.lanes import (
    entered_opposing_lane,
    footprint_corner_offsets_m,
    left_ego_lane,
    left_road,
)
from mufusion.road.obstacles import (
    Obstacle,
    footprint_clearance_m,
    obstacle_active,
    obstacle_corners,
)
from mufusion.road.path import PathSegment, ReferencePath
from mufusion.road.road import Road, straight_road, turn_road

__all__ = [
    "DEFAULT_LANE_WIDTH_M",
    "FrictionMap",
    "Obstacle",
    "PathSegment",
    "ReferencePath",
    "Road",
    "entered_opposing_lane",
    "footprint_clearance_m",
    "footprint_corner_offsets_m",
    "left_ego_lane",
    "left_road",
    "obstacle_active",
    "obstacle_corners",
    "rectangle_corners",
    "signed_clearance_m",
    "straight_road",
    "turn_road",
]
