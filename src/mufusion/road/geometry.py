"""Oriented rectangles in the Cartesian plane: footprints, overlap and signed clearance."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

Point = tuple[float, float]


def rectangle_corners(
    x_m: np.ndarray | float,
    y_m: np.ndarray | float,
    heading_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
) -> np.ndarray:
    """Corners of rectangles centred at ``(x, y)`` with the long side along ``heading``.

    Parameters
    ----------
    x_m, y_m, heading_rad
        Centre [m] and heading [rad]; broadcast to a batch shape ``B``.
    length_m, width_m
        Size along and across the heading [m].

    Returns
    -------
    ndarray
        Shape ``B + (4, 2)``: front-left, front-right, rear-right, rear-left (consecutive, so
        corner ``i`` and ``i + 1`` span an edge).
    """
    x, y, heading = np.broadcast_arrays(
        np.asarray(x_m, float), np.asarray(y_m, float), np.asarray(heading_rad, float)
    )
    along = np.array([0.5, 0.5, -0.5, -0.5]) * length_m
    across = np.array([0.5, -0.5, -0.5, 0.5]) * width_m
    c, s = np.cos(heading)[..., None], np.sin(heading)[..., None]
    cx = x[..., None] + along * c - across * s
    cy = y[..., None] + along * s + across * c
    return np.stack([cx, cy], axis=-1)


def _point_segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances of ``points`` (..., P, 1, 2) to segments a→b (..., 1, E, 2) → (..., P, E)."""
    ab = b - a
    t = np.sum((points - a) * ab, axis=-1) / np.maximum(np.sum(ab * ab, axis=-1), 1e-300)
    t = np.clip(t, 0.0, 1.0)
    closest = a + t[..., None] * ab
    return np.linalg.norm(points - closest, axis=-1)


def _axis_overlap(a: np.ndarray, b: np.ndarray, of_b: bool, edge: int) -> np.ndarray:
    """Overlap of the projections of ``a`` and ``b`` onto the normal of edge ``edge`` (0 or 1)
    of ``b`` (``of_b``) or of ``a``; ≤ 0 where that axis separates them."""
    poly = b if of_b else a
    direction = poly[..., edge + 1, :] - poly[..., edge, :]
    normal = np.stack([-direction[..., 1], direction[..., 0]], axis=-1)
    normal = normal / np.linalg.norm(normal, axis=-1, keepdims=True)
    pa = np.sum(a * normal[..., None, :], axis=-1)
    pb = np.sum(b * normal[..., None, :], axis=-1)
    return np.minimum(pa.max(axis=-1), pb.max(axis=-1)) - np.maximum(pa.min(axis=-1),
                                                                      pb.min(axis=-1))


_SAT_AXES = ((False, 0), (False, 1), (True, 0), (True, 1))
"""The separating-axis test's axes: both edge normals of the first rectangle, then the second's."""


def _penetration(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest projection overlap over the edge normals of both rectangles (SAT); ≤ 0 if apart."""
    return np.min(np.stack([_axis_overlap(a, b, of_b, edge) for of_b, edge in _SAT_AXES]),
                  axis=0)


def signed_clearance_m(corners_a: np.ndarray, corners_b: np.ndarray) -> np.ndarray:
    """Signed clearance between pairs of rectangles [m] (batch shapes broadcast).

    Parameters
    ----------
    corners_a, corners_b
        Rectangle corners, shapes ``B + (4, 2)`` in consecutive order (see
        :func:`rectangle_corners`).

    Returns
    -------
    ndarray
        Shape ``B``: the Euclidean distance between the rectangles when they are apart, minus the
        penetration depth (smallest separating translation along an edge normal) when they
        overlap; 0 when they touch.

    Examples
    --------
    >>> a = rectangle_corners(0.0, 0.0, 0.0, 2.0, 2.0)
    >>> float(signed_clearance_m(a, rectangle_corners(5.0, 0.0, 0.0, 2.0, 2.0)))
    3.0
    >>> float(signed_clearance_m(a, rectangle_corners(1.5, 0.0, 0.0, 2.0, 2.0)))
    -0.5
    """
    a, b = np.broadcast_arrays(np.asarray(corners_a, float), np.asarray(corners_b, float))
    next_a, next_b = np.roll(a, -1, axis=-2), np.roll(b, -1, axis=-2)
    d_ab = _point_segment_distance(a[..., :, None, :], b[..., None, :, :], next_b[..., None, :, :])
    d_ba = _point_segment_distance(b[..., :, None, :], a[..., None, :, :], next_a[..., None, :, :])
    distance = np.minimum(d_ab.min(axis=(-2, -1)), d_ba.min(axis=(-2, -1)))
    penetration = _penetration(a, b)
    return np.where(penetration > 0.0, -penetration, distance)


def rectangles_overlap(corners_a: np.ndarray, corners_b: np.ndarray) -> np.ndarray:
    """Whether pairs of rectangles overlap (batch shapes broadcast): exactly where
    :func:`signed_clearance_m` is negative, for finite corners, without its distances.

    Examples
    --------
    >>> a = rectangle_corners(0.0, 0.0, 0.0, 2.0, 2.0)
    >>> bool(rectangles_overlap(a, rectangle_corners(1.5, 0.0, 0.0, 2.0, 2.0)))
    True
    >>> bool(rectangles_overlap(a, rectangle_corners(2.0, 0.0, 0.0, 2.0, 2.0)))  # touching
    False
    """
    a, b = np.broadcast_arrays(np.asarray(corners_a, float), np.asarray(corners_b, float))
    batch = a.shape[:-2]
    a, b = a.reshape(-1, 4, 2), b.reshape(-1, 4, 2)
    # The penetration is positive where every axis overlaps: the pairs an axis separates are
    # dropped before the next (each pair's overlaps are computed as _penetration computes them).
    rows = np.arange(len(a))
    for of_b, edge in _SAT_AXES:
        if rows.size:
            rows = rows[_axis_overlap(a[rows], b[rows], of_b, edge) > 0.0]
    overlap = np.zeros(len(a), dtype=bool)
    overlap[rows] = True
    return overlap.reshape(batch)


# Plain-float versions for one rectangle pair at a time: the closed loop checks one footprint per
# tick, where numpy's per-call overhead costs ten times the arithmetic. Same algorithm, same
# corner order; the tests hold them equal to the array versions to rounding.


def rectangle_corner_points(
    x_m: float, y_m: float, heading_rad: float, length_m: float, width_m: float
) -> tuple[Point, Point, Point, Point]:
    """Corners of one rectangle as plain floats, in the order of :func:`rectangle_corners`.

    Examples
    --------
    >>> rectangle_corner_points(0.0, 0.0, 0.0, 4.0, 2.0)
    ((2.0, 1.0), (2.0, -1.0), (-2.0, -1.0), (-2.0, 1.0))
    """
    c, s = math.cos(heading_rad), math.sin(heading_rad)
    half_l, half_w = 0.5 * length_m, 0.5 * width_m
    return (
        (x_m + half_l * c - half_w * s, y_m + half_l * s + half_w * c),
        (x_m + half_l * c + half_w * s, y_m + half_l * s - half_w * c),
        (x_m - half_l * c + half_w * s, y_m - half_l * s - half_w * c),
        (x_m - half_l * c - half_w * s, y_m - half_l * s + half_w * c),
    )


def _point_segment_distance_scalar(p: Point, a: Point, b: Point) -> float:
    abx, aby = b[0] - a[0], b[1] - a[1]
    t = ((p[0] - a[0]) * abx + (p[1] - a[1]) * aby) / max(abx * abx + aby * aby, 1e-300)
    t = min(max(t, 0.0), 1.0)
    return math.hypot(p[0] - (a[0] + t * abx), p[1] - (a[1] + t * aby))


def _penetration_scalar(a: Sequence[Point], b: Sequence[Point]) -> float:
    depth = math.inf
    for poly in (a, b):
        for edge in (0, 1):
            dx, dy = poly[edge + 1][0] - poly[edge][0], poly[edge + 1][1] - poly[edge][1]
            norm = math.hypot(dx, dy)
            nx, ny = -dy / norm, dx / norm
            pa = [p[0] * nx + p[1] * ny for p in a]
            pb = [p[0] * nx + p[1] * ny for p in b]
            depth = min(depth, min(max(pa), max(pb)) - max(min(pa), min(pb)))
    return depth


def signed_clearance_points(corners_a: Sequence[Point], corners_b: Sequence[Point]) -> float:
    """Signed clearance between two rectangles given as corner points [m].

    The plain-float counterpart of :func:`signed_clearance_m` for one pair (corners in
    consecutive order, e.g. from :func:`rectangle_corner_points`).

    Examples
    --------
    >>> a = rectangle_corner_points(0.0, 0.0, 0.0, 2.0, 2.0)
    >>> signed_clearance_points(a, rectangle_corner_points(5.0, 0.0, 0.0, 2.0, 2.0))
    3.0
    >>> signed_clearance_points(a, rectangle_corner_points(1.5, 0.0, 0.0, 2.0, 2.0))
    -0.5
    """
    penetration = _penetration_scalar(corners_a, corners_b)
    if penetration > 0.0:
        return -penetration
    # _point_segment_distance_scalar for every corner against every edge, inlined with each
    # edge's vector and squared length computed once (the same expressions, so the same
    # values); ``if x < distance`` is ``min(distance, x)``, NaN included.
    hypot = math.hypot
    distance = math.inf
    for points, poly in ((corners_a, corners_b), (corners_b, corners_a)):
        n = len(poly)
        for k in range(n):
            (ax, ay), (bx, by) = poly[k], poly[(k + 1) % n]
            abx, aby = bx - ax, by - ay
            squared = abx * abx + aby * aby
            squared = 1e-300 if 1e-300 > squared else squared  # max(squared, 1e-300)
            for px, py in points:
                t = ((px - ax) * abx + (py - ay) * aby) / squared
                t = 0.0 if 0.0 > t else t  # max(t, 0.0)
                t = 1.0 if 1.0 < t else t  # min(t, 1.0)
                gap = hypot(px - (ax + t * abx), py - (ay + t * aby))
                if gap < distance:
                    distance = gap
    return distance
