"""Reference path: curvature, exact positions, Frenet ↔ Cartesian round trip."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import fresnel

from mufusion.road import PathSegment, ReferencePath, straight_road, turn_road


def test_arc_positions_match_the_circle() -> None:
    radius = 28.0
    path = ReferencePath([PathSegment.straight(10.0), PathSegment.arc(radius, math.pi / 2)])
    s = np.linspace(10.0, 10.0 + radius * math.pi / 2, 50)
    angle = (s - 10.0) / radius
    x, y = path.position(s)
    np.testing.assert_allclose(x, 10.0 + radius * np.sin(angle), atol=1e-10)
    np.testing.assert_allclose(y, radius * (1.0 - np.cos(angle)), atol=1e-10)
    np.testing.assert_allclose(path.curvature(s[1:-1]), 1.0 / radius)
    np.testing.assert_allclose(path.heading(s), angle, atol=1e-12)


def test_clothoid_positions_match_fresnel_integrals() -> None:
    # Curvature from 0 to 1/R over L: ψ = s²/(2RL); x + iy = ∫ exp(iψ) = a (C + iS)(s/a) with
    # a = sqrt(π R L) (scipy's fresnel uses cos(π t²/2)).
    radius, length = 28.0, 20.0
    path = ReferencePath([PathSegment.clothoid(length, 0.0, 1.0 / radius)])
    s = np.linspace(0.0, length, 41)
    scale = math.sqrt(math.pi * radius * length)
    fs, fc = fresnel(s / scale)
    x, y = path.position(s)
    np.testing.assert_allclose(x, scale * fc, atol=1e-10)
    np.testing.assert_allclose(y, scale * fs, atol=1e-10)
    np.testing.assert_allclose(path.curvature(s), s / (radius * length), atol=1e-14)


@pytest.mark.parametrize("direction, sign", [("left", 1.0), ("right", -1.0)])
def test_turn_road_turns_ninety_degrees_with_continuous_curvature(direction, sign) -> None:
    road = turn_road(radius_m=28.0, approach_m=60.0, exit_m=50.0, clothoid_m=6.0,
                     direction=direction)
    path = road.path
    assert path.end_heading_rad == pytest.approx(sign * math.pi / 2, abs=1e-12)
    s = np.linspace(0.0, path.length_m, 20_001)
    kappa = path.curvature(s)
    assert np.max(np.abs(np.diff(kappa))) < 1e-3  # clothoids: no curvature jump
    assert np.max(sign * kappa) == pytest.approx(1.0 / 28.0)
    assert kappa[0] == 0.0 and kappa[-1] == 0.0
    # Heading is the integral of curvature.
    heading = path.heading(s)
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * np.diff(s))])
    np.testing.assert_allclose(heading, integral, atol=1e-6)
    # Positions are the integral of the heading direction.
    x, y = path.position(s)
    steps = np.hypot(np.diff(x), np.diff(y))
    np.testing.assert_allclose(steps, np.diff(s), rtol=1e-6)


def test_beyond_the_ends_the_path_continues_straight() -> None:
    road = turn_road()
    path = road.path
    x, y = path.position(np.array([-5.0, path.length_m + 7.0]))
    assert (x[0], y[0]) == pytest.approx((-5.0, 0.0))
    end = np.array(path.end_xy_m)
    assert (x[1], y[1]) == pytest.approx(tuple(end + 7.0 * np.array([0.0, 1.0])), abs=1e-9)
    assert path.curvature(-1.0) == 0.0


ROAD = turn_road(radius_m=28.0, approach_m=40.0, exit_m=40.0, clothoid_m=5.0)


@settings(max_examples=60, deadline=None)
@given(
    s=st.floats(-10.0, ROAD.length_m + 10.0),
    d=st.floats(-10.0, 10.0),
    dpsi=st.floats(-3.0, 3.0),
)
def test_frenet_cartesian_round_trip(s: float, d: float, dpsi: float) -> None:
    x, y, psi = ROAD.to_cartesian(s, d, dpsi)
    s2, d2, dpsi2 = ROAD.to_frenet(x, y, psi)
    assert float(s2) == pytest.approx(s, abs=1e-8)
    assert float(d2) == pytest.approx(d, abs=1e-8)
    assert float(dpsi2) == pytest.approx(dpsi, abs=1e-9)


def test_round_trip_vectorised_and_cartesian_first() -> None:
    rng = np.random.default_rng(7)
    s = rng.uniform(0.0, ROAD.length_m, (30, 20))
    d = rng.uniform(-5.0, 5.0, (30, 20))
    x, y, _ = ROAD.to_cartesian(s, d)
    assert x.shape == (30, 20)
    s2, d2, _ = ROAD.to_frenet(x, y)
    np.testing.assert_allclose(s2, s, atol=1e-8)
    np.testing.assert_allclose(d2, d, atol=1e-8)
    # Cartesian → Frenet → Cartesian lands on the same point.
    x3, y3, _ = ROAD.to_cartesian(s2, d2)
    np.testing.assert_allclose(np.hypot(x3 - x, y3 - y), 0.0, atol=1e-8)


def test_left_is_positive_d() -> None:
    road = straight_road(100.0)
    _, d, _ = road.to_frenet(10.0, 2.0)
    assert float(d) == pytest.approx(2.0)
    _, y, _ = road.to_cartesian(10.0, -1.0)
    assert float(y) == pytest.approx(-1.0)


@pytest.mark.parametrize(
    "kwargs, name",
    [({"radius_m": -1.0}, "radius_m"), ({"clothoid_m": 50.0}, "clothoid_m"),
     ({"approach_m": -1.0}, "approach_m"), ({"direction": "up"}, "direction")],
)
def test_bad_turn_arguments_are_rejected(kwargs, name) -> None:
    with pytest.raises(ValueError, match=name):
        turn_road(**kwargs)


def test_bad_segments_are_rejected() -> None:
    with pytest.raises(ValueError, match="length_m"):
        PathSegment(0.0)
    with pytest.raises(ValueError, match="segments"):
        ReferencePath([])
    with pytest.raises(ValueError, match="length_m"):
        straight_road(-5.0)
