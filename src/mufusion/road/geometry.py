"""Oriented rectangles in the Cartesian plane: footprints, overlap and signed clearance."""

from __future__ import annotations

import numpy as np


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


def _penetration(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest projection overlap over the edge normals of both rectangles (SAT); ≤ 0 if apart."""
    overlaps = []
    for poly in (a, b):
        for edge in (0, 1):
            direction = poly[..., edge + 1, :] - poly[..., edge, :]
            normal = np.stack([-direction[..., 1], direction[..., 0]], axis=-1)
            normal = normal / np.linalg.norm(normal, axis=-1, keepdims=True)
            pa = np.sum(a * normal[..., None, :], axis=-1)
            pb = np.sum(b * normal[..., None, :], axis=-1)
            overlaps.append(
                np.minimum(pa.max(axis=-1), pb.max(axis=-1))
                - np.maximum(pa.min(axis=-1), pb.min(axis=-1))
            )
    return np.min(np.stack(overlaps), axis=0)


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
