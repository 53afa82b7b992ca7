"""Ego and opposing lane (right-hand traffic) and footprint-based lane checks.

The reference path is the ego lane centre; the ego lane is ``|d| ≤ w/2``; the opposing lane lies
to its left, ``w/2 < d ≤ 3w/2``. A footprint is a ``length × width`` rectangle centred at the
given Frenet pose; its corners are placed exactly in the Cartesian plane and projected back onto
the path, so the checks stay exact in curves.
"""

from __future__ import annotations

import numpy as np

from mufusion.road.geometry import rectangle_corners
from mufusion.road.path import ReferencePath


def footprint_corner_offsets_m(
    path: ReferencePath,
    s_m: np.ndarray | float,
    d_m: np.ndarray | float,
    dpsi_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
) -> np.ndarray:
    """Lateral offsets ``d`` [m] of the four footprint corners, shape ``B + (4,)``.

    Parameters
    ----------
    path
        Reference path (the ego lane centre).
    s_m, d_m, dpsi_rad
        Frenet pose of the footprint centre (progress, lateral offset, heading error); broadcast.
    length_m, width_m
        Footprint size [m].
    """
    x, y, psi = path.to_cartesian(s_m, d_m, dpsi_rad)
    corners = rectangle_corners(x, y, psi, length_m, width_m)
    _, d, _ = path.to_frenet(corners[..., 0], corners[..., 1])
    return d


def left_ego_lane(
    path: ReferencePath,
    s_m: np.ndarray | float,
    d_m: np.ndarray | float,
    dpsi_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
    lane_width_m: float,
) -> np.ndarray:
    """True where any footprint corner lies outside the ego lane (``|d| > w/2``).

    Parameters are those of :func:`footprint_corner_offsets_m` plus ``lane_width_m`` [m].
    """
    d = footprint_corner_offsets_m(path, s_m, d_m, dpsi_rad, length_m, width_m)
    return np.any(np.abs(d) > 0.5 * lane_width_m, axis=-1)


def entered_opposing_lane(
    path: ReferencePath,
    s_m: np.ndarray | float,
    d_m: np.ndarray | float,
    dpsi_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
    lane_width_m: float,
) -> np.ndarray:
    """True where any footprint corner is left of the centre line (``d > w/2``).

    A corner beyond the opposing lane's far edge (``d > 3w/2``) also counts: it crossed it.
    """
    d = footprint_corner_offsets_m(path, s_m, d_m, dpsi_rad, length_m, width_m)
    return np.any(d > 0.5 * lane_width_m, axis=-1)


def left_road(
    path: ReferencePath,
    s_m: np.ndarray | float,
    d_m: np.ndarray | float,
    dpsi_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
    lane_width_m: float,
) -> np.ndarray:
    """True where any footprint corner is off both lanes (``d < −w/2`` or ``d > 3w/2``)."""
    d = footprint_corner_offsets_m(path, s_m, d_m, dpsi_rad, length_m, width_m)
    return np.any((d < -0.5 * lane_width_m) | (d > 1.5 * lane_width_m), axis=-1)
