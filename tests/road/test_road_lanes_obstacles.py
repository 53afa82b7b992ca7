"""Lanes, friction map, obstacles and clearance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.road import (
    FrictionMap,
    Obstacle,
    footprint_clearance_m,
    footprint_corner_offsets_m,
    obstacle_active,
    rectangle_corners,
    signed_clearance_m,
    straight_road,
    turn_road,
)

LENGTH, WIDTH = 6.28, 2.6


def test_lane_checks_on_a_straight_road() -> None:
    road = straight_road(200.0, lane_width_m=3.5)
    d = np.array([0.0, 0.4, 0.6, 1.0, 3.0, -0.6])
    left = road.left_ego_lane(50.0, d, 0.0, LENGTH, WIDTH)
    opposing = road.entered_opposing_lane(50.0, d, 0.0, LENGTH, WIDTH)
    # Corners at d ± 1.3; the lane edge is at ± 1.75.
    assert left.tolist() == [False, False, True, True, True, True]
    assert opposing.tolist() == [False, False, True, True, True, False]
    off = road.left_road(50.0, np.array([0.0, 3.5, 4.5, -0.5]), 0.0, LENGTH, WIDTH)
    assert off.tolist() == [False, False, True, True]


def test_heading_error_swings_the_corners_out() -> None:
    road = straight_road(200.0)
    assert not road.left_ego_lane(50.0, 0.0, 0.0, LENGTH, WIDTH)
    # Corner at (L/2, W/2) rotated by 0.1 rad: d = 3.14 sin 0.1 + 1.3 cos 0.1 ≈ 1.607 < 1.75.
    assert not road.left_ego_lane(50.0, 0.0, 0.1, LENGTH, WIDTH)
    assert road.left_ego_lane(50.0, 0.0, 0.2, LENGTH, WIDTH)


def test_corner_offsets_are_exact_in_a_curve() -> None:
    radius = 28.0
    road = turn_road(radius_m=radius, clothoid_m=0.0, approach_m=50.0, exit_m=50.0)
    s_mid = 50.0 + radius * math.pi / 4
    d = footprint_corner_offsets_m(road.path, s_mid, 0.0, 0.0, LENGTH, WIDTH)
    # In the arc, a corner at (±L/2, w) relative to a tangent pose lies at distance
    # hypot(L/2, R − w) from the centre: d = R − hypot(L/2, R − w) (left turn: centre on the left).
    for across, sign in ((WIDTH / 2, 1.0), (-WIDTH / 2, -1.0)):
        expected = radius - math.hypot(LENGTH / 2, radius - across)
        assert np.sort(d)[0 if sign < 0 else -1] == pytest.approx(expected, abs=1e-9)


def test_friction_map_segments_and_lanes() -> None:
    friction = FrictionMap((0.0, 50.0, 80.0), (0.8, 0.4, 0.9), mu_opposing=(0.3, 0.3, 0.3))
    s = np.array([-5.0, 0.0, 49.9, 50.0, 79.0, 500.0])
    assert friction.mu_at(s).tolist() == [0.8, 0.8, 0.8, 0.4, 0.4, 0.9]
    d = np.array([0.0, 0.0, 0.0, 2.0, 1.7, 2.0])
    assert friction.mu_at(s, d).tolist() == [0.8, 0.8, 0.8, 0.3, 0.4, 0.3]
    assert FrictionMap.uniform(0.6).mu_at(np.zeros((2, 3))).shape == (2, 3)
    road = turn_road(friction=FrictionMap.step(0.8, 0.4, 70.0))
    x, y, _ = road.to_cartesian(np.array([60.0, 90.0]), 0.3)
    assert road.mu_at_xy(x, y).tolist() == [0.8, 0.4]


@pytest.mark.parametrize(
    "kwargs, name",
    [({"start_s_m": (0.0,), "mu": (0.0,)}, "mu"),
     ({"start_s_m": (0.0, 1.0), "mu": (0.5, -0.1)}, "mu"),
     ({"start_s_m": (1.0, 0.0), "mu": (0.5, 0.5)}, "start_s_m"),
     ({"start_s_m": (0.0,), "mu": (0.5,), "mu_opposing": (0.0,)}, "mu_opposing")],
)
def test_bad_friction_maps_name_the_field(kwargs, name) -> None:
    with pytest.raises(ValueError, match=name):
        FrictionMap(**kwargs)


def test_pop_up_trigger() -> None:
    obstacle = Obstacle.pop_up(100.0, 0.0, distance_ahead_m=20.0)
    assert obstacle_active(obstacle, np.array([0.0, 79.9, 80.0, 120.0]), 0.0).tolist() == [
        False, False, True, True,
    ]
    timed = Obstacle(100.0, 0.0, appear_at_time_s=2.0)
    assert obstacle_active(timed, 0.0, np.array([1.9, 2.0])).tolist() == [False, True]
    assert bool(obstacle_active(Obstacle(100.0, 0.0), 0.0, 0.0))
    with pytest.raises(ValueError, match="width_m"):
        Obstacle(10.0, 0.0, width_m=0.0)


def test_clearance_to_an_obstacle_ahead_in_the_lane() -> None:
    road = straight_road(300.0)
    obstacle = Obstacle(100.0, 0.0, length_m=1.0, width_m=1.0)
    x = np.array([80.0, 96.0, 97.0, 98.0])
    clearance = footprint_clearance_m(obstacle, road.path, x, 0.0, 0.0, LENGTH, WIDTH)
    front = x + LENGTH / 2
    np.testing.assert_allclose(clearance[:2], 99.5 - front[:2], atol=1e-12)
    assert clearance[2] < 0.0 and clearance[3] < clearance[2]
    # Passing beside it: lateral gap.
    beside = footprint_clearance_m(obstacle, road.path, 100.0, 3.0, 0.0, LENGTH, WIDTH)
    assert float(beside) == pytest.approx(3.0 - 0.5 - WIDTH / 2)


@settings(max_examples=50, deadline=None)
@given(
    x=st.floats(-10.0, 10.0), y=st.floats(-10.0, 10.0), heading=st.floats(-3.2, 3.2),
    length=st.floats(0.5, 6.0), width=st.floats(0.5, 3.0),
)
def test_clearance_is_symmetric_and_matches_sampled_distance(x, y, heading, length, width) -> None:
    a = rectangle_corners(0.0, 0.0, 0.3, 4.0, 2.0)
    b = rectangle_corners(x, y, heading, length, width)
    ab, ba = float(signed_clearance_m(a, b)), float(signed_clearance_m(b, a))
    assert ab == pytest.approx(ba, abs=1e-9)
    # Brute force: distance between densely sampled boundaries (an upper bound, tight to ~1 cm).
    def boundary(corners: np.ndarray) -> np.ndarray:
        t = np.linspace(0.0, 1.0, 200)[:, None]
        return np.concatenate(
            [corners[i] + t * (corners[(i + 1) % 4] - corners[i]) for i in range(4)]
        )

    pa, pb = boundary(a), boundary(b)
    sampled = np.min(np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=-1))
    if ab > 0.0:
        assert ab == pytest.approx(sampled, abs=0.03)
    else:
        # Overlap: the boundaries cross, or one rectangle contains the other's centre.
        def inside(cx, cy, hd, ln, wd, px, py) -> bool:
            along = (px - cx) * math.cos(hd) + (py - cy) * math.sin(hd)
            across = -(px - cx) * math.sin(hd) + (py - cy) * math.cos(hd)
            return abs(along) <= ln / 2 and abs(across) <= wd / 2

        contained = inside(0.0, 0.0, 0.3, 4.0, 2.0, x, y) or inside(
            x, y, heading, length, width, 0.0, 0.0
        )
        assert sampled < 0.03 or contained
