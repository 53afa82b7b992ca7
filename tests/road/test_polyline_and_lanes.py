"""A polyline smoothed into clothoids keeps the curve it samples; an opposing lane of its own
width moves the road's left edge (0: one-way) and nothing else."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mufusion.road import FrictionMap, PathSegment, ReferencePath, Road, footprint_lane_margins
from mufusion.road.lanes import road_margin_m
from mufusion.road.polyline import path_from_polyline


def _arc_with_straights(radius_m: float, spacing_m: float = 1.0) -> np.ndarray:
    """Points every ``spacing_m`` along 30 m straight, a 90° left arc and 30 m straight (the
    arc entered and left without a clothoid: the hardest case for a smoothing spline)."""
    path = ReferencePath([PathSegment.straight(30.0), PathSegment.arc(radius_m, math.pi / 2),
                          PathSegment.straight(30.0)])
    s = np.arange(0.0, path.length_m + 1e-9, spacing_m)
    return np.column_stack(path.position(s))


def _mid_arc_radii(points: np.ndarray, radius_m: float, **kwargs) -> np.ndarray:
    smoothed = path_from_polyline(points, **kwargs)
    path = smoothed.path()
    # The middle half of the arc (well away from the spline's response to the curvature jumps).
    s = 30.0 + radius_m * math.pi / 2 * np.linspace(0.25, 0.75, 50)
    return 1.0 / np.abs(path.curvature(s))


def test_a_sampled_arc_gives_its_radius_within_one_percent() -> None:
    radius = 40.0
    radii = _mid_arc_radii(_arc_with_straights(radius), radius)
    assert np.all(np.abs(radii / radius - 1.0) < 0.01), radii.min()


def test_a_noisy_arc_smoothed_over_5_m_keeps_its_radius_within_5_percent() -> None:
    radius = 40.0
    rng = np.random.default_rng(3)
    noisy = _arc_with_straights(radius, 2.0) + rng.normal(0.0, 0.05, size=(1, 2))
    noisy = noisy + rng.normal(0.0, 0.05, size=noisy.shape)
    radii = _mid_arc_radii(noisy, radius, smoothing_length_m=5.0)
    assert abs(float(np.median(radii)) / radius - 1.0) < 0.05
    # Unsmoothed, the same noise is curvature: the radius scatters far more.
    rough = _mid_arc_radii(noisy, radius, smoothing_length_m=0.5)
    assert np.ptp(1.0 / rough) > 3.0 * np.ptp(1.0 / radii)


def test_the_smoothed_path_starts_and_ends_where_the_polyline_does() -> None:
    points = _arc_with_straights(25.0)
    path = path_from_polyline(points).path()
    assert np.hypot(*(np.array(path.end_xy_m) - points[-1])) < 0.1
    assert abs(path.end_heading_rad - math.pi / 2) < 1e-3
    # The last point lies short of the sampled path's end (points every 1 m).
    assert abs(path.length_m - (points.shape[0] - 1)) < 0.01
    assert all(seg.length_m <= 2.0 + 1e-9 for seg in path.segments)


@pytest.mark.parametrize(
    ("points", "fragment"),
    [
        ([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], "at least 4 points"),
        ([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [2.0, 0.0]], "points_m 1 and 2 coincide"),
        ([[0.0, 0.0], [1.0, 0.0], [2.0, math.nan], [3.0, 0.0]], "finite"),
    ],
)
def test_bad_polylines_are_named(points, fragment) -> None:
    with pytest.raises(ValueError, match=fragment):
        path_from_polyline(points)


def test_the_opposing_width_moves_only_the_road_edge() -> None:
    corners = [2.0, 2.2, 2.0, 2.2]  # 0.45 m into the opposing lane
    two_lanes = footprint_lane_margins(corners, 3.5)
    assert footprint_lane_margins(corners, 3.5, 3.5) == two_lanes
    one_way = footprint_lane_margins(corners, 3.5, 0.0)
    assert one_way.lane_margin_m == two_lanes.lane_margin_m
    assert one_way.opposing_depth_m == two_lanes.opposing_depth_m
    assert two_lanes.road_margin_m == pytest.approx(5.25 - 2.2)
    assert one_way.off_road and one_way.road_margin_m == pytest.approx(1.75 - 2.2)
    assert float(road_margin_m(corners, 3.5, 0.0)) == one_way.road_margin_m
    narrow = footprint_lane_margins(corners, 3.5, 2.5)
    assert narrow.road_margin_m == pytest.approx(4.25 - 2.2)


def test_a_one_way_road_is_left_across_the_lane_line() -> None:
    path = ReferencePath([PathSegment.straight(100.0)])
    one_way = Road(path, 3.5, FrictionMap.uniform(1.0), (), opposing_lane_width_m=0.0)
    two_way = Road(path, 3.5, FrictionMap.uniform(1.0))
    assert one_way.opposing_width_m == 0.0 and two_way.opposing_width_m == 3.5
    # The footprint (4.5 × 1.8) centred 1.2 m left: its left side at 2.1 m.
    assert bool(one_way.left_road(50.0, 1.2, 0.0, 4.5, 1.8))
    assert not bool(two_way.left_road(50.0, 1.2, 0.0, 4.5, 1.8))
    with pytest.raises(ValueError, match="opposing_lane_width_m"):
        Road(path, 3.5, opposing_lane_width_m=-1.0)
