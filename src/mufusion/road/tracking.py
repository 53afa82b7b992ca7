"""Frenet projection of points that move a little between calls (an axle, a footprint corner).

The closed loop projects the same few vehicle points onto the path at every plant step; each
moves a few centimetres per step, so its last foot point is an excellent start for the next
Newton search (:meth:`~mufusion.road.path.ReferencePath.to_frenet_point`), which then skips the
global table search. The warm start is the only state; the results equal the stateless projection
to rounding.
"""

from __future__ import annotations

from mufusion.road.path import ReferencePath


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
