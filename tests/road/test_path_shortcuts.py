"""Shortcuts of ReferencePath that must answer exactly what the general expressions answer."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.road.path import PathSegment, ReferencePath


def _general(path: ReferencePath, s_m: np.ndarray) -> np.ndarray:
    """The general expression of ReferencePath.curvature."""
    s = np.asarray(s_m, dtype=float)
    i = path._segment_index(s)
    sigma = s - path._seg_start[i]
    inside = (s >= 0.0) & (s <= path.length_m)
    return np.where(inside, path._k0[i] + path._dk[i] * sigma, 0.0)


@pytest.mark.parametrize("s_m", [
    np.linspace(-50.0, 400.0, 1001),
    np.array([np.nan, np.inf, -np.inf, -0.0, 0.0, 150.0, 300.0]),
    np.array(42.0),
    7.5,
])
def test_straight_path_curvature_is_bitwise_the_general_expression(s_m) -> None:
    path = ReferencePath([PathSegment.straight(100.0), PathSegment.straight(200.0)])
    assert path._flat
    got, expected = path.curvature(s_m), _general(path, s_m)
    assert got.shape == expected.shape and got.dtype == expected.dtype
    assert np.array_equal(got, expected)
    assert not np.signbit(got).any()  # +0.0, as the general expression gives


def test_a_path_with_an_arc_keeps_the_general_expression() -> None:
    path = ReferencePath([PathSegment.straight(10.0), PathSegment.arc(20.0, 1.0)])
    assert not path._flat
    s = np.linspace(-5.0, 40.0, 91)
    np.testing.assert_array_equal(path.curvature(s), _general(path, s))
    assert path.curvature(15.0) == 0.05


PATHS = [
    ReferencePath([PathSegment.straight(100.0), PathSegment.straight(200.0)]),
    ReferencePath([PathSegment.straight(20.0), PathSegment.clothoid(30.0, 0.0, 0.05),
                   PathSegment.arc(20.0, -2.0), PathSegment.straight(10.0)],
                  start_xy_m=(3.0, -2.0), start_heading_rad=0.7),
]


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("shape", [(), (1,), (40,), (3, 7)])
def test_to_cartesian_is_bitwise_position_plus_heading(path: ReferencePath, shape) -> None:
    rng = np.random.default_rng(len(shape))
    s = rng.uniform(-20.0, path.length_m + 20.0, shape)
    d = rng.uniform(-4.0, 4.0, shape)
    dpsi = rng.uniform(-0.5, 0.5, shape)
    x, y = path.position(s)
    psi_path = path.heading(s)
    expected = (x - d * np.sin(psi_path), y + d * np.cos(psi_path), psi_path + dpsi)
    for got, want in zip(path.to_cartesian(s, d, dpsi), expected, strict=True):
        assert got.shape == np.shape(want)
        np.testing.assert_array_equal(got, want)
