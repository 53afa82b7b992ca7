"""The road: reference path, lanes, true friction and obstacles, plus the paper's geometries."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from mufusion.road.friction import DEFAULT_LANE_WIDTH_M, FrictionMap
from mufusion.road.lanes import entered_opposing_lane, left_ego_lane, left_road
from mufusion.road.obstacles import Obstacle
from mufusion.road.path import PathSegment, ReferencePath


@dataclass(frozen=True)
class Road:
    """Everything the world knows about the road (right-hand traffic).

    Attributes
    ----------
    path
        Ego lane centre line.
    lane_width_m
        Width of the ego lane [m] (and of the opposing lane unless ``opposing_lane_width_m``
        says otherwise); the opposing lane lies left of the ego lane.
    friction
        True friction map.
    obstacles
        Obstacles with their triggers.
    opposing_lane_width_m
        Width of the opposing lane [m]; None: ``lane_width_m`` (two equal lanes); 0: a one-way
        road whose left edge is the ego lane's.
    """

    path: ReferencePath
    lane_width_m: float = DEFAULT_LANE_WIDTH_M
    friction: FrictionMap = field(default_factory=lambda: FrictionMap.uniform(1.0))
    obstacles: tuple[Obstacle, ...] = ()
    opposing_lane_width_m: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lane_width_m) and self.lane_width_m > 0.0):
            raise ValueError(f"lane_width_m must be finite and > 0, got {self.lane_width_m!r}")
        opposing = self.opposing_lane_width_m
        if opposing is not None and not (math.isfinite(opposing) and opposing >= 0.0):
            raise ValueError(f"opposing_lane_width_m must be finite and >= 0, got {opposing!r}")
        object.__setattr__(self, "obstacles", tuple(self.obstacles))

    @property
    def opposing_width_m(self) -> float:
        """Width of the opposing lane [m] (``lane_width_m`` unless set, 0 on a one-way road)."""
        return self.lane_width_m if self.opposing_lane_width_m is None else (
            self.opposing_lane_width_m)

    @property
    def length_m(self) -> float:
        """Length of the reference path [m]."""
        return self.path.length_m

    def curvature(self, s_m: np.ndarray | float) -> np.ndarray:
        """Curvature κ(s) [1/m] of the reference path, left positive."""
        return self.path.curvature(s_m)

    def to_cartesian(self, s_m, d_m, dpsi_rad=0.0):
        """Frenet → Cartesian, see :meth:`ReferencePath.to_cartesian`."""
        return self.path.to_cartesian(s_m, d_m, dpsi_rad)

    def to_frenet(self, x_m, y_m, psi_rad=0.0):
        """Cartesian → Frenet, see :meth:`ReferencePath.to_frenet`."""
        return self.path.to_frenet(x_m, y_m, psi_rad)

    def mu_at(self, s_m: np.ndarray | float, d_m: np.ndarray | float | None = None) -> np.ndarray:
        """True friction at ``(s, d)``, see :meth:`FrictionMap.mu_at`."""
        return self.friction.mu_at(s_m, d_m)

    def mu_at_xy(self, x_m: np.ndarray | float, y_m: np.ndarray | float) -> np.ndarray:
        """True friction at Cartesian points (e.g. under each axle)."""
        s, d, _ = self.path.to_frenet(x_m, y_m)
        return self.friction.mu_at(s, d)

    def left_ego_lane(self, s_m, d_m, dpsi_rad, length_m: float, width_m: float) -> np.ndarray:
        """Any footprint corner outside the ego lane, see :func:`lanes.left_ego_lane`."""
        return left_ego_lane(self.path, s_m, d_m, dpsi_rad, length_m, width_m, self.lane_width_m)

    def entered_opposing_lane(
        self, s_m, d_m, dpsi_rad, length_m: float, width_m: float
    ) -> np.ndarray:
        """Any footprint corner in (or beyond) the opposing lane."""
        return entered_opposing_lane(
            self.path, s_m, d_m, dpsi_rad, length_m, width_m, self.lane_width_m
        )

    def left_road(self, s_m, d_m, dpsi_rad, length_m: float, width_m: float) -> np.ndarray:
        """Any footprint corner off both lanes."""
        return left_road(self.path, s_m, d_m, dpsi_rad, length_m, width_m, self.lane_width_m,
                         self.opposing_lane_width_m)


def straight_road(
    length_m: float,
    lane_width_m: float = DEFAULT_LANE_WIDTH_M,
    friction: FrictionMap | None = None,
    obstacles: tuple[Obstacle, ...] = (),
) -> Road:
    """A straight road along +X starting at the origin.

    Raises
    ------
    ValueError
        If ``length_m`` is not > 0.
    """
    if not (math.isfinite(length_m) and length_m > 0.0):
        raise ValueError(f"length_m must be finite and > 0, got {length_m!r}")
    path = ReferencePath([PathSegment.straight(length_m)])
    return Road(path, lane_width_m, friction or FrictionMap.uniform(1.0), tuple(obstacles))


def turn_road(
    radius_m: float = 28.0,
    approach_m: float = 80.0,
    exit_m: float = 100.0,
    clothoid_m: float = 5.0,
    direction: Literal["left", "right"] = "left",
    lane_width_m: float = DEFAULT_LANE_WIDTH_M,
    friction: FrictionMap | None = None,
    obstacles: tuple[Obstacle, ...] = (),
    angle_rad: float = math.pi / 2,
) -> Road:
    """The paper's turn (90° by default): straight, clothoid, arc, clothoid, straight (starts at
    the origin, heading +X).

    Parameters
    ----------
    radius_m
        Arc radius [m] (paper: 28 m).
    approach_m, exit_m
        Straight lengths before and after the curve [m].
    clothoid_m
        Length of each clothoid transition [m]; 0 gives a curvature jump. The two clothoids turn
        by ``clothoid_m / radius_m`` together, the arc by the rest of ``angle_rad``.
    direction
        ``"left"`` (default, κ > 0, ends heading +Y) or ``"right"`` (κ < 0, ends heading −Y).
    lane_width_m, friction, obstacles
        As in :class:`Road`; the default friction is μ = 1 everywhere.
    angle_rad
        Total heading change of the turn [rad], in (0, π] (paper: π/2).

    Raises
    ------
    ValueError
        If a length is negative (approach/exit/clothoid), the radius is not > 0, the angle is not
        in (0, π], the clothoids alone would turn more than the angle, or ``direction`` is
        unknown.

    Examples
    --------
    >>> road = turn_road()
    >>> round(float(road.path.end_heading_rad), 12) == round(math.pi / 2, 12)
    True
    """
    if not (math.isfinite(radius_m) and radius_m > 0.0):
        raise ValueError(f"radius_m must be finite and > 0, got {radius_m!r}")
    for name, value in (("approach_m", approach_m), ("exit_m", exit_m), ("clothoid_m", clothoid_m)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
    if direction not in ("left", "right"):
        raise ValueError(f"direction must be 'left' or 'right', got {direction!r}")
    if not (math.isfinite(angle_rad) and 0.0 < angle_rad <= math.pi):
        raise ValueError(f"angle_rad must be in (0, pi] rad, got {angle_rad!r}")
    arc_angle = angle_rad - clothoid_m / radius_m
    if arc_angle < 0.0:
        raise ValueError(
            f"clothoid_m must be <= radius_m * angle_rad = {radius_m * angle_rad:.3f} m, "
            f"got {clothoid_m!r}"
        )
    sign = 1.0 if direction == "left" else -1.0
    kappa = sign / radius_m
    segments = []
    if approach_m > 0.0:
        segments.append(PathSegment.straight(approach_m))
    if clothoid_m > 0.0:
        segments.append(PathSegment.clothoid(clothoid_m, 0.0, kappa))
    if arc_angle > 0.0:
        segments.append(PathSegment.arc(radius_m, sign * arc_angle))
    if clothoid_m > 0.0:
        segments.append(PathSegment.clothoid(clothoid_m, kappa, 0.0))
    if exit_m > 0.0:
        segments.append(PathSegment.straight(exit_m))
    return Road(
        ReferencePath(segments), lane_width_m, friction or FrictionMap.uniform(1.0),
        tuple(obstacles),
    )
