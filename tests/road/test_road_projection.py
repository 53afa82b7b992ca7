"""The fast single-point geometry against the array (reference) implementations.

The closed loop uses plain-float frames (closed form on straights and arcs), warm-started
projections and plain-float rectangles; the array versions evaluate positions by Gauss–Legendre
quadrature and project from the global table. Both must agree to rounding (≤ 1e-9) everywhere,
including beyond the path's ends and from bad warm starts.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.road import (
    FrictionMap,
    PathSegment,
    PointTracker,
    ReferencePath,
    rectangle_corner_points,
    rectangle_corners,
    signed_clearance_m,
    signed_clearance_points,
    turn_road,
)
from mufusion.road.path import compiled_frames_available

TOL = 1e-9
# Both turn directions, with clothoids (linear curvature: quadrature) and without.
PATHS = [
    turn_road(radius_m=28.0, approach_m=40.0, exit_m=40.0, clothoid_m=5.0).path,
    turn_road(radius_m=28.0, approach_m=40.0, exit_m=40.0, clothoid_m=0.0,
              direction="right").path,
    ReferencePath([PathSegment.straight(20.0), PathSegment.clothoid(30.0, 0.0, 0.05),
                   PathSegment.arc(20.0, -2.0), PathSegment.straight(10.0)],
                  start_xy_m=(3.0, -2.0), start_heading_rad=0.7),
]


def _reference_frenet(path: ReferencePath, x: np.ndarray, y: np.ndarray, psi: np.ndarray):
    """The array projection (more than 8 points take the vectorised Newton path)."""
    assert x.size > 8
    return path.to_frenet(x, y, psi)


@pytest.mark.parametrize("path", PATHS)
def test_plain_float_frame_equals_the_quadrature(path: ReferencePath) -> None:
    s = np.concatenate([np.linspace(-15.0, path.length_m + 15.0, 2_001),
                        np.cumsum([seg.length_m for seg in path.segments])])
    x, y, heading, kappa = path._frame(s)
    scalar = np.array([path._frame_scalar(v) for v in s.tolist()])
    np.testing.assert_allclose(scalar[:, 0], x, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(scalar[:, 1], y, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(scalar[:, 2], heading, rtol=0.0, atol=1e-15)
    np.testing.assert_allclose(scalar[:, 3], kappa, rtol=0.0, atol=1e-15)
    assert [path.curvature_at(v) for v in s.tolist()] == path.curvature(s).tolist()


@pytest.mark.parametrize("path", PATHS)
def test_point_projection_equals_the_array_projection_cold_and_warm(path) -> None:
    rng = np.random.default_rng(11)
    n = 400
    s_true = rng.uniform(-10.0, path.length_m + 10.0, n)
    x, y, psi = path.to_cartesian(s_true, rng.uniform(-6.0, 6.0, n), rng.uniform(-3.0, 3.0, n))
    s_ref, d_ref, dpsi_ref = _reference_frenet(path, x, y, psi)
    # Warm starts up to 4 m off (accepted) and 30–60 m off (the global search answers).
    near = s_ref + rng.uniform(-4.0, 4.0, n)
    far = s_ref + rng.choice([-1.0, 1.0], n) * rng.uniform(30.0, 60.0, n)
    for guess in (None, near, far):
        got = np.array([
            path.to_frenet_point(xi, yi, pi, None if guess is None else float(guess[i]))
            for i, (xi, yi, pi) in enumerate(zip(x.tolist(), y.tolist(), psi.tolist(),
                                                 strict=True))
        ])
        np.testing.assert_allclose(got[:, 0], s_ref, rtol=0.0, atol=TOL)
        np.testing.assert_allclose(got[:, 1], d_ref, rtol=0.0, atol=TOL)
        wrapped = np.angle(np.exp(1j * (got[:, 2] - dpsi_ref)))
        np.testing.assert_allclose(wrapped, 0.0, rtol=0.0, atol=TOL)


@pytest.mark.parametrize("path", PATHS)
def test_tracker_along_a_trajectory_equals_the_array_projection(path) -> None:
    # A point weaving along the path at 20 m/s sampled at 200 Hz, with one jump back.
    rng = np.random.default_rng(3)
    s = np.concatenate([np.arange(-5.0, path.length_m + 5.0, 0.1), [10.0, 10.05]])
    d = 1.5 * np.sin(0.2 * s) + 0.01 * rng.standard_normal(s.size)
    x, y, _ = path.to_cartesian(s, d)
    s_ref, d_ref, _ = _reference_frenet(path, x, y, np.zeros_like(x))
    tracker = PointTracker(path)
    got = np.array([tracker.to_frenet(a, b)[:2] for a, b in zip(x.tolist(), y.tolist(),
                                                                strict=True)])
    np.testing.assert_allclose(got[:, 0], s_ref, rtol=0.0, atol=TOL)
    np.testing.assert_allclose(got[:, 1], d_ref, rtol=0.0, atol=TOL)
    assert tracker.last_s_m == got[-1, 0]
    # The same pose twice returns the stored answer; reset forgets the warm start.
    assert tracker.to_frenet(x[-1], y[-1]) == tracker.to_frenet(x[-1], y[-1])
    tracker.reset()
    assert tracker.last_s_m is None


def test_friction_at_a_point_equals_the_array_lookup() -> None:
    friction = FrictionMap((0.0, 50.0, 80.0), (0.8, 0.4, 0.9), mu_opposing=(0.3, 0.2, 0.1))
    s = np.array([-5.0, 0.0, 49.9, 50.0, 79.0, 80.0, 500.0, np.nan])
    d = np.array([0.0, 1.75, 1.76, 2.0, -3.0, 1.0, 9.0, 0.0])
    expected = friction.mu_at(s, d).tolist()
    assert [friction.mu_at_point(a, b) for a, b in zip(s.tolist(), d.tolist(),
                                                       strict=True)] == expected
    assert [friction.mu_at_point(a) for a in s.tolist()] == friction.mu_at(s).tolist()


@settings(max_examples=80, deadline=None)
@given(
    x=st.floats(-8.0, 8.0), y=st.floats(-8.0, 8.0), heading=st.floats(-3.2, 3.2),
    length=st.floats(0.5, 12.0), width=st.floats(0.5, 3.0),
)
def test_plain_float_rectangles_equal_the_array_versions(x, y, heading, length, width) -> None:
    points = rectangle_corner_points(x, y, heading, length, width)
    corners = rectangle_corners(x, y, heading, length, width)
    np.testing.assert_allclose(np.array(points), corners, rtol=0.0, atol=1e-12)
    other = rectangle_corners(1.0, -0.5, 0.3, 4.0, 2.0)
    expected = float(signed_clearance_m(corners, other))
    got = signed_clearance_points(points, [tuple(p) for p in other.tolist()])
    assert got == pytest.approx(expected, abs=1e-12)
    assert math.isfinite(got)


def test_the_install_built_the_compiled_frames() -> None:
    # `pip install -e .` compiles them; without them every run silently takes the slower path.
    assert compiled_frames_available()
    assert PATHS[0]._newton_scalar != PATHS[0]._newton_python


@pytest.mark.parametrize("path", PATHS)
def test_compiled_frame_and_newton_equal_the_python_bitwise(path: ReferencePath) -> None:
    # Progress beyond both ends, at segment starts, NaN; points on both sides, far off the
    # path (the slope floor), warm starts good and bad, and iteration limits 1 to 30.
    rng = np.random.default_rng(5)
    starts = np.cumsum([0.0] + [seg.length_m for seg in path.segments]).tolist()
    s_values = [*rng.uniform(-20.0, path.length_m + 20.0, 600).tolist(), *starts,
                -0.0, math.nan, math.inf, -math.inf]
    for s in s_values:
        # repr: exact digits and the sign of zero, not just ==
        assert repr(path._frame_scalar(s)) == repr(path._frame_python(s)), s
    s_true = rng.uniform(-10.0, path.length_m + 10.0, 600)
    x, y, _ = path.to_cartesian(s_true, rng.uniform(-40.0, 40.0, 600))
    guesses = s_true + rng.normal(0.0, 8.0, 600)
    iterations = rng.integers(1, 31, 600)
    for px, py, guess, k in zip(x.tolist(), y.tolist(), guesses.tolist(), iterations.tolist(),
                                strict=True):
        want = path._newton_python(px, py, guess, k)
        assert repr(path._newton_scalar(px, py, guess, k)) == repr(want)


def test_a_pickled_path_projects_as_the_original() -> None:
    # Campaign workers receive roads pickled; the compiled frames travel with them.
    path = PATHS[2]
    copy = pickle.loads(pickle.dumps(path))
    assert copy.to_frenet_point(12.0, 3.0, 0.2, 11.0) == path.to_frenet_point(12.0, 3.0, 0.2, 11.0)
    assert copy._frame_scalar(31.5) == path._frame_scalar(31.5)
