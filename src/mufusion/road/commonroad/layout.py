"""What lies along an imported route: the reference polyline, the lanes' widths, the obstacles.

All of it is measured in the route's smoothed curvilinear frame (:mod:`.route`), because the
smoothing cuts corners: the lanelets' boundaries are re-projected onto the smoothed path rather
than taken from the lanelets' own widths (docs/decisions/0059).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mufusion.road.commonroad.route import Route

__all__ = [
    "ImportedObstacle",
    "LaneWidths",
    "interval_mid",
    "lane_widths",
    "obstacles_on_route",
    "polyline_curvature_1pm",
    "reference_points",
    "smallest_radius_m",
    "to_frame",
]

# Spacing of the written polyline [m]: 1 m resolves a 20 m radius with 0.1 % chord error, and at
# 0.1 mm rounding its three-point curvature is good to ~2e-4 1/m.
POINT_STEP_M = 1.0
# Spacing of the three points whose circle measures a bend [m] (:func:`smallest_radius_m`): 3 m
# passes over a one-vertex kink and resolves a 10 m radius within 1 %.
BEND_BASELINE_M = 3.0
# Boundary polylines are densified to this spacing before projection [m], so the lateral offset
# between two far-apart lanelet vertices follows the straight boundary segment, not its chord in s.
_BOUNDARY_STEP_M = 0.5


def reference_points(route: Route, step_m: float = POINT_STEP_M) -> tuple[np.ndarray, np.ndarray]:
    """The smoothed reference path resampled every ``step_m`` of arc length.

    Returns
    -------
    points_m : (n, 2) array
        Cartesian points in the file's coordinates [m], the last one at the path's end.
    s_m : (n,) array
        Their progress along the frame's path [m] (0 at the first point).
    """
    path = np.asarray(route.frame.ref_path, dtype=float)
    s_ref = np.asarray(route.frame.ref_pos, dtype=float)
    s = np.arange(0.0, s_ref[-1], step_m)
    if s_ref[-1] - s[-1] > 0.25 * step_m:
        s = np.append(s, s_ref[-1])
    else:
        s[-1] = s_ref[-1]
    points = np.column_stack([np.interp(s, s_ref, path[:, 0]), np.interp(s, s_ref, path[:, 1])])
    return points, s


def polyline_curvature_1pm(points_m: np.ndarray) -> np.ndarray:
    """Signed curvature of the circle through each three consecutive points [1/m], left +.

    Returns an array of ``n - 2`` values (the middle points'); the smallest radius of a written
    path is ``1 / max |κ|``.

    Examples
    --------
    >>> theta = np.linspace(0.0, 1.0, 21)
    >>> k = polyline_curvature_1pm(np.column_stack([25 * np.cos(theta), 25 * np.sin(theta)]))
    >>> bool(np.allclose(k, 1 / 25))
    True
    """
    a, b, c = points_m[:-2], points_m[1:-1], points_m[2:]
    ab, bc, ca = b - a, c - b, a - c
    cross = ab[:, 0] * (c - a)[:, 1] - ab[:, 1] * (c - a)[:, 0]
    return 2.0 * cross / (np.hypot(*ab.T) * np.hypot(*bc.T) * np.hypot(*ca.T))


def to_frame(frame: Any, xy: np.ndarray) -> tuple[float, float] | None:
    """``(s, d)`` of a Cartesian point in the frame [m], or None outside its projection domain
    (clcs raises its own ``CartesianProjectionDomainError`` there, not a ``ValueError``)."""
    try:
        s, d = frame.convert_to_curvilinear_coords(float(xy[0]), float(xy[1]))
    except Exception:
        return None
    return float(s), float(d)


def smallest_radius_m(points_m: np.ndarray, baseline_m: float, step_m: float) -> float:
    """The smallest radius of the circles through points ``baseline_m`` apart along a polyline
    sampled every ``step_m`` [m] (inf on a straight).

    With ``baseline_m = step_m`` every vertex counts; a longer baseline measures bends and
    passes over a kink at one vertex (curve subdivision leaves some at lanelet seams).
    """
    stride = max(1, round(baseline_m / step_m))
    kappa = max(float(np.max(np.abs(polyline_curvature_1pm(points_m[k::stride]))))
                for k in range(stride) if len(points_m[k::stride]) >= 3)
    return math.inf if kappa == 0.0 else 1.0 / kappa


def _densify(polyline: np.ndarray, step_m: float = _BOUNDARY_STEP_M) -> np.ndarray:
    seg = np.hypot(*np.diff(polyline, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    fine = np.union1d(s, np.arange(0.0, s[-1], step_m))
    return np.column_stack([np.interp(fine, s, polyline[:, 0]), np.interp(fine, s, polyline[:, 1])])


def _offsets(frame: Any, polylines: list[np.ndarray], s_m: np.ndarray) -> np.ndarray:
    """Lateral offset [m] of the boundary ``polylines`` at each ``s_m`` (NaN where none
    projects); where several cover an s, the one nearest the path counts."""
    out = np.full(len(s_m), np.nan)
    for line in polylines:
        sd = np.asarray(frame.convert_list_of_points_to_curvilinear_coords(_densify(line), 1))
        if sd.size < 2 * 2:
            continue
        order = np.argsort(sd[:, 0])
        s_b, d_b = sd[order, 0], sd[order, 1]
        inside = (s_m >= s_b[0]) & (s_m <= s_b[-1])
        d = np.interp(s_m[inside], s_b, d_b)
        old = out[inside]
        out[inside] = np.where(np.isnan(old) | (np.abs(d) < np.abs(old)), d, old)
    return out


@dataclass(frozen=True)
class LaneWidths:
    """The own lane's and the opposing lane's extent along the imported path.

    Attributes
    ----------
    s_m
        Progress along the path [m].
    left_m, right_m
        Distance from the path to the route lanelets' left and right boundaries [m] (both > 0
        when the path lies inside its lane).
    opposing_m
        Width of the adjacent opposite-direction lanelet beyond the left boundary [m]; NaN where
        there is none.
    """

    s_m: np.ndarray
    left_m: np.ndarray
    right_m: np.ndarray
    opposing_m: np.ndarray

    @property
    def ego_width_m(self) -> float:
        """Twice the smallest distance to the nearer boundary [m]: a symmetric lane that never
        reaches beyond the real one."""
        return 2.0 * float(np.nanmin(np.minimum(self.left_m, self.right_m)))

    @property
    def opposing_width_m(self) -> float:
        """The opposing lane's smallest width where it exists [m]; 0 if it exists nowhere."""
        if np.all(np.isnan(self.opposing_m)):
            return 0.0
        return max(0.0, float(np.nanmin(self.opposing_m)))

    @property
    def opposing_coverage(self) -> float:
        """Share of the path with an adjacent opposing lanelet [-]."""
        return float(np.mean(~np.isnan(self.opposing_m)))


def lane_widths(file_scenario: Any, route: Route, s_m: np.ndarray) -> LaneWidths:
    """Distances from the smoothed path to the route's lane boundaries along ``s_m``.

    The route lanelets' left and right boundaries and, for each, the far boundary of its left
    neighbour if that one runs the other way are projected into the route's frame and
    interpolated over s. Where no boundary projects (the ends of the projection domain) the
    nearest s that has one stands in.

    Raises
    ------
    ValueError
        If the path leaves its lane somewhere (a boundary on the wrong side).
    """
    network = file_scenario.lanelet_network
    lanelets = [network.find_lanelet_by_id(i) for i in route.lanelet_ids]
    left = _offsets(route.frame, [la.left_vertices for la in lanelets], s_m)
    right = -_offsets(route.frame, [la.right_vertices for la in lanelets], s_m)
    far_left: list[np.ndarray] = []
    for la in lanelets:
        if la.adj_left is not None and la.adj_left_same_direction is False:
            neighbour = network.find_lanelet_by_id(la.adj_left)
            # An opposite-direction neighbour shares its left boundary with ours: its right one
            # (in its own direction) is the far edge.
            far_left.append(neighbour.right_vertices)
    far = _offsets(route.frame, far_left, s_m) if far_left else np.full(len(s_m), np.nan)
    left, right = _fill_ends(left, "left", route), _fill_ends(right, "right", route)
    opposing = far - left
    if np.nanmin(left) <= 0.0 or np.nanmin(right) <= 0.0:
        side, values = ("left", left) if np.nanmin(left) <= 0.0 else ("right", right)
        i = int(np.nanargmin(values))
        raise ValueError(f"{route.label}: the smoothed path crosses the lane's {side} boundary "
                         f"at s = {s_m[i]:.1f} m (offset {values[i]:.2f} m)")
    return LaneWidths(s_m, left, right, opposing)


def _fill_ends(values: np.ndarray, side: str, route: Route) -> np.ndarray:
    """NaN stretches (no boundary projected) take the nearest s's value."""
    known = np.flatnonzero(~np.isnan(values))
    if known.size == 0:
        raise ValueError(f"{route.label}: no {side} lane boundary projects onto the path")
    idx = np.arange(len(values))
    return np.interp(idx, known, values[known])


@dataclass(frozen=True)
class ImportedObstacle:
    """An obstacle of the file at the route's time step, in the route's frame.

    Attributes
    ----------
    obstacle_id
        Its ID in the file.
    s_m, d_m
        Centre's progress along the path and lateral offset from it (left +) [m].
    length_m, width_m
        Its shape's extent [m].
    speed_mps
        Its velocity's component along the path's heading [m/s] (negative: oncoming).
    """

    obstacle_id: int
    s_m: float
    d_m: float
    length_m: float
    width_m: float
    speed_mps: float


def interval_mid(value: Any) -> float:
    """A number, or the middle of a 2018b ``Interval``."""
    if hasattr(value, "start") and hasattr(value, "end"):
        return 0.5 * (float(value.start) + float(value.end))
    return float(value)


def _extent(shape: Any) -> tuple[float, float]:
    """Length and width [m] of a rectangle, circle or polygon shape."""
    if hasattr(shape, "length") and hasattr(shape, "width"):
        return float(shape.length), float(shape.width)
    if hasattr(shape, "radius"):
        return 2.0 * float(shape.radius), 2.0 * float(shape.radius)
    vertices = np.asarray(shape.vertices, dtype=float)
    span = vertices.max(axis=0) - vertices.min(axis=0)
    return float(span.max()), float(span.min())


def obstacles_on_route(file_scenario: Any, route: Route, s_m: np.ndarray, *,
                       lateral_range_m: tuple[float, float]
                       ) -> tuple[list[ImportedObstacle], list[str]]:
    """The file's static and dynamic obstacles at the route's time step, in its frame.

    Parameters
    ----------
    lateral_range_m
        ``(right, left)`` lateral offsets [m] of the road's edges: an obstacle whose body
        reaches beyond them is not on this road and is dropped.

    Returns
    -------
    The obstacles kept, sorted by s, and one message per obstacle dropped (outside the projection
    domain, not within the road, not present at the time step).
    """
    kept: list[ImportedObstacle] = []
    dropped: list[str] = []
    heading = np.asarray(route.frame.ref_theta, dtype=float)
    s_ref = np.asarray(route.frame.ref_pos, dtype=float)
    for obstacle in [*file_scenario.static_obstacles, *file_scenario.dynamic_obstacles]:
        oid = int(obstacle.obstacle_id)
        state = obstacle.state_at_time(route.time_step)
        if state is None:
            dropped.append(f"obstacle {oid}: not present at time step {route.time_step}")
            continue
        position = state.position
        xy = np.asarray(getattr(position, "center", position), dtype=float)
        sd = to_frame(route.frame, xy)
        if sd is None:
            dropped.append(f"obstacle {oid} at ({xy[0]:.1f}, {xy[1]:.1f}): outside the path's "
                           "projection domain")
            continue
        s, d = sd
        length, width = _extent(obstacle.obstacle_shape)
        # The road kind refuses an obstacle whose body leaves the road; one off this road
        # (crossing traffic, a parked car on the verge) is not an obstacle of the route.
        if not (0.0 <= s <= s_m[-1] and lateral_range_m[0] <= d - 0.5 * width
                and d + 0.5 * width <= lateral_range_m[1]):
            dropped.append(f"obstacle {oid} at s = {s:.1f} m, d = {d:.1f} m ({width:.1f} m "
                           "wide): not within the road")
            continue
        velocity = interval_mid(getattr(state, "velocity", 0.0) or 0.0)
        orientation = interval_mid(getattr(state, "orientation", 0.0) or 0.0)
        relative = orientation - float(np.interp(s, s_ref, heading))
        kept.append(ImportedObstacle(oid, s, d, length, width, velocity * math.cos(relative)))
    return sorted(kept, key=lambda o: o.s_m), dropped
