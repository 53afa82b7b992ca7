"""Ego and opposing lane (right-hand traffic) and footprint-based lane checks.

The reference path is the ego lane centre; the ego lane is ``|d| ≤ w/2``; the opposing lane lies
to its left, ``w/2 < d ≤ w/2 + w_o`` (``w_o``: its width, ``w`` unless given; 0 on a one-way
road); the road is both lanes, ``−w/2 ≤ d ≤ w/2 + w_o`` (``3w/2`` with equal lanes). A footprint
is a ``length × width`` rectangle centred at the given Frenet pose; its corners are placed
exactly in the Cartesian plane and projected back onto the path, so the checks stay exact in
curves.

The graded quantities (:func:`lane_margin_m`, :func:`opposing_lane_depth_m`,
:func:`road_margin_m`) are pure functions of the corners' offsets ``d``; the boolean checks are
these with a zero threshold. They measure the corners only: in a curve of radius ``R`` the
middle of a footprint side of length ``L`` lies up to ``L²/(8R)`` further towards the curve's
centre than its corners.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

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


def _offsets(corner_d_m: np.ndarray | list[float], lane_width_m: float) -> np.ndarray:
    if not (np.isfinite(lane_width_m) and lane_width_m > 0.0):
        raise ValueError(f"lane_width_m must be finite and > 0, got {lane_width_m!r}")
    d = np.asarray(corner_d_m, dtype=float)
    if d.ndim == 0 or d.shape[-1] == 0:
        raise ValueError(f"corner_d_m must have the corners along its last axis, got {d.shape}")
    return d


def lane_margin_m(corner_d_m: np.ndarray | list[float], lane_width_m: float) -> np.ndarray:
    """Smallest signed distance of the footprint's corners to the ego lane's edges [m].

    Parameters
    ----------
    corner_d_m
        Lateral offsets of the corners [m], shape ``B + (n_corners,)``.
    lane_width_m
        Lane width ``w`` [m], > 0.

    Returns
    -------
    ndarray
        Shape ``B``: ``min(w/2 − |d|)``, positive when every corner is inside the ego lane (the
        room left to the nearest edge), negative when one is outside (minus the deepest corner's
        distance beyond its edge).

    Raises
    ------
    ValueError
        If ``lane_width_m`` is not > 0 or ``corner_d_m`` has no corner axis.

    Examples
    --------
    >>> float(lane_margin_m([0.2, -0.9, -1.2, 0.1], 3.5))
    0.55
    >>> float(lane_margin_m([2.0, 1.0, 0.5, 1.5], 3.5))
    -0.25
    """
    d = _offsets(corner_d_m, lane_width_m)
    return np.min(0.5 * lane_width_m - np.abs(d), axis=-1)


def lane_excursion_m(corner_d_m: np.ndarray | list[float], lane_width_m: float) -> np.ndarray:
    """How far the deepest corner lies outside the ego lane [m], 0 if none: ``max(0, −margin)``.

    Examples
    --------
    >>> float(lane_excursion_m([2.0, 1.0, 0.5, 1.5], 3.5))
    0.25
    """
    return np.maximum(0.0, -lane_margin_m(corner_d_m, lane_width_m))


def opposing_lane_depth_m(
    corner_d_m: np.ndarray | list[float], lane_width_m: float
) -> np.ndarray:
    """How far the deepest corner lies left of the centre line (``d = w/2``) [m], 0 if none.

    A corner beyond the opposing lane's far edge keeps counting from the centre line (the
    depth then exceeds ``w``; :func:`road_margin_m` tells that it left the road).

    Examples
    --------
    >>> float(opposing_lane_depth_m([2.0, 1.0, 0.5, 1.5], 3.5))
    0.25
    >>> float(opposing_lane_depth_m([0.2, -0.9, -1.2, 0.1], 3.5))
    0.0
    """
    d = _offsets(corner_d_m, lane_width_m)
    return np.maximum(0.0, np.max(d, axis=-1) - 0.5 * lane_width_m)


def _far_edge_m(lane_width_m: float, opposing_width_m: float | None) -> float:
    # w/2 + w is 1.5 w to the last bit (both round the same exact sum once).
    return 0.5 * lane_width_m + (lane_width_m if opposing_width_m is None else opposing_width_m)


def road_margin_m(
    corner_d_m: np.ndarray | list[float], lane_width_m: float,
    opposing_width_m: float | None = None,
) -> np.ndarray:
    """Smallest signed distance of the corners to the road's outer edges (``−w/2`` and
    ``w/2 + w_o``, ``3w/2`` with equal lanes) [m].

    Positive when every corner is on the road, negative (minus the deepest corner's distance
    beyond the edge) when one is off it. ``opposing_width_m`` is the opposing lane's width
    ``w_o`` (None: ``lane_width_m``).

    Examples
    --------
    >>> float(road_margin_m([0.2, -0.9, -2.0, 0.1], 3.5))
    -0.25
    """
    d = _offsets(corner_d_m, lane_width_m)
    far = _far_edge_m(lane_width_m, opposing_width_m)
    return np.min(np.minimum(d + 0.5 * lane_width_m, far - d), axis=-1)


@dataclass(frozen=True)
class LaneMargins:
    """The graded lane quantities of one footprint (see the functions of the same names) [m]."""

    lane_margin_m: float
    opposing_depth_m: float
    road_margin_m: float

    @property
    def lane_excursion_m(self) -> float:
        """``max(0, −lane_margin_m)`` [m]."""
        return max(0.0, -self.lane_margin_m)

    @property
    def left_lane(self) -> bool:
        return self.lane_margin_m < 0.0

    @property
    def in_opposing_lane(self) -> bool:
        return self.opposing_depth_m > 0.0

    @property
    def off_road(self) -> bool:
        return self.road_margin_m < 0.0


def footprint_lane_margins(
    corner_d_m: Sequence[float], lane_width_m: float, opposing_width_m: float | None = None
) -> LaneMargins:
    """:func:`lane_margin_m`, :func:`opposing_lane_depth_m` and :func:`road_margin_m` of one
    footprint, in plain floats (the closed loop's per-tick check; equal to the array functions).

    Parameters
    ----------
    corner_d_m
        Lateral offsets of the footprint's corners [m].
    lane_width_m
        Lane width ``w`` [m] (not validated here: the road checked it).
    opposing_width_m
        The opposing lane's width [m]; None: ``lane_width_m``.

    Examples
    --------
    >>> m = footprint_lane_margins([2.0, 1.0, 0.5, 1.5], 3.5)
    >>> m.lane_margin_m, m.opposing_depth_m, m.road_margin_m, m.left_lane, m.off_road
    (-0.25, 0.25, 2.25, True, False)
    """
    half = 0.5 * lane_width_m
    far = _far_edge_m(lane_width_m, opposing_width_m)
    return LaneMargins(
        lane_margin_m=min(half - abs(d) for d in corner_d_m),
        opposing_depth_m=max(0.0, max(corner_d_m) - half),
        road_margin_m=min(min(d + half, far - d) for d in corner_d_m),
    )


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
    return lane_margin_m(d, lane_width_m) < 0.0


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
    return opposing_lane_depth_m(d, lane_width_m) > 0.0


def left_road(
    path: ReferencePath,
    s_m: np.ndarray | float,
    d_m: np.ndarray | float,
    dpsi_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
    lane_width_m: float,
    opposing_width_m: float | None = None,
) -> np.ndarray:
    """True where any footprint corner is off both lanes (``d < −w/2`` or ``d > w/2 + w_o``)."""
    d = footprint_corner_offsets_m(path, s_m, d_m, dpsi_rad, length_m, width_m)
    return road_margin_m(d, lane_width_m, opposing_width_m) < 0.0
