"""mufusion.road: reference path, lanes, true friction map and obstacles."""

from mufusion.road.friction import DEFAULT_LANE_WIDTH_M, FrictionMap
from mufusion.road.geometry import (
    rectangle_corner_points,
    rectangle_corners,
    rectangles_overlap,
    signed_clearance_m,
    signed_clearance_points,
)
from mufusion.road.lanes import (
    LaneMargins,
    entered_opposing_lane,
    footprint_corner_offsets_m,
    footprint_lane_margins,
    lane_excursion_m,
    lane_margin_m,
    left_ego_lane,
    left_road,
    opposing_lane_depth_m,
    road_margin_m,
)
from mufusion.road.obstacles import (
    Obstacle,
    footprint_clearance_m,
    obstacle_active,
    obstacle_active_at,
    obstacle_corners,
)
from mufusion.road.path import PathSegment, ReferencePath
from mufusion.road.road import Road, straight_road, turn_road
from mufusion.road.tracking import FrictionTracker, PointTracker

__all__ = [
    "DEFAULT_LANE_WIDTH_M",
    "FrictionMap",
    "FrictionTracker",
    "LaneMargins",
    "Obstacle",
    "PathSegment",
    "PointTracker",
    "ReferencePath",
    "Road",
    "entered_opposing_lane",
    "footprint_clearance_m",
    "footprint_corner_offsets_m",
    "footprint_lane_margins",
    "lane_excursion_m",
    "lane_margin_m",
    "left_ego_lane",
    "left_road",
    "obstacle_active",
    "obstacle_active_at",
    "obstacle_corners",
    "opposing_lane_depth_m",
    "rectangle_corner_points",
    "rectangle_corners",
    "rectangles_overlap",
    "road_margin_m",
    "signed_clearance_m",
    "signed_clearance_points",
    "straight_road",
    "turn_road",
]
