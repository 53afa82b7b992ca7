"""Frenet projection of points that move a little between calls (an axle, a footprint corner).

The closed loop projects the same few vehicle points onto the path at every plant step; each
moves a few centimetres per step, so its last foot point is an excellent start for the next
Newton search (:meth:`~mufusion.road.path.ReferencePath.to_frenet_point`), which then skips the
global table search. The warm start is the only state; the results equal the stateless projection
to rounding.

:class:`FrictionTracker` goes one step further for the friction under an axle: the friction map
is piecewise constant, so while the point provably stays inside the friction cell of its last
projection no projection is needed at all.
"""

from __future__ import annotations

import bisect
import math

from mufusion.road.friction import FrictionMap
from mufusion.road.path import ReferencePath

# Slack on the bounds of FrictionTracker [m]: far above the rounding of the projection.
_BOUND_SLACK_M = 1e-6


class PointTracker:
    """Projects one moving point onto a path, warm-started from its previous foot point.

    Parameters
    ----------
    path
        The reference path.

    Examples
    --------
    >>> from mufusion.road.path import PathSegment
    >>> tracker = PointTracker(ReferencePath([PathSegment.straight(100.0)]))
    >>> [round(v, 9) for v in tracker.to_frenet(10.0, 0.5)]
    [10.0, 0.5, 0.0]
    >>> round(tracker.last_s_m, 9)
    10.0
    """

    __slots__ = ("_last_frenet", "_last_pose", "path")

    def __init__(self, path: ReferencePath) -> None:
        self.path = path
        self._last_pose: tuple[float, float, float] | None = None
        self._last_frenet: tuple[float, float, float] | None = None

    @property
    def last_s_m(self) -> float | None:
        """Progress of the last foot point [m] (None before the first projection)."""
        return None if self._last_frenet is None else self._last_frenet[0]

    def to_frenet(
        self, x_m: float, y_m: float, psi_rad: float = 0.0
    ) -> tuple[float, float, float]:
        """``(s, d, Δψ)`` of the Cartesian pose, see :meth:`ReferencePath.to_frenet_point`.

        The same pose twice in a row (e.g. an axle looked up by the plant and by the footprint
        status within one tick) returns the stored answer.
        """
        pose = (x_m, y_m, psi_rad)
        if pose == self._last_pose and self._last_frenet is not None:
            return self._last_frenet
        frenet = self.path.to_frenet_point(x_m, y_m, psi_rad, self.last_s_m)
        self._last_pose, self._last_frenet = pose, frenet
        return frenet

    def reset(self) -> None:
        """Forget the warm start (the next projection searches the whole path)."""
        self._last_pose = self._last_frenet = None


class FrictionTracker:
    """True friction under one moving point, projecting only when the answer could change.

    After a projection ``(s₀, d₀)`` of the point at ``P₀``, the point at ``P`` with
    ``δ = |P − P₀|`` has its foot point within ``|s − s₀| ≤ δ / (1 − κ_max (|d₀| + δ))`` and
    its offset within ``|d − d₀| ≤ δ`` (the foot point moves with ``ds = t·dP / (1 − κ d)``
    and the distance to the path is 1-Lipschitz, near a path that does not come back near
    itself: the condition under which the warm-started projection is used at all). With
    ``κ_max (|d₀| + δ) ≤ 1/2`` that is ``|s − s₀| ≤ 2δ``. If no friction change lies within
    that range of ``s₀`` and, with per-lane values, the lane boundary not within ``δ`` of
    ``d₀``, the friction is that of the last projection, exactly; otherwise the point is
    projected (warm-started, :class:`PointTracker`).

    Parameters
    ----------
    path
        The reference path.
    friction
        The road's friction map.

    Examples
    --------
    >>> from mufusion.road.path import PathSegment
    >>> path = ReferencePath([PathSegment.straight(100.0)])
    >>> tracker = FrictionTracker(path, FrictionMap.step(0.8, 0.4, 50.0))
    >>> tracker.mu_at(40.0, 0.2), tracker.mu_at(40.1, 0.2), tracker.projections
    (0.8, 0.8, 1)
    >>> tracker.mu_at(50.5, 0.2), tracker.projections
    (0.4, 2)
    """

    __slots__ = ("_breaks", "_friction", "_half_lane", "_kappa_max", "_last", "projections",
                 "tracker")

    def __init__(self, path: ReferencePath, friction: FrictionMap) -> None:
        self.tracker = PointTracker(path)
        self._friction = friction
        # The segment index changes only where s crosses a later segment's start.
        self._breaks = friction.start_s_m[1:]
        self._half_lane = None if friction.mu_opposing is None else 0.5 * friction.lane_width_m
        self._kappa_max = path.max_abs_curvature_1pm
        self._last: tuple[float, float, float, float, float] | None = None
        self.projections = 0

    def mu_at(self, x_m: float, y_m: float) -> float:
        """True friction [-] at the Cartesian point ``(x_m, y_m)``."""
        last = self._last
        if last is not None:
            x0, y0, s0, d0, mu = last
            moved = math.hypot(x_m - x0, y_m - y0) + _BOUND_SLACK_M
            if (abs(d0) + moved) * self._kappa_max <= 0.5:
                reach = 2.0 * moved
                breaks = self._breaks
                i = bisect.bisect_left(breaks, s0 - reach)
                if (i == len(breaks) or breaks[i] > s0 + reach) and (
                    self._half_lane is None or abs(d0 - self._half_lane) > moved
                ):
                    return mu
        s, d, _ = self.tracker.to_frenet(x_m, y_m)
        mu = self._friction.mu_at_point(s, d)
        self._last = (x_m, y_m, s, d, mu)
        self.projections += 1
        return mu

    def reset(self) -> None:
        """Forget the last projection (the next call projects, searching the whole path)."""
        self.tracker.reset()
        self._last = None
