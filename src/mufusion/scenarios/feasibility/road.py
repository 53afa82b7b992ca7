"""Feasibility along any road: the friction-limited speed profile of a point mass along the
path, and the pop-up envelopes for static obstacles in the own lane.

*Path*: the ego lane's centre line from the vehicle's start to the path's end, as
:class:`~mufusion.scenarios.feasibility.profile.Piece` pieces (the path's own straights, arcs
and clothoids, the first one cut at the start), with the road's ego-lane μ along s, the lower
under the two axles (:func:`~mufusion.scenarios.feasibility.profile.axle_span_friction`'s rule
for every change). The backward pass on the g-g circle at the planner's utilisation and the
forward cruise through the brakes' dead time are the turn oracle's
(:func:`~mufusion.scenarios.feasibility.turn.line_limit`); the verdict is the centre line's
(the lane's play is not used: a road's curves are not one symmetric turn).

*Obstacles*: each static obstacle reaching into the own lane is a pop-up
(:func:`~mufusion.scenarios.feasibility.popup.popup_feasibility`) at the distance from the
vehicle's front when it appears (at the start if it is there from the start or the trigger lies
behind the start; by time: after cruising at the entry speed), at the entry speed, with the
lowest ego-lane μ between the front and the obstacle. The envelopes assume a straight road;
moving obstacles and those outside the own lane are not judged. The variant's class is the
worst of the path's and the obstacles', its margin that verdict's. Derivation and limits:
docs/feasibility.md, "Any road".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mufusion.road import FrictionMap, Obstacle, ReferencePath
from mufusion.scenarios.feasibility.attitude import BodyInLane
from mufusion.scenarios.feasibility.common import FeasibilityClass
from mufusion.scenarios.feasibility.popup import PopupFeasibility
from mufusion.scenarios.feasibility.profile import FrictionOfS, Piece
from mufusion.scenarios.feasibility.turn import TurnLimit, line_limit


@dataclass(frozen=True)
class RoadFeasibility:
    """Verdict on a road variant: the path's profile and each judged obstacle's envelopes.

    ``obstacles`` pairs each judged obstacle's index in the scenario with its verdict;
    ``deciding`` names the part whose verdict is the variant's (``"path"`` or
    ``"obstacles.<i>"``).
    """

    feasibility_class: FeasibilityClass
    margin_mps: float
    entry_speed_mps: float
    path: TurnLimit
    obstacles: tuple[tuple[int, PopupFeasibility], ...]
    deciding: str


def path_pieces(path: ReferencePath, start_s_m: float) -> list[Piece]:
    """The path's segments from ``start_s_m`` [m] to its end as profile pieces (centre line).

    Examples
    --------
    >>> from mufusion.road import PathSegment
    >>> p = ReferencePath([PathSegment.straight(10.0), PathSegment.clothoid(10.0, 0.0, 0.1)])
    >>> path_pieces(p, 15.0)
    [Piece(length_m=5.0, kappa_start_1pm=0.05, kappa_end_1pm=0.1, centre_length_m=5.0)]
    """
    pieces, start = [], 0.0
    for seg in path.segments:
        end = start + seg.length_m
        if end > start_s_m:
            cut = max(start_s_m - start, 0.0)
            slope = (seg.curvature_end_1pm - seg.curvature_start_1pm) / seg.length_m
            length = seg.length_m - cut
            pieces.append(Piece(length, seg.curvature_start_1pm + slope * cut,
                                seg.curvature_end_1pm, length))
        start = end
    return [p for p in pieces if p.length_m > 0.0]


def axle_friction(
    friction: FrictionMap, start_s_m: float, front_m: float, rear_m: float
) -> tuple[FrictionOfS, tuple[float, ...]]:
    """The ego lane's μ under the lower of the two axles, over the progress from the start:
    ``mu_of(x)`` with the centre of gravity at ``start_s_m + x``, and where it may jump.

    Examples
    --------
    >>> mu, points = axle_friction(FrictionMap((0.0, 50.0), (0.9, 0.3)), 40.0, 1.0, 2.0)
    >>> [mu(x) for x in (8.9, 9.0, 30.0)], points
    ([0.9, 0.3, 0.3], (9.0, 12.0))
    """
    def mu_of(x_m: float) -> float:
        s = start_s_m + x_m
        return min(friction.mu_at_point(s + front_m), friction.mu_at_point(s - rear_m))

    points = tuple(p for change in friction.start_s_m[1:]
                   for p in (change - start_s_m - front_m, change - start_s_m + rear_m))
    return mu_of, points


def path_limit(
    *, path: ReferencePath, friction: FrictionMap, start_s_m: float, entry_speed_mps: float,
    utilization_factor: float, dead_time_s: float, max_decel_mps2: float,
    front_axle_ahead_m: float, rear_axle_behind_m: float, body: BodyInLane | None = None,
) -> TurnLimit:
    """The centre line's limit from the start (:func:`line_limit`; ``body``: the rigid body
    the lane must hold, None: a point mass); a path without a curve ahead has no limit
    (``margin_mps`` = +inf)."""
    pieces = path_pieces(path, start_s_m)
    curvature = max((max(abs(p.kappa_start_1pm), abs(p.kappa_end_1pm)) for p in pieces),
                    default=0.0)
    if curvature == 0.0:
        return TurnLimit(
            path="centreline", radius_m=math.inf, limit_speed_mps=math.inf,
            limit_distance_m=math.inf, max_entry_speed_mps=math.inf, braking_distance_m=0.0,
            spare_distance_m=math.inf, margin_mps=math.inf,
            feasibility_class=FeasibilityClass.FEASIBLE)
    # The pass brakes towards |κ|: a right curve limits as a left one does.
    pieces = [piece for p in pieces for piece in _split_at_zero(p)]
    mu_of, points = axle_friction(friction, start_s_m, front_axle_ahead_m, rear_axle_behind_m)
    return line_limit("centreline", 1.0 / curvature, pieces, mu_of, points, entry_speed_mps,
                      utilization_factor, dead_time_s, max_decel_mps2,
                      None if body is None else body.lateral_cap)


def _split_at_zero(piece: Piece) -> list[Piece]:
    """A piece whose curvature changes sign, as two with ``|κ|`` linear on each."""
    k0, k1 = piece.kappa_start_1pm, piece.kappa_end_1pm
    if k0 * k1 >= 0.0:
        return [Piece(piece.length_m, abs(k0), abs(k1), piece.centre_length_m)]
    at = piece.length_m * k0 / (k0 - k1)
    return [Piece(at, abs(k0), 0.0, at),
            Piece(piece.length_m - at, 0.0, abs(k1), piece.length_m - at)]


def obstacle_distance_m(
    obstacle: Obstacle, start_s_m: float, front_m: float, entry_speed_mps: float
) -> float:
    """From the vehicle's front to the obstacle's centre when it appears [m] (cruising at the
    entry speed until then; at the start if it is there from the start)."""
    at_start = obstacle.s_m - start_s_m - front_m
    times = []
    if obstacle.appear_at_ego_s_m is not None:
        times.append(max(obstacle.appear_at_ego_s_m - start_s_m, 0.0) / entry_speed_mps)
    if obstacle.appear_at_time_s is not None:
        times.append(obstacle.appear_at_time_s)
    return at_start - entry_speed_mps * (min(times) if times else 0.0)


def in_own_lane(obstacle: Obstacle, lane_width_m: float) -> bool:
    """Whether a static obstacle reaches into the own lane (``|d| < w/2`` for some part)."""
    return (not obstacle.moving
            and abs(obstacle.d_m) - 0.5 * obstacle.width_m < 0.5 * lane_width_m)


def road_feasibility(
    entry_speed_mps: float, path: TurnLimit,
    obstacles: tuple[tuple[int, PopupFeasibility], ...],
) -> RoadFeasibility:
    """The variant's verdict: the worst of the path's and the obstacles' (ties: the smaller
    margin)."""
    parts: list[tuple[str, FeasibilityClass, float]] = [
        ("path", path.feasibility_class, path.margin_mps)]
    parts += [(f"obstacles.{i}", v.feasibility_class, v.margin_mps) for i, v in obstacles]
    name, verdict, margin = min(parts, key=lambda part: (part[1].rank, part[2]))
    return RoadFeasibility(feasibility_class=verdict, margin_mps=margin,
                           entry_speed_mps=entry_speed_mps, path=path, obstacles=obstacles,
                           deciding=name)
