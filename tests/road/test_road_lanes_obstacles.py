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
    footprint_lane_margins,
    lane_excursion_m,
    lane_margin_m,
    obstacle_active,
    opposing_lane_depth_m,
    rectangle_corners,
    rectangles_overlap,
    road_margin_m,
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


def test_graded_margins_of_a_yawed_rectangle_on_a_straight_road() -> None:
    # A 4 m × 2 m rectangle yawed by 30° at d = 0.5 m, lane width 3.5 m. Corners at
    # d = 0.5 ± 2 sin 30° ± 1 cos 30°: the outermost left at 0.5 + 1 + 0.866 = 2.366 m, the
    # outermost right at 0.5 − 1.866 = −1.366 m.
    road = straight_road(100.0, lane_width_m=3.5)
    d = footprint_corner_offsets_m(road.path, 50.0, 0.5, math.radians(30.0), 4.0, 2.0)
    top, bottom = 0.5 + 1.0 + math.sqrt(3.0) / 2.0, 0.5 - 1.0 - math.sqrt(3.0) / 2.0
    assert sorted(d.tolist()) == pytest.approx(
        sorted([top, bottom, 0.5 + 1.0 - math.sqrt(3.0) / 2.0, 0.5 - 1.0 + math.sqrt(3.0) / 2.0]),
        abs=1e-12,
    )
    assert float(lane_margin_m(d, 3.5)) == pytest.approx(1.75 - top, abs=1e-12)  # −0.616
    assert float(lane_excursion_m(d, 3.5)) == pytest.approx(top - 1.75, abs=1e-12)
    assert float(opposing_lane_depth_m(d, 3.5)) == pytest.approx(top - 1.75, abs=1e-12)
    # Road edges at −1.75 and 5.25: the right side is the closer one, 1.75 − 1.366 = 0.384 m.
    assert float(road_margin_m(d, 3.5)) == pytest.approx(bottom + 1.75, abs=1e-12)
    # Centred and straight: 0.75 m of room each side, nothing in the opposing lane.
    d0 = footprint_corner_offsets_m(road.path, 50.0, 0.0, 0.0, 4.0, 2.0)
    assert float(lane_margin_m(d0, 3.5)) == pytest.approx(0.75)
    assert float(lane_excursion_m(d0, 3.5)) == 0.0
    assert float(opposing_lane_depth_m(d0, 3.5)) == 0.0
    # Off the road on the right by 0.25 m.
    d_off = footprint_corner_offsets_m(road.path, 50.0, -1.5, 0.0, 4.0, 2.0)
    assert float(road_margin_m(d_off, 3.5)) == pytest.approx(-0.75)
    assert float(lane_margin_m(d_off, 3.5)) == pytest.approx(-0.75)


def test_graded_margins_in_a_curve_match_the_circle() -> None:
    # Left arc of radius R: a corner at (±L/2, a) from a tangent pose at offset d0 lies
    # hypot(L/2, R − d0 − a) from the centre, so d = R − hypot(L/2, R − d0 − a).
    radius, d0, lane = 28.0, 0.9, 3.5
    road = turn_road(radius_m=radius, clothoid_m=0.0, approach_m=50.0, exit_m=50.0,
                     lane_width_m=lane)
    s_mid = 50.0 + radius * math.pi / 4
    d = footprint_corner_offsets_m(road.path, s_mid, d0, 0.0, LENGTH, WIDTH)
    left = radius - math.hypot(LENGTH / 2, radius - d0 - WIDTH / 2)
    right = radius - math.hypot(LENGTH / 2, radius - d0 + WIDTH / 2)
    assert float(lane_margin_m(d, lane)) == pytest.approx(lane / 2 - left, abs=1e-9)
    assert float(opposing_lane_depth_m(d, lane)) == pytest.approx(
        max(0.0, left - lane / 2), abs=1e-9
    )
    assert float(road_margin_m(d, lane)) == pytest.approx(right + lane / 2, abs=1e-9)


def test_margins_reject_bad_input_and_work_on_batches() -> None:
    with pytest.raises(ValueError, match="lane_width_m"):
        lane_margin_m([0.0, 1.0], 0.0)
    with pytest.raises(ValueError, match="corner_d_m"):
        road_margin_m(np.zeros((3, 0)), 3.5)
    d = np.array([[0.0, 1.0, -1.0, 0.5], [2.0, 1.0, 0.5, 1.5]])
    np.testing.assert_allclose(lane_margin_m(d, 3.5), [0.75, -0.25])
    np.testing.assert_allclose(opposing_lane_depth_m(d, 3.5), [0.0, 0.25])


def test_booleans_are_the_graded_quantities_at_zero_on_random_poses() -> None:
    # Straight and curved roads, poses across both lanes and beyond, yawed either way.
    rng = np.random.default_rng(5)
    for road in (straight_road(200.0), turn_road(radius_m=28.0, clothoid_m=5.0)):
        s = rng.uniform(0.0, road.length_m, 2_000)
        d = rng.uniform(-3.0, 7.0, 2_000)
        dpsi = rng.uniform(-0.6, 0.6, 2_000)
        corners = footprint_corner_offsets_m(road.path, s, d, dpsi, LENGTH, WIDTH)
        w = road.lane_width_m
        # The definitions the booleans had before the graded quantities existed.
        left = np.any(np.abs(corners) > 0.5 * w, axis=-1)
        opposing = np.any(corners > 0.5 * w, axis=-1)
        off = np.any((corners < -0.5 * w) | (corners > 1.5 * w), axis=-1)
        assert 0 < left.sum() < left.size and 0 < off.sum() < off.size
        np.testing.assert_array_equal(road.left_ego_lane(s, d, dpsi, LENGTH, WIDTH), left)
        np.testing.assert_array_equal(
            road.entered_opposing_lane(s, d, dpsi, LENGTH, WIDTH), opposing
        )
        np.testing.assert_array_equal(road.left_road(s, d, dpsi, LENGTH, WIDTH), off)
        np.testing.assert_array_equal(lane_margin_m(corners, w) < 0.0, left)
        np.testing.assert_array_equal(opposing_lane_depth_m(corners, w) > 0.0, opposing)
        np.testing.assert_array_equal(road_margin_m(corners, w) < 0.0, off)
        # The plain-float version of one footprint gives the same numbers.
        for row in rng.choice(corners.shape[0], 50, replace=False):
            one = footprint_lane_margins(corners[row].tolist(), w)
            assert one.lane_margin_m == float(lane_margin_m(corners[row], w))
            assert one.opposing_depth_m == float(opposing_lane_depth_m(corners[row], w))
            assert one.road_margin_m == float(road_margin_m(corners[row], w))
            assert one.lane_excursion_m == float(lane_excursion_m(corners[row], w))
            assert (one.left_lane, one.in_opposing_lane, one.off_road) == (
                left[row], opposing[row], off[row]
            )


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


def test_rectangles_overlap_where_the_clearance_is_negative() -> None:
    # A batch of rectangles around a fixed one (apart, crossing, contained, axis-aligned ones
    # touching it): the overlap test answers as the clearance's sign does, pair by pair.
    rng = np.random.default_rng(3)
    a = rectangle_corners(0.0, 0.0, 0.0, 4.0, 2.0)
    b = np.concatenate([
        rectangle_corners(rng.uniform(-6.0, 6.0, 250), rng.uniform(-4.0, 4.0, 250),
                          rng.uniform(-3.2, 3.2, 250), length, width)
        for length, width in ((1.0, 0.5), (6.0, 2.6))])
    touching = rectangle_corners(np.array([4.0, 0.0, -4.0]), np.array([0.0, 2.0, 0.0]), 0.0,
                                 4.0, 2.0)
    for others in (b, touching):
        overlap = rectangles_overlap(a, others)
        np.testing.assert_array_equal(overlap, signed_clearance_m(a, others) < 0.0)
    assert 0 < np.count_nonzero(rectangles_overlap(a, b)) < 500
    assert not rectangles_overlap(a, touching).any()
