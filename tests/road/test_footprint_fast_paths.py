"""The footprint checks' plain-float paths answer exactly what the general ones answer."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.road import Obstacle, obstacle_active, obstacle_active_at
from mufusion.road.geometry import (
    _penetration_scalar,
    _point_segment_distance_scalar,
    rectangle_corner_points,
    signed_clearance_points,
)


def _reference(corners_a, corners_b) -> float:
    """The straightforward formulation: every corner against every edge, one call each."""
    penetration = _penetration_scalar(corners_a, corners_b)
    if penetration > 0.0:
        return -penetration
    distance = math.inf
    for points, poly in ((corners_a, corners_b), (corners_b, corners_a)):
        for k in range(len(poly)):
            a, b = poly[k], poly[(k + 1) % len(poly)]
            for p in points:
                distance = min(distance, _point_segment_distance_scalar(p, a, b))
    return distance


_coord = st.floats(-60.0, 60.0)
_heading = st.floats(-7.0, 7.0)
_size = st.floats(0.05, 20.0)


@settings(max_examples=400, deadline=None)
@given(ax=_coord, ay=_coord, ah=_heading, al=_size, aw=_size,
       bx=_coord, by=_coord, bh=_heading, bl=_size, bw=_size)
def test_clearance_is_bitwise_the_reference(ax, ay, ah, al, aw, bx, by, bh, bl, bw) -> None:
    a = rectangle_corner_points(ax, ay, ah, al, aw)
    b = rectangle_corner_points(bx, by, bh, bl, bw)
    got, expected = signed_clearance_points(a, b), _reference(a, b)
    assert got == expected or (math.isnan(got) and math.isnan(expected))


def test_clearance_with_a_nan_corner_matches_the_reference() -> None:
    a = rectangle_corner_points(0.0, 0.0, 0.0, 4.0, 2.0)
    b = list(rectangle_corner_points(8.0, 1.0, 0.3, 4.0, 2.0))
    b[2] = (math.nan, b[2][1])
    got, expected = signed_clearance_points(a, b), _reference(a, b)
    assert got == expected or (math.isnan(got) and math.isnan(expected))


_maybe = st.one_of(st.none(), st.floats(-50.0, 200.0))
_value = st.one_of(st.floats(-50.0, 200.0), st.just(math.nan))


@settings(max_examples=300, deadline=None)
@given(appear_s=_maybe, appear_t=_maybe, ego_s=_value, t=_value)
def test_obstacle_active_at_is_obstacle_active(appear_s, appear_t, ego_s, t) -> None:
    obstacle = Obstacle(100.0, 0.0, 2.0, 2.0, appear_at_ego_s_m=appear_s, appear_at_time_s=appear_t)
    got = obstacle_active_at(obstacle, ego_s, t)
    assert type(got) is bool
    assert got == bool(obstacle_active(obstacle, ego_s, t))
